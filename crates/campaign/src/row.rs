//! One row per run: the trial's terrain descriptors and the run report's figures, written as
//! CSV and as JSON lines.

use crate::plan::{TerrainKind, TrialInfo};
use rovernav_executive::{Report, StageTimes};
use serde::{Deserialize, Serialize};

/// The figures of one (trial, navigator) run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Row {
    /// Trial index.
    pub trial: usize,
    /// `procedural` or `dem`.
    pub terrain_kind: TerrainKind,
    /// `yard` or the DEM mission's name.
    pub terrain: String,
    /// Seed of the terrain and the sensor noise.
    pub seed: u64,
    /// Rock abundance k.
    pub rock_abundance: f64,
    /// Regional slope (deg), procedural yards only.
    pub slope_deg: Option<f64>,
    /// Relief amplitude (m), procedural yards only.
    pub relief_m: Option<f64>,
    /// Yard side (m), procedural yards only.
    pub size_m: Option<f64>,
    /// Navigator registry name.
    pub navigator: String,
    /// The report's outcome (`reached`, `unreachable`, `help_requested`, `aborted`, `timeout`).
    pub outcome: String,
    /// Reached the goal with no hazard contact.
    pub success: bool,
    /// True final position to goal (m).
    pub goal_error_m: f64,
    /// True path length driven (m).
    pub distance_driven_m: f64,
    /// Shortest safe path with full knowledge of the true terrain (m), if one exists.
    pub optimal_length_m: Option<f64>,
    /// Distance driven over optimal length, for reached runs with an optimal length.
    pub path_ratio: Option<f64>,
    /// Times the true rover entered a hazard.
    pub hazard_contacts: u32,
    /// Range images taken.
    pub sensing_actions: u64,
    /// Navigator cycles.
    pub cycles: u64,
    /// Simulated mission time (s).
    pub sim_time_s: f64,
    /// Final |estimate - truth| in the plane (m).
    pub localization_error_m: f64,
    /// Wall-clock compute per cycle by stage (machine-dependent).
    pub compute_per_cycle: StageTimes,
    /// Wall-clock time of the run (machine-dependent).
    pub wall_time_s: f64,
    /// The report's message: why the run ended (empty in rows written before it was kept).
    #[serde(default)]
    pub message: String,
    /// The simulator's description of the first hazard contact (e.g. `hazard: step of 0.182 m
    /// at wheel 0`), if there was one: which limit the run broke and by how much.
    #[serde(default)]
    pub first_contact: Option<String>,
    /// The fault drill, if the trial injected one: kind and what it names (`silent_sensor:mast`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fault: Option<String>,
    /// Simulated time the fault struck (s); null when the run ended before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fault_time_s: Option<f64>,
    /// Fault protection acted at or after the fault.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fault_detected: Option<bool>,
    /// Simulated time from the fault to fault protection's stop (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_to_detect_s: Option<f64>,
    /// Fault protection stopped the rover (`help_requested`) after the fault.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_safely: Option<bool>,
    /// Hazard contacts of the true rover after the fault.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contacts_after_fault: Option<u32>,
}

/// CSV column names, in the order of [`Row::csv_fields`] (the JSON keys, with
/// `compute_per_cycle` flattened).
pub const CSV_HEADER: [&str; 32] = [
    "trial",
    "terrain_kind",
    "terrain",
    "seed",
    "rock_abundance",
    "slope_deg",
    "relief_m",
    "size_m",
    "navigator",
    "outcome",
    "success",
    "goal_error_m",
    "distance_driven_m",
    "optimal_length_m",
    "path_ratio",
    "hazard_contacts",
    "sensing_actions",
    "cycles",
    "sim_time_s",
    "localization_error_m",
    "navigation_s_per_cycle",
    "localization_s_per_cycle",
    "platform_s_per_cycle",
    "wall_time_s",
    "message",
    "first_contact",
    "fault",
    "fault_time_s",
    "fault_detected",
    "time_to_detect_s",
    "stopped_safely",
    "contacts_after_fault",
];

impl Row {
    /// The row of `navigator`'s run on a trial.
    pub fn new(trial: &TrialInfo, navigator: &str, report: &Report) -> Self {
        let reached = report.outcome == "reached";
        let path_ratio = match report.optimal_length_m {
            Some(opt) if reached && opt > 0.0 => Some(report.distance_driven_m / opt),
            _ => None,
        };
        Self {
            trial: trial.trial,
            terrain_kind: trial.terrain_kind,
            terrain: trial.terrain.clone(),
            seed: trial.seed,
            rock_abundance: trial.rock_abundance,
            slope_deg: trial.slope_deg,
            relief_m: trial.relief_m,
            size_m: trial.size_m,
            navigator: navigator.into(),
            outcome: report.outcome.clone(),
            success: reached && report.hazard_contacts == 0,
            goal_error_m: report.goal_error_m,
            distance_driven_m: report.distance_driven_m,
            optimal_length_m: report.optimal_length_m,
            path_ratio,
            hazard_contacts: report.hazard_contacts,
            sensing_actions: report.sensing_actions,
            cycles: report.cycles,
            sim_time_s: report.sim_time_s,
            localization_error_m: report.localization_error_m,
            compute_per_cycle: report.compute_per_cycle,
            wall_time_s: report.wall_time_s,
            message: report.message.clone(),
            first_contact: report.hazard_events.first().map(|e| e.cause.clone()),
            fault: None,
            fault_time_s: None,
            fault_detected: None,
            time_to_detect_s: None,
            stopped_safely: None,
            contacts_after_fault: None,
        }
        .with_fault(trial.fault.as_deref(), report)
    }

    /// The fault drill's figures: the first injected fault against fault protection's stop.
    fn with_fault(mut self, kind: Option<&str>, report: &Report) -> Self {
        let Some(kind) = kind else { return self };
        self.fault = Some(kind.to_string());
        let Some(injected) = report.injected_faults.first() else { return self };
        self.fault_time_s = Some(injected.time_s);
        let stop = report.fault.as_ref().filter(|f| f.time_s >= injected.time_s - 1e-9);
        self.fault_detected = Some(stop.is_some());
        self.time_to_detect_s = stop.map(|f| f.time_s - injected.time_s);
        self.stopped_safely = Some(stop.is_some() && report.outcome == "help_requested");
        self.contacts_after_fault = Some(injected.hazard_contacts_after);
        self
    }

    /// Whether the run failed: a fault drill fails when the fault struck and the rover was not
    /// stopped safely or met a hazard after it; any other run when it did not succeed.
    pub fn failed(&self) -> bool {
        match (&self.fault, self.stopped_safely) {
            (Some(_), Some(stopped)) => !stopped || self.contacts_after_fault.unwrap_or(0) > 0,
            (Some(_), None) => false,
            (None, _) => !self.success,
        }
    }

    /// The trial descriptors this row carries.
    pub fn trial_info(&self) -> TrialInfo {
        TrialInfo {
            trial: self.trial,
            terrain_kind: self.terrain_kind,
            terrain: self.terrain.clone(),
            seed: self.seed,
            rock_abundance: self.rock_abundance,
            slope_deg: self.slope_deg,
            relief_m: self.relief_m,
            size_m: self.size_m,
            fault: self.fault.clone(),
        }
    }

    /// Why the run failed, in a line: its first hazard contact, else its closing message.
    pub fn why(&self) -> String {
        self.first_contact.clone().unwrap_or_else(|| self.message.clone())
    }

    /// Picture file name of this run (when it failed), e.g. `trial-0003-nat.png`.
    pub fn picture_name(&self) -> String {
        format!("trial-{:04}-{}.png", self.trial, self.navigator)
    }

    /// The CSV fields, in [`CSV_HEADER`] order; floats in Rust's shortest round-trip form.
    pub fn csv_fields(&self) -> Vec<String> {
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        let StageTimes { navigation_s, localization_s, platform_s } = self.compute_per_cycle;
        vec![
            self.trial.to_string(),
            self.terrain_kind.as_str().into(),
            csv_quote(&self.terrain),
            self.seed.to_string(),
            self.rock_abundance.to_string(),
            opt(self.slope_deg),
            opt(self.relief_m),
            opt(self.size_m),
            csv_quote(&self.navigator),
            csv_quote(&self.outcome),
            self.success.to_string(),
            self.goal_error_m.to_string(),
            self.distance_driven_m.to_string(),
            opt(self.optimal_length_m),
            opt(self.path_ratio),
            self.hazard_contacts.to_string(),
            self.sensing_actions.to_string(),
            self.cycles.to_string(),
            self.sim_time_s.to_string(),
            self.localization_error_m.to_string(),
            navigation_s.to_string(),
            localization_s.to_string(),
            platform_s.to_string(),
            self.wall_time_s.to_string(),
            csv_quote(&self.message),
            self.first_contact.as_deref().map_or(String::new(), csv_quote),
            self.fault.as_deref().map_or(String::new(), csv_quote),
            opt(self.fault_time_s),
            self.fault_detected.map_or(String::new(), |v| v.to_string()),
            opt(self.time_to_detect_s),
            self.stopped_safely.map_or(String::new(), |v| v.to_string()),
            self.contacts_after_fault.map_or(String::new(), |v| v.to_string()),
        ]
    }
}

/// A CSV field, quoted (RFC 4180) when it holds a comma, a quote or a line break.
fn csv_quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// The whole CSV file: header and one line per row.
pub fn to_csv(rows: &[Row]) -> String {
    let mut out = CSV_HEADER.join(",");
    out.push('\n');
    for r in rows {
        out.push_str(&r.csv_fields().join(","));
        out.push('\n');
    }
    out
}

/// The rows as JSON lines.
pub fn to_jsonl(rows: &[Row]) -> String {
    let mut out = String::new();
    for r in rows {
        out.push_str(&serde_json::to_string(r).expect("rows serialise"));
        out.push('\n');
    }
    out
}

/// Parses JSON lines; `origin` names the file in errors, with the line number.
pub fn from_jsonl(text: &str, origin: &str) -> Result<Vec<Row>, crate::CampaignError> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| crate::CampaignError::Parse {
                path: origin.into(),
                message: format!("line {}: {e}", i + 1),
            })
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A row with the given figures and plausible others.
    pub(crate) fn row(trial: usize, nav: &str, outcome: &str, hazards: u32, driven: f64) -> Row {
        let report = Report {
            outcome: outcome.into(),
            navigator: nav.into(),
            distance_driven_m: driven,
            optimal_length_m: Some(10.0),
            hazard_contacts: hazards,
            hazard_events: (0..hazards)
                .map(|k| rovernav_executive::HazardEvent {
                    x: 1.0,
                    y: 2.0,
                    cycle: 3 + u64::from(k),
                    cause: format!("hazard: step of 0.18{k} m at wheel 0"),
                })
                .collect(),
            message: format!("{outcome}, after all"),
            sensing_actions: 7,
            cycles: 20,
            goal_error_m: 0.3,
            compute_per_cycle: StageTimes { navigation_s: 0.01, localization_s: 0.001, platform_s: 0.002 },
            ..Default::default()
        };
        let info = TrialInfo {
            trial,
            terrain_kind: TerrainKind::Procedural,
            terrain: "yard".into(),
            seed: 100 + trial as u64,
            rock_abundance: [0.05, 0.1, 0.2][trial % 3],
            slope_deg: Some(1.5),
            relief_m: Some(0.25),
            size_m: Some(30.0),
            fault: None,
        };
        Row::new(&info, nav, &report)
    }

    #[test]
    fn success_needs_the_goal_and_no_hazard_contact() {
        assert!(row(0, "nat", "reached", 0, 12.0).success);
        assert!(!row(0, "nat", "reached", 1, 12.0).success);
        assert!(!row(0, "nat", "timeout", 0, 12.0).success);
    }

    #[test]
    fn a_row_keeps_why_the_run_ended_and_its_first_contact() {
        let r = row(0, "roverbug", "reached", 2, 12.0);
        assert_eq!(r.message, "reached, after all");
        assert_eq!(r.first_contact.as_deref(), Some("hazard: step of 0.180 m at wheel 0"));
        assert_eq!(row(0, "roverbug", "reached", 0, 12.0).first_contact, None);
        // Rows written before these fields were kept still read.
        let mut old = serde_json::to_value(&r).unwrap();
        old.as_object_mut().unwrap().retain(|k, _| k != "message" && k != "first_contact");
        let back: Row = serde_json::from_value(old).unwrap();
        assert_eq!((back.message.as_str(), back.first_contact), ("", None));
    }

    #[test]
    fn path_ratio_only_for_reached_runs() {
        assert_eq!(row(0, "nat", "reached", 2, 12.0).path_ratio, Some(1.2));
        assert_eq!(row(0, "nat", "unreachable", 0, 12.0).path_ratio, None);
    }

    #[test]
    fn csv_columns_are_the_json_keys() {
        // A fault drill's row, whose fault columns are in the JSON (other rows leave them out).
        let mut r = row(1, "gestalt+field-dstar", "reached", 0, 11.0);
        r.fault = Some("compass_nan".into());
        r.fault_time_s = Some(20.0);
        r.fault_detected = Some(true);
        r.time_to_detect_s = Some(0.1);
        r.stopped_safely = Some(true);
        r.contacts_after_fault = Some(0);
        let json = serde_json::to_value(&r).unwrap();
        let mut keys = Vec::new();
        for (k, v) in json.as_object().unwrap() {
            match v.as_object() {
                Some(inner) => keys.extend(inner.keys().map(|i| format!("{}_per_cycle", i))),
                None => keys.push(k.clone()),
            }
        }
        keys.sort();
        let mut header: Vec<String> = CSV_HEADER.iter().map(|s| s.to_string()).collect();
        header.sort();
        assert_eq!(keys, header);
        assert_eq!(r.csv_fields().len(), CSV_HEADER.len());
    }

    #[test]
    fn csv_quotes_commas_and_quotes() {
        assert_eq!(csv_quote("a,b"), "\"a,b\"");
        assert_eq!(csv_quote("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_quote("plain"), "plain");
    }

    #[test]
    fn json_lines_round_trip_exactly() {
        let mut rows: Vec<Row> = (0..5).map(|i| row(i, "sr2", "reached", 0, 10.0 + 0.1 * i as f64)).collect();
        rows[2].distance_driven_m = 0.1 + 0.2;
        rows[3].compute_per_cycle.navigation_s = 1.0 / 3.0;
        let back = from_jsonl(&to_jsonl(&rows), "rows.jsonl").unwrap();
        assert_eq!(back, rows);
        let e = from_jsonl("{\"trial\": 1}\n", "rows.jsonl").unwrap_err().to_string();
        assert!(e.contains("rows.jsonl") && e.contains("line 1"), "{e}");
    }
}
