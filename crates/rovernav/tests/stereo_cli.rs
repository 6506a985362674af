//! `rovernav stereo`: the Middlebury benchmark figures against the pairs' ground truth, the
//! files it writes, and one-line errors naming the file on bad input.

use std::path::PathBuf;
use std::process::Command;

fn rovernav(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(args).output().expect("binary runs");
    let text = |b: &[u8]| String::from_utf8_lossy(b).trim().to_string();
    (out.status.success(), text(&out.stdout), text(&out.stderr))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-stereo-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A Middlebury file, or `None` (after saying why) when the data set is absent; with
/// ROVERNAV_REQUIRE_DATA=1 a missing file fails the test.
fn middlebury(relative: &str) -> Option<String> {
    let path = rovernav_core::data_dir().join("stereo/middlebury").join(relative);
    if path.is_file() {
        return Some(path.display().to_string());
    }
    assert!(std::env::var("ROVERNAV_REQUIRE_DATA").as_deref() != Ok("1"), "{} is missing", path.display());
    eprintln!("skipping: {} not found (set ROVERNAV_DATA)", path.display());
    None
}

fn assert_one_line_error(ok: bool, stderr: &str, must_contain: &[&str]) {
    assert!(!ok, "expected failure, stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr}");
    for s in must_contain {
        assert!(stderr.contains(s), "`{s}` missing from: {stderr}");
    }
}

/// Runs the benchmark on one pair and returns its JSON figures.
fn score(
    set: &str,
    left: &str,
    right: &str,
    truth: &str,
    scale: &str,
    max_d: &str,
    out: Option<&str>,
) -> Option<serde_json::Value> {
    let (l, r, t) = (
        middlebury(&format!("{set}/{left}"))?,
        middlebury(&format!("{set}/{right}"))?,
        middlebury(&format!("{set}/{truth}"))?,
    );
    let mut args =
        vec!["stereo", &l, &r, "--max-disparity", max_d, "--truth", &t, "--truth-scale", scale, "--json"];
    if let Some(dir) = out {
        args.extend(["--out", dir]);
    }
    let (ok, stdout, stderr) = rovernav(&args);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON on stdout");
    eprintln!("{set}: {v}");
    Some(v)
}

fn figure(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("{key} missing from {v}"))
}

#[test]
fn tsukuba_is_within_the_semi_global_matching_target() {
    let dir = temp_dir("tsukuba");
    let out = dir.display().to_string();
    let Some(v) = score("tsukuba", "im3.png", "im4.png", "disp3.pgm", "16", "16", Some(&out)) else { return };
    assert!(figure(&v, "bad_pixel_fraction") <= 0.08, "{v}");
    // The measured map: most pixels measured, and those accurate.
    assert!(figure(&v, "valid_fraction") >= 0.85, "{v}");
    assert!(figure(&v, "mean_abs_error_px") < 0.6, "{v}");
    assert!(figure(&v, "measured_bad_pixel_fraction") <= 1.0 - figure(&v, "valid_fraction") + 0.05, "{v}");
    // The written 16-bit disparity (x 16, 0 = invalid) agrees with the truth file on its own.
    let written = image::open(dir.join("disparity.png")).unwrap().into_luma16();
    let truth = image::open(middlebury("tsukuba/disp3.pgm").unwrap()).unwrap().into_luma8();
    assert_eq!(written.dimensions(), truth.dimensions());
    let (mut both, mut close) = (0, 0);
    for (d, t) in written.pixels().zip(truth.pixels()) {
        if d.0[0] > 0 && t.0[0] > 0 {
            both += 1;
            close += usize::from((f64::from(d.0[0]) / 16.0 - f64::from(t.0[0]) / 16.0).abs() <= 1.0);
        }
    }
    assert!(close as f64 > 0.95 * both as f64, "{close} of {both}");
    let colour = image::open(dir.join("disparity_colour.png")).unwrap();
    assert_eq!((colour.width(), colour.height()), truth.dimensions());
    // A larger search range changes little.
    let Some(wide) = score("tsukuba", "im3.png", "im4.png", "disp3.pgm", "16", "32", None) else { return };
    assert!(figure(&wide, "bad_pixel_fraction") <= 0.08, "{wide}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn cones_is_within_the_semi_global_matching_target() {
    let Some(v) = score("cones", "im2.png", "im6.png", "disp2.png", "4", "64", None) else { return };
    assert!(figure(&v, "bad_pixel_fraction") <= 0.15, "{v}");
    assert!(figure(&v, "valid_fraction") >= 0.8, "{v}");
    assert!(figure(&v, "mean_abs_error_px") < 0.6, "{v}");
}

#[test]
fn text_output_names_the_figures() {
    let Some(l) = middlebury("tsukuba/im3.png") else { return };
    let (r, t) = (middlebury("tsukuba/im4.png").unwrap(), middlebury("tsukuba/disp3.pgm").unwrap());
    let (ok, stdout, stderr) =
        rovernav(&["stereo", &l, &r, "--max-disparity", "16", "--truth", &t, "--truth-scale", "16"]);
    assert!(ok, "{stderr}");
    for key in ["bad_pixel_fraction: ", "valid_fraction: ", "mean_abs_error_px: "] {
        assert!(stdout.contains(key), "{key} missing from {stdout}");
    }
}

/// Writes a small random grey PNG.
fn write_png(dir: &std::path::Path, name: &str, w: u32, h: u32) -> String {
    let img = image::GrayImage::from_fn(w, h, |x, y| image::Luma([((x * 37 + y * 91) % 251) as u8]));
    let p = dir.join(name);
    img.save(&p).unwrap();
    p.display().to_string()
}

#[test]
fn bad_input_is_one_line_naming_the_file() {
    let dir = temp_dir("errors");
    let a = write_png(&dir, "a.png", 40, 30);
    let b = write_png(&dir, "b.png", 40, 30);
    let small = write_png(&dir, "small.png", 39, 30);
    let (ok, _, err) = rovernav(&["stereo", "/nonexistent/left.png", &b]);
    assert_one_line_error(ok, &err, &["/nonexistent/left.png"]);
    let (ok, _, err) = rovernav(&["stereo", &a, &small]);
    assert_one_line_error(ok, &err, &["small.png", "39x30", "40x30"]);
    let junk = dir.join("junk.png");
    std::fs::write(&junk, b"not an image").unwrap();
    let (ok, _, err) = rovernav(&["stereo", &a, &junk.display().to_string()]);
    assert_one_line_error(ok, &err, &["junk.png"]);
    for scale in ["0", "-4", "NaN"] {
        let scale = format!("--truth-scale={scale}");
        let (ok, _, err) = rovernav(&["stereo", &a, &b, "--truth", &b, &scale]);
        assert_one_line_error(ok, &err, &["--truth-scale"]);
    }
    let (ok, _, err) = rovernav(&["stereo", &a, &b, "--truth", &b]);
    assert_one_line_error(ok, &err, &["--truth-scale"]);
    let (ok, _, err) = rovernav(&["stereo", &a, &b, "--truth", &small, "--truth-scale", "4"]);
    assert_one_line_error(ok, &err, &["small.png", "39x30"]);
    let (ok, _, err) = rovernav(&["stereo", &a, &b, "--max-disparity", "0"]);
    assert_one_line_error(ok, &err, &["--max-disparity"]);
    let (ok, _, err) = rovernav(&["stereo", &a, &b, "--max-disparity", "1000000"]);
    assert_one_line_error(ok, &err, &["--max-disparity"]);
    // A pair without truth still reports its valid fraction.
    let (ok, stdout, err) = rovernav(&["stereo", &a, &b, "--max-disparity", "8", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["valid_fraction"].as_f64().is_some() && v["bad_pixel_fraction"].is_null(), "{v}");
    let _ = std::fs::remove_dir_all(dir);
}
