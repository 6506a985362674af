//! The words of a traverse picture: its title (mission, navigator, localiser, seed), the outcome
//! and its reason from the report, the run's figures, and the end points' errors.

use plotters::style::{FontDesc, RGBColor};
use rovernav_executive::Report;

/// The picture's header.
#[derive(Clone, Debug, PartialEq)]
pub struct Caption {
    /// Mission, navigator, localiser and seed.
    pub title: String,
    /// The outcome in words (`Reached the goal`, `Asked for help`...).
    pub outcome: String,
    /// The outcome's colour.
    pub colour: RGBColor,
    /// Why the run ended (the report's message, and the fault that stopped it if any).
    pub reason: String,
    /// Distance, time, cycles and contacts.
    pub figures: String,
}

/// The outcome in words and its colour.
pub fn outcome_words(outcome: &str) -> (&'static str, RGBColor) {
    match outcome {
        "reached" => ("Reached the goal", RGBColor(0, 140, 60)),
        "help_requested" => ("Asked for help", RGBColor(215, 110, 0)),
        "timeout" => ("Timed out", RGBColor(140, 40, 170)),
        "unreachable" => ("Goal unreachable", RGBColor(200, 30, 30)),
        "aborted" => ("Aborted", RGBColor(200, 30, 30)),
        _ => ("Ended", RGBColor(60, 60, 60)),
    }
}

/// The header of a run's picture.
pub fn caption(report: &Report) -> Caption {
    let (outcome, colour) = outcome_words(&report.outcome);
    let mut reason = report.message.trim().to_string();
    if let Some(fault) = &report.fault {
        let by = fault.component.as_deref().map(|c| format!(" from {c}")).unwrap_or_default();
        reason.push_str(&format!(
            " · fault protection stopped the rover at {:.0} s: {}{by}: {}",
            fault.time_s, fault.kind, fault.message
        ));
    }
    let optimal =
        report.optimal_length_m.map(|m| format!(" (shortest safe path {m:.1} m)")).unwrap_or_default();
    let figures = format!(
        "driven {:.1} m{optimal} in {:.0} s simulated, {} cycles, {} hazard contact{}",
        report.distance_driven_m,
        report.sim_time_s,
        report.cycles,
        report.hazard_contacts,
        if report.hazard_contacts == 1 { "" } else { "s" }
    );
    Caption {
        title: format!(
            "{} · navigator {} · localiser {} · seed {}",
            report.mission, report.navigator, report.localizer, report.seed
        ),
        outcome: outcome.to_string(),
        colour,
        reason,
        figures,
    }
}

/// Splits `text` into lines no wider than `max_px` in `font` (at word boundaries; a single word
/// wider than that gets a line of its own), at most `max_lines` (the last ends with "…" when cut).
pub fn wrap(text: &str, font: &FontDesc<'_>, max_px: u32, max_lines: usize) -> Vec<String> {
    let width = |s: &str| font.box_size(s).map_or(s.chars().count() as u32 * 8, |(w, _)| w);
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if !line.is_empty() && width(&candidate) > max_px {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    if lines.len() > max_lines {
        lines.truncate(max_lines);
        if let Some(last) = lines.last_mut() {
            while !last.is_empty() && width(&format!("{last} …")) > max_px {
                last.pop();
            }
            last.push_str(" …");
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_executive::FaultReport;

    #[test]
    fn caption_names_the_run_and_says_why_it_ended() {
        let report = Report {
            outcome: "help_requested".into(),
            message: "boxed in by rocks".into(),
            mission: "yard".into(),
            navigator: "sr2".into(),
            localizer: "ekf".into(),
            seed: 7,
            hazard_contacts: 1,
            fault: Some(FaultReport {
                kind: "no_progress".into(),
                component: Some("navigator".into()),
                message: "stuck".into(),
                cycle: 3,
                time_s: 12.0,
            }),
            ..Report::default()
        };
        let c = caption(&report);
        assert_eq!(c.title, "yard · navigator sr2 · localiser ekf · seed 7");
        assert_eq!(c.outcome, "Asked for help");
        assert!(
            c.reason.starts_with("boxed in by rocks")
                && c.reason.contains("no_progress from navigator: stuck")
        );
        assert!(c.figures.ends_with("1 hazard contact"), "{}", c.figures);
    }

    #[test]
    fn wrapped_lines_fit_and_keep_every_word() {
        let font = FontDesc::new(crate::font::family(), 14.0, plotters::style::FontStyle::Normal);
        let text = "the quick brown fox jumps over the lazy dog again and again until the line is long";
        let lines = wrap(text, &font, 150, 10);
        assert!(lines.len() > 2);
        for l in &lines {
            assert!(font.box_size(l).unwrap().0 <= 150 || !l.contains(' '), "{l}");
        }
        assert_eq!(lines.join(" "), text);
        let cut = wrap(text, &font, 150, 2);
        assert_eq!(cut.len(), 2);
        assert!(cut[1].ends_with('…'));
    }
}
