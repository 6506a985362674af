//! Tests of the mission file reader.

use super::*;

#[test]
fn default_mission_parses() {
    let m = Mission::default_mission();
    assert_eq!(m.navigator, "astar-grid");
    assert!(matches!(m.terrain, TerrainSpec::Procedural { .. }));
}

#[test]
fn misspelt_field_is_named_with_its_line() {
    let text = DEFAULT_MISSION_TOML.replace("navigator =", "navigatr =");
    let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
    assert!(err.contains("m.toml") && err.contains("navigatr") && err.contains("line "), "{err}");
}

#[test]
fn sensor_overrides_out_of_range_name_their_field() {
    for (line, field) in [
        ("stereo_dropout = 1.5", "sensors.stereo_dropout"),
        ("stereo_noise_scale = -1.0", "sensors.stereo_noise_scale"),
        ("compass_sigma_deg = nan", "sensors.compass_sigma_deg"),
        ("range_source = \"lidar\"", "expected `raycast` or `stereo`"),
    ] {
        let text = format!("{DEFAULT_MISSION_TOML}\n[sensors]\n{line}\n");
        let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
        assert!(err.contains("m.toml") && err.contains(field), "{line}: {err}");
    }
    let text = format!(
        "{DEFAULT_MISSION_TOML}\n[sensors]\nstereo_noise_scale = 0.0\nstereo_dropout = 0.1\nrange_source = \"stereo\"\n"
    );
    let m = Mission::from_toml(&text, "m.toml").unwrap();
    // The mission file table written back parses to the same overrides.
    let again =
        Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}{}", m.sensors.toml_table()), "m.toml").unwrap();
    assert_eq!(again.sensors, m.sensors);
    assert_eq!(m.sensors.stereo_noise_scale, Some(0.0));
    assert_eq!(m.sensors.range_source, Some(RangeSourceSpec::Stereo));
}

#[test]
fn a_sensor_override_takes_the_place_of_the_given_field_only() {
    let own = SensorSpec { compass_sigma_deg: Some(2.0), stereo_dropout: Some(0.2), ..Default::default() };
    let over = SensorSpec { stereo_dropout: Some(0.0), stereo_noise_scale: Some(0.5), ..Default::default() };
    let merged = own.overridden_by(&over);
    assert_eq!(merged.compass_sigma_deg, Some(2.0));
    assert_eq!(merged.stereo_dropout, Some(0.0));
    assert_eq!(merged.stereo_noise_scale, Some(0.5));
    assert_eq!(own.overridden_by(&SensorSpec::default()), own);
}

#[test]
fn invalid_value_names_the_field() {
    let text = DEFAULT_MISSION_TOML.replace("rock_abundance = 0.16", "rock_abundance = 3.0");
    let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
    assert!(err.contains("terrain.rock_abundance"), "{err}");
}

#[test]
fn tasks_and_faults_are_read_and_checked() {
    let text = format!(
        "{DEFAULT_MISSION_TOML}\n[[tasks]]\nkind = \"panorama\"\n[[tasks]]\nkind = \"scoop\"\nx = 20.5\ny = 20.0\nparallel = true\n\
         [[faults]]\nkind = \"stalled_wheel\"\nside = \"right\"\nat_cycle = 4\n"
    );
    let m = Mission::from_toml(&text, "m.toml").unwrap();
    assert_eq!(m.tasks.len(), 2);
    let plan = m.plan_tasks(&|x, y| rovernav_core::Point2::new(x, y));
    assert_eq!(
        plan[1].kind,
        crate::deliberative::TaskKind::Scoop { target: rovernav_core::Point2::new(20.5, 20.0) }
    );
    assert!(plan[1].parallel);
    let schedule = m.fault_schedule();
    assert_eq!(schedule[0].fault, rovernav_sim::Fault::StalledWheel { left: false });
    assert_eq!(schedule[0].at, crate::platform::FaultTrigger::Cycle(4));
    for (bad, field) in [
        ("[[tasks]]\nkind = \"scoop\"\nx = 1.0\n", "tasks[0].y"),
        ("[[tasks]]\nkind = \"panorama\"\nx = 1.0\n", "tasks[0].x"),
        (
            "[[tasks]]\nkind = \"panorama\"\n[[tasks]]\nkind = \"science_image\"\nx = 1.0\ny = 1.0\nparallel = true\n",
            "tasks[1].parallel",
        ),
        ("[[tasks]]\nkind = \"panorama\"\nparallel = true\n", "tasks[0].parallel"),
        ("[[tasks]]\nkind = \"track_target\"\nx = 1.0\ny = 1.0\n", "tasks[0].parallel"),
        (
            "[[tasks]]\nkind = \"track_target\"\nx = 1.0\ny = 1.0\nstandoff_m = 1.0\nparallel = true\n",
            "tasks[0].standoff_m",
        ),
        ("[[faults]]\nkind = \"silent_sensor\"\n", "faults[0].sensor"),
        ("[[faults]]\nkind = \"compass_nan\"\nside = \"left\"\n", "faults[0].side"),
        ("[[faults]]\nkind = \"compass_nan\"\nat_cycle = 1\nat_time_s = 2.0\n", "faults[0].at_time_s"),
    ] {
        let err =
            Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}\n{bad}"), "m.toml").unwrap_err().to_string();
        assert!(err.contains(field), "{field}: {err}");
    }
    let err =
        Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}\n[[faults]]\nkind = \"meteor\"\n"), "m.toml")
            .unwrap_err()
            .to_string();
    assert!(err.contains("meteor") && err.contains("line "), "{err}");
}

#[test]
fn navigator_params_are_read_and_checked_against_the_navigator() {
    let text = DEFAULT_MISSION_TOML.replace("\"astar-grid\"", "\"roverbug\"");
    let m = Mission::from_toml(
        &format!("{text}\n[navigator_params]\nsafety_buffer_m = 0.2\nmax_wedges = 40\n"),
        "m.toml",
    )
    .unwrap();
    assert_eq!(m.navigator_params.get("max_wedges"), Some(&40.0));
    for (bad, field) in [
        ("wedge_budget = 40", "navigator_params.wedge_budget"),
        ("clearance_margin = 1.5", "navigator_params.clearance_margin"),
        ("max_wedges = 2.5", "navigator_params.max_wedges"),
    ] {
        let full = format!("{text}\n[navigator_params]\n{bad}\n");
        let line = full.lines().count();
        let err = Mission::from_toml(&full, "m.toml").unwrap_err().to_string();
        assert!(err.contains("m.toml") && err.contains(field), "{field}: {err}");
        assert!(err.contains(&format!("line {line}:")), "{field}: {err}");
    }
    // Parameters are the named navigator's: astar-grid has no wedge budget.
    let err = Mission::from_toml(
        &format!("{DEFAULT_MISSION_TOML}\n[navigator_params]\nmax_wedges = 40\n"),
        "m.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("astar-grid") && err.contains("max_wedges"), "{err}");
}

#[test]
fn start_needs_one_coordinate_frame() {
    let text = DEFAULT_MISSION_TOML.replace("x = 5.0\n", "");
    let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
    assert!(err.contains("`start`"), "{err}");
}

#[test]
fn combinations_are_chosen_by_options_and_old_names_stay_aliases() {
    let with = |lines: &str| {
        let text = DEFAULT_MISSION_TOML.replace("navigator = \"astar-grid\"\n", "");
        Mission::from_toml(&format!("{lines}\n{text}"), "m.toml")
    };
    for (lines, spec) in [
        ("navigator = \"gestalt\"\nglobal_planner = \"field-dstar\"", "gestalt+field-dstar"),
        ("navigator = \"gestalt+field-dstar\"", "gestalt+field-dstar"),
        ("navigator = \"grid\"\nglobal_planner = \"dstar-lite\"", "mrpta"),
        ("navigator = \"grid\"", "astar-grid"),
        ("navigator = \"mrpta+look-back\"", "mrpta+look-back"),
    ] {
        assert_eq!(with(lines).unwrap().navigator_spec(), spec, "{lines}");
    }
    for (lines, field) in [
        ("navigator = \"gestalt\"\nglobal_planner = \"astar\"", "`global_planner`"),
        ("navigator = \"mrpta\"\nglobal_planner = \"astar\"", "`global_planner`"),
        ("navigator = \"sr2\"\nglobal_planner = \"astar\"", "`global_planner`"),
    ] {
        let err = with(lines).unwrap_err().to_string();
        assert!(err.contains(field) && err.contains("line 2"), "{lines}: {err}");
    }
    let m = Mission::from_toml(
        &format!("{DEFAULT_MISSION_TOML}\n[localizer_params]\nselect_targets = 1\n")
            .replace("\"dead-reckoning\"", "\"ekf-ml\""),
        "m.toml",
    )
    .unwrap();
    assert_eq!(m.localizer_spec(), "ekf-ml-targets");
    let text = DEFAULT_MISSION_TOML.replace("\"ekf-ml\"", "\"ekf-ml-targets\"");
    assert_eq!(Mission::from_toml(&text, "m.toml").unwrap().localizer_spec(), "ekf-ml-targets");
    for (bad, field) in
        [("min_travel_m = -1.0", "localizer_params.min_travel_m"), ("warp = 1", "localizer_params.warp")]
    {
        let full = format!("{DEFAULT_MISSION_TOML}\n[localizer_params]\n{bad}\n")
            .replace("\"dead-reckoning\"", "\"ekf-ml\"");
        let err = Mission::from_toml(&full, "m.toml").unwrap_err().to_string();
        assert!(
            err.contains(field) && err.contains(&format!("line {}", full.lines().count())),
            "{bad}: {err}"
        );
    }
}
