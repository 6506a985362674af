//! A navigator in shadow (`shadow_navigator`, paper 003 section 6's "no update" checkout):
//! Field D* beside GESTALT computes and logs its plans at every step while GESTALT drives. The
//! drive must be GESTALT's alone, bit for bit (checked against the same mission without the
//! shadow), and the shadow's plans must be in the log.

use rovernav_executive::{Mission, Run, RunObserver};
use rovernav_harness::JudgedRun;

/// The `/navigation/shadow` messages a run published.
#[derive(Default)]
struct ShadowLog(Vec<serde_json::Value>);

impl RunObserver for ShadowLog {
    fn wants_bus(&self) -> bool {
        true
    }
    fn on_bus(&mut self, records: &[rovernav_bus::Record]) {
        for r in records.iter().filter(|r| r.topic == "/navigation/shadow") {
            self.0.push(serde_json::from_slice(&r.payload).expect("a shadow message is JSON"));
        }
    }
}

fn mission(shadow: Option<&str>) -> Mission {
    let mut text = rovernav_executive::mission::DEFAULT_MISSION_TOML
        .replace("navigator = \"astar-grid\"", "navigator = \"gestalt\"")
        .replace("localizer = \"ekf-ml\"", "localizer = \"dead-reckoning\"");
    if let Some(name) = shadow {
        text = format!("shadow_navigator = \"{name}\"\n{text}");
    }
    Mission::from_toml(&text, "shadow").expect("valid mission")
}

#[test]
fn field_dstar_in_shadow_logs_its_plans_and_leaves_gestalts_drive_bit_for_bit() {
    let alone = Run::mission(&mission(None), "alone").and_then(Run::execute).expect("runs");
    let mut log = ShadowLog::default();
    let shadowed = Run::mission(&mission(Some("gestalt+field-dstar")), "shadowed")
        .expect("builds")
        .observer(&mut log)
        .execute()
        .expect("runs");
    // The drive: the same true path, pose for pose, and the same report but for the shadow's
    // record and the wall clock.
    assert_eq!(alone.trace.truth, shadowed.trace.truth, "the shadow changed the drive");
    let (mut a, mut b) = (alone.report.clone(), shadowed.report.clone());
    let shadow = b.shadow.take().expect("the report has the shadow's record");
    for r in [&mut a, &mut b] {
        r.wall_time_s = 0.0;
        r.compute_per_cycle = Default::default();
        r.peak_rss_mb = None;
    }
    assert_eq!(a, b);
    assert!(a.shadow.is_none());
    // The shadow: one message per step it took, plans among them, its agreement counted from
    // the messages themselves.
    assert_eq!(shadow.navigator, "gestalt+field-dstar");
    assert!(shadow.steps > 10, "{shadow:?}");
    assert_eq!(log.0.len() as u64, shadow.steps);
    let plans = log.0.iter().filter(|m| m["plan"].is_array()).count() as u64;
    assert_eq!(plans, shadow.plans);
    assert!(plans > 0, "Field D* announced no plan");
    let agreeing = log.0.iter().filter(|m| m["agrees"] == serde_json::Value::Bool(true)).count() as u64;
    assert_eq!(agreeing, shadow.agreeing_steps);
    assert!(log.0.iter().all(|m| m["navigator"] == "gestalt+field-dstar"));
}

#[test]
fn an_unknown_shadow_navigator_is_a_one_line_error_naming_the_field() {
    let text =
        format!("shadow_navigator = \"warp-drive\"\n{}", rovernav_executive::mission::DEFAULT_MISSION_TOML);
    let e = Mission::from_toml(&text, "shadow").unwrap_err().to_string();
    assert!(e.contains("shadow_navigator") && e.contains("warp-drive") && !e.contains('\n'), "{e}");
}
