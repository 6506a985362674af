//! Tests of the campaign charts: the figures they print are summary.rs's, intervals are Wilson's,
//! and no two labels overlap.

use super::*;
use crate::output::CampaignMeta;
use crate::row::tests::row;
use crate::spec::CampaignSpec;
use crate::summary::{median, percentile, summarise};

fn summary_and_rows(names: &[&str]) -> (Summary, Vec<Row>) {
    let spec = CampaignSpec::from_toml("name = \"p\"", "t").unwrap();
    let meta = CampaignMeta {
        spec,
        navigators: names.iter().map(|n| n.to_string()).collect(),
        trials: vec![],
        skipped: vec![],
        shard: None,
        jobs: 0,
    };
    let mut rows = Vec::new();
    for t in 0..6 {
        for (k, name) in names.iter().enumerate() {
            let reached = k == 0 || t < 3;
            rows.push(row(
                t,
                name,
                if reached { "reached" } else { "timeout" },
                0,
                10.0 + (t * (k + 1)) as f64,
            ));
        }
    }
    (summarise(&meta, &rows).0, rows)
}

/// Every `<text>` of an SVG: its x, y, anchor and words.
fn texts(svg: &str) -> Vec<(f64, f64, String, String)> {
    let mut out = Vec::new();
    for part in svg.split("<text").skip(1) {
        let attr = |name: &str| -> Option<String> {
            let start = part.find(&format!(" {name}=\""))? + name.len() + 3;
            Some(part[start..].split('"').next()?.to_string())
        };
        let (Some(x), Some(y)) = (attr("x"), attr("y")) else { continue };
        let words =
            part.split('>').nth(1).unwrap_or("").split("</text").next().unwrap_or("").trim().to_string();
        out.push((x.parse().unwrap(), y.parse().unwrap(), attr("text-anchor").unwrap_or_default(), words));
    }
    out
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&amp;", "&")
}

#[test]
fn path_ratio_plot_prints_summary_medians_of_its_dots() {
    let (s, rows) = summary_and_rows(&["nat", "a<b"]);
    let svg = path_ratio(&s, &rows);
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for nav in ["nat", "a<b"] {
        let ratios: Vec<f64> =
            rows.iter().filter(|r| r.navigator == nav).filter_map(|r| r.path_ratio).collect();
        // An even count: the median is the mean of the middle two, not a nearest-rank value.
        let m = median(&ratios).unwrap();
        let p = percentile(&ratios, 0.95).unwrap();
        let words = format!("n={} · median {m:.3} · p95 {p:.3}", ratios.len());
        assert!(texts(&svg).iter().any(|t| unescape(&t.3) == words), "{words} in\n{svg}");
    }
    assert!(svg.contains("a&lt;b") && !svg.contains(">a<b<"), "names are escaped");
}

#[test]
fn success_plot_gives_each_navigator_its_wilson_interval() {
    let (s, _) = summary_and_rows(&["nat", "other"]);
    let svg = success_vs_rock_abundance(&s);
    let all: Vec<String> = texts(&svg).into_iter().map(|t| unescape(&t.3)).collect();
    for n in &s.navigators {
        let [a, b] = wilson(n.successes, n.runs, Z95).unwrap();
        let words = format!(
            "{} {:.0} % [{:.0}, {:.0}]",
            n.navigator,
            100.0 * n.success_rate.unwrap(),
            100.0 * a,
            100.0 * b
        );
        assert!(all.contains(&words), "{words} in {all:?}");
    }
}

#[test]
fn label_rows_never_overlap_and_stay_on_one_row_when_there_is_room() {
    assert_eq!(label_rows(&[50.0, 150.0, 250.0], &[80.0, 80.0, 80.0], 6.0), vec![0, 0, 0]);
    // Wide labels at close centres: alternate rows, and a third row only when needed.
    let rows = label_rows(&[50.0, 120.0, 190.0], &[120.0, 120.0, 120.0], 6.0);
    assert_eq!(rows, vec![0, 1, 0]);
    let rows = label_rows(&[50.0, 60.0, 70.0], &[100.0, 100.0, 100.0], 6.0);
    assert_eq!(rows, vec![0, 1, 2]);
}

#[test]
fn long_navigator_names_do_not_collide_under_the_path_ratio_plot() {
    let names = [
        "bug2-with-a-very-long-name",
        "tangent-bug-long-name",
        "sr2-obstacle-avoider",
        "astar-grid",
        "dstar",
    ];
    let (s, rows) = summary_and_rows(&names);
    let svg = path_ratio(&s, &rows);
    // The boxes of the centred labels under the axis, from their measured extents.
    let boxes: Vec<(f64, f64, f64, f64)> = texts(&svg)
        .into_iter()
        .filter(|t| t.2 == "middle" && t.1 > 300.0)
        .map(|(x, y, _, words)| {
            let w = width_of(&unescape(&words), 12.0);
            (x - w / 2.0, x + w / 2.0, y, y + 14.0)
        })
        .collect();
    assert_eq!(boxes.len(), names.len(), "a label per navigator");
    assert!(boxes.iter().any(|b| b.2 != boxes[0].2), "long names need a second row: {boxes:?}");
    for (i, a) in boxes.iter().enumerate() {
        assert!(a.3 <= SIZE.1 as f64, "inside the picture: {a:?}");
        for b in &boxes[i + 1..] {
            let apart = a.1 <= b.0 || b.1 <= a.0 || a.3 <= b.2 || b.3 <= a.2;
            assert!(apart, "labels overlap: {a:?} {b:?}");
        }
    }
}
