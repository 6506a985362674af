//! Hostile mission input (issue 44): each malformed mission of the issue is refused with one
//! line naming the file, the line and the field, before any world is built from it.

use rovernav_executive::Mission;
use rovernav_executive::mission::DEFAULT_MISSION_TOML;
use rovernav_harness::build_world;

/// The default mission with `extra` appended (a table) or `from` replaced by `to`.
fn refused(text: &str) -> String {
    let e = Mission::from_toml(text, "m.toml").expect_err("refused").to_string();
    assert!(!e.contains('\n') && e.starts_with("m.toml: "), "not one line naming the file: {e}");
    e
}

/// The world builder's refusal of `m`, as text.
fn world_error(m: &Mission) -> String {
    match build_world(m, "m.toml") {
        Ok(_) => panic!("the world was built"),
        Err(e) => e.to_string(),
    }
}

fn with_table(table: &str) -> String {
    format!("{DEFAULT_MISSION_TOML}\n{table}\n")
}

fn replaced(from: &str, to: &str) -> String {
    assert!(DEFAULT_MISSION_TOML.contains(from), "{from}");
    DEFAULT_MISSION_TOML.replace(from, to)
}

/// The 1-based line of the first line of `text` starting with `key`.
fn line_of(text: &str, key: &str) -> usize {
    text.lines().position(|l| l.trim_start().starts_with(key)).expect("key present") + 1
}

#[test]
fn mission_with_negative_clearance_is_refused() {
    let text = with_table("[rover]\nclearance_m = -1.0");
    let e = refused(&text);
    assert!(
        e.contains("`rover.clearance_m`") && e.contains(&format!("line {}", line_of(&text, "clearance_m"))),
        "{e}"
    );
}

#[test]
fn mission_with_nan_or_zero_rover_sizes_is_refused() {
    for line in [
        "width_m = nan",
        "length_m = 0.0",
        "max_speed_mps = inf",
        "mast_fov_deg = 0.0",
        "max_tilt_deg = 90.0",
    ] {
        let e = refused(&with_table(&format!("[rover]\n{line}")));
        let field = line.split(' ').next().unwrap();
        assert!(e.contains(&format!("`rover.{field}`")), "{line}: {e}");
    }
}

#[test]
fn mission_with_a_waypoint_at_1e308_is_refused() {
    let e = refused(&replaced("tolerance_m = 0.5", "tolerance_m = 0.5\nwaypoints = [[1e308, 5.0]]"));
    assert!(e.contains("`goal.waypoints[0]`") && e.contains("finite number"), "{e}");
    let e = refused(&replaced("x = 20.0", "x = 1e308"));
    assert!(e.contains("`goal`"), "{e}");
}

#[test]
fn waypoint_outside_the_terrain_is_refused_by_the_world() {
    let text = replaced("tolerance_m = 0.5", "tolerance_m = 0.5\nwaypoints = [[5000.0, 5.0]]");
    let m = Mission::from_toml(&text, "m.toml").unwrap();
    let e = world_error(&m);
    assert!(e.contains("goal.waypoints[0]") && e.contains("outside the terrain"), "{e}");
}

#[test]
fn mission_name_leaving_the_output_folder_is_refused() {
    for name in ["/tmp/escaped", "../escaped", "a/../../b", ".."] {
        let e = refused(&replaced("name = \"default-mars-yard\"", &format!("name = \"{name}\"")));
        assert!(e.contains("`name`") && e.contains("line 4"), "{name}: {e}");
    }
}

#[test]
fn mission_with_a_billion_craters_per_hectare_is_refused() {
    let e = refused(&replaced("slope_deg = 2.0", "slope_deg = 2.0\ncraters_per_hectare = 1e9"));
    assert!(e.contains("`terrain.craters_per_hectare`"), "{e}");
}

#[test]
fn keep_out_with_a_nan_vertex_is_refused() {
    let text = replaced(
        "tolerance_m = 0.5",
        "tolerance_m = 0.5\nkeep_out = [[[10.0, 10.0], [nan, 12.0], [12.0, 10.0]]]",
    );
    let e = refused(&text);
    assert!(e.contains("`goal.keep_out[0]`") && e.contains("finite"), "{e}");
}

#[test]
fn arrival_tolerance_is_bounded() {
    for tol in ["1e308", "0.0", "nan", "11.0"] {
        let e = refused(&replaced("tolerance_m = 0.5", &format!("tolerance_m = {tol}")));
        assert!(e.contains("`goal.tolerance_m`") && e.contains("line 26"), "{tol}: {e}");
    }
    Mission::from_toml(&replaced("tolerance_m = 0.5", "tolerance_m = 10.0"), "m.toml").unwrap();
}

#[test]
fn navigator_parameters_that_are_not_finite_are_refused() {
    let e = refused(&with_table("[navigator_params]\nmax_step_m = nan"));
    assert!(e.contains("navigator_params"), "{e}");
}

#[test]
fn navigator_lengths_and_counts_are_bounded() {
    // Found by the mission fuzz target: a 1e9 m map margin overflowed a grid allocation.
    // A 100 m safety buffer stalled the run for over two minutes growing hazards.
    for (line, field) in [
        ("map_margin_m = 1e9", "map_margin_m"),
        ("map_margin_m = 101", "map_margin_m"),
        ("safety_buffer_m = 100", "safety_buffer_m"),
        ("patience = 1e12", "patience"),
    ] {
        let e = refused(&with_table(&format!("[navigator_params]\n{line}")));
        assert!(e.contains(&format!("`navigator_params.{field}`")), "{line}: {e}");
    }
}

#[test]
fn dem_resolution_is_bounded() {
    // Found by the mission fuzz target: 4294967296 m overflowed a grid allocation (panic).
    let gale = include_str!("../../../missions/gale-traverse.toml");
    for res in ["4294967296", "0.0001", "nan"] {
        let text = gale.replace("resolution_m = 0.1", &format!("resolution_m = {res}"));
        assert_ne!(text, gale);
        let e = refused(&text);
        assert!(e.contains("`terrain.resolution_m`") && e.contains("line "), "{res}: {e}");
    }
    let text = gale.replace("8142640.0, -276640.0]", "8152640.0, -266640.0]");
    assert_ne!(text, gale);
    let e = refused(&text);
    assert!(e.contains("over 1e8 cells"), "{e}");
}

#[cfg(unix)]
#[test]
fn dem_path_that_is_a_fifo_is_refused_without_blocking() {
    let dir = std::env::temp_dir().join(format!("rovernav-fifo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("dem.tif");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
    if !made {
        eprintln!("skipped: mkfifo is not available");
        return;
    }
    let text = DEFAULT_MISSION_TOML.replace(
        "kind = \"procedural\"\nsize_m = 30.0\nresolution_m = 0.05\nrock_abundance = 0.16\nrelief_m = 0.25\nslope_deg = 2.0",
        &format!("kind = \"dem\"\npath = \"{}\"", fifo.display()),
    );
    let m = Mission::from_toml(&text, "m.toml").unwrap();
    let e = world_error(&m);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(e.contains("terrain.path") && e.contains("not a regular file"), "{e}");
}
