//! Tests of the registry: aliases expand to the combinations the old names built, names are
//! unique, unknown names list the known ones.

use super::*;
use crate::GridNavigatorConfig;
use crate::gestalt::GestaltConfig;
use rovernav_localization::EkfMlParams;

/// The old names and what the code before the registry built for each: (old name, entry,
/// global planner, the config it set).
const OLD_NAMES: [(&str, &str, Option<&str>); 7] = [
    ("astar-grid", "grid", Some("astar")),
    ("mrpta", "grid", Some("dstar-lite")),
    ("gestalt", "gestalt", Some("none")),
    ("gestalt+field-dstar", "gestalt", Some("field-dstar")),
    ("sr2", "sr2", None),
    ("nat", "nat", None),
    ("roverbug", "roverbug", None),
];

#[test]
fn every_old_name_expands_to_the_combination_it_built_and_reports_the_same_name() {
    let r = Registry::builtin();
    let rover = RoverConfig::default();
    assert_eq!(r.navigator_names(), OLD_NAMES.map(|(n, _, _)| n).to_vec(), "`all` keeps its order");
    for (old, entry, planner) in OLD_NAMES {
        for name in [old.to_string(), format!("{old}{LOOK_BACK_SUFFIX}")] {
            let c = r.navigator(&name, None).unwrap();
            assert_eq!((c.entry.name, c.global_planner, c.label), (entry, planner, old), "{name}");
            assert_eq!(c.look_back, name.ends_with(LOOK_BACK_SUFFIX), "{name}");
            assert_eq!(c.spec(), name);
            // The navigator reports the old name, as reports and campaign rows did.
            assert_eq!(r.build_navigator(&name, &rover, &NavigatorParams::new()).unwrap().name(), old);
        }
        // The mission-file spelling (entry + global_planner) is the same combination.
        let spelled = r.navigator(entry, planner).unwrap();
        assert_eq!((spelled.label, spelled.global_planner), (old, planner));
    }
    // The configs the constructors set are the old ones: grid's planner and GESTALT's switch.
    let grid = |planner| {
        let b = NavigatorBuild {
            label: "x",
            global_planner: Some(planner),
            rover: &rover,
            params: &NavigatorParams::new(),
        };
        b.configured(GridNavigatorConfig { planner, ..Default::default() }, &GridNavigatorConfig::params())
            .unwrap()
    };
    assert_eq!(grid("dstar-lite").planner, "dstar-lite");
    assert_eq!(format!("{:?}", grid("astar")), format!("{:?}", GridNavigatorConfig::default()));
    assert!(!GestaltConfig::default().field_dstar, "plain gestalt is the default config");
    assert_eq!(r.navigator("grid+dstar-lite", None).unwrap().label, "mrpta");
}

#[test]
fn parameters_reach_the_entry_whatever_the_name_and_errors_name_the_label() {
    let r = Registry::builtin();
    for name in ["mrpta", "astar-grid+look-back", "grid"] {
        let params = (r.navigator(name, None).unwrap().entry.params)();
        assert!(params.iter().any(|p| p.name == "map_resolution_m"), "{name}");
    }
    let tiny: NavigatorParams = [("map_resolution_m".to_string(), 1e-6)].into();
    let err = r.check_navigator("mrpta", &tiny).unwrap_err();
    assert!(
        err.to_string().contains("navigator `mrpta`") && err.param() == Some("map_resolution_m"),
        "{err}"
    );
}

#[test]
fn unknown_names_and_planners_are_one_line_errors_listing_the_known_ones() {
    let r = Registry::builtin();
    let err = r.navigator("warp-drive", None).unwrap_err().to_string();
    assert!(!err.contains('\n'), "{err}");
    for name in ["warp-drive", "grid", "astar-grid", "mrpta", "gestalt+field-dstar", "roverbug"] {
        assert!(err.contains(name), "{name} missing from: {err}");
    }
    let err = r.navigator("gestalt", Some("astar")).unwrap_err();
    assert!(err.is_about_global_planner() && err.to_string().contains("none, field-dstar"), "{err}");
    let err = r.navigator("sr2", Some("astar")).unwrap_err().to_string();
    assert!(err.contains("takes no global planner"), "{err}");
    let err = r.navigator("mrpta", Some("astar")).unwrap_err().to_string();
    assert!(err.contains("`dstar-lite`") && err.contains("`astar`"), "{err}");
    assert!(r.navigator("mrpta", Some("dstar-lite")).is_ok());
    let err = r.localizer("gps", &NavigatorParams::new()).err().unwrap().to_string();
    let known = "dead-reckoning, ekf, ekf-ml, orbital-map, lander, ekf-ml-targets";
    assert!(!err.contains('\n') && err.contains(known), "{err}");
    let err = r.check_localizer("ekf", &[("min_travel_m".to_string(), 1.0)].into()).unwrap_err().to_string();
    assert!(err.contains("localizer `ekf` takes no parameters"), "{err}");
    let err = r.check_localizer("ekf-ml", &[("min_travel_m".to_string(), -1.0)].into()).unwrap_err();
    assert!(
        err.to_string().contains("of localizer `ekf-ml`") && err.param() == Some("min_travel_m"),
        "{err}"
    );
}

#[test]
fn no_name_is_registered_twice() {
    let r = Registry::builtin();
    let mut names: Vec<&str> = r.navigators().iter().map(|e| e.name).collect();
    for label in r.navigator_names() {
        // A label equal to its own entry's name (`gestalt`) is the same navigator.
        if !r.navigators().iter().any(|e| e.name == label && e.labels().contains(&label)) {
            names.push(label);
        }
    }
    let mut sorted = names.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), names.len(), "{names:?}");
    let mut localizers = r.localizer_names();
    let n = localizers.len();
    localizers.sort_unstable();
    localizers.dedup();
    assert_eq!(localizers.len(), n);
}

#[test]
#[should_panic(expected = "navigator name `mrpta` is registered twice")]
fn registering_a_taken_name_panics_naming_it() {
    let mut again = crate::sr2::ENTRY;
    again.name = "mrpta";
    let _ = Registry::builtin().with(again);
}

#[test]
fn the_localizer_alias_is_ekf_ml_with_target_selection_and_specs_round_trip() {
    let r = Registry::builtin();
    let rover = RoverConfig::default();
    let alias = r.localizer("ekf-ml-targets", &NavigatorParams::new()).unwrap();
    assert_eq!(alias.entry.name, "ekf-ml");
    assert_eq!(alias.params, [("select_targets".to_string(), 1.0)].into());
    let spelled = r.localizer("ekf-ml", &[("select_targets".to_string(), 1.0)].into()).unwrap();
    assert_eq!(r.localizer_spec(&spelled), "ekf-ml-targets");
    // The built localiser is the one the old name built (EkfMl reports its target switch).
    let built =
        r.build_localizer("ekf-ml-targets", &rover, Pose3::default(), &NavigatorParams::new()).unwrap();
    assert_eq!(built.name(), "ekf-ml-targets");
    let old = EkfMlParams { select_targets: true, ..Default::default() };
    let b = LocalizerBuild {
        name: "ekf-ml",
        rover: &rover,
        initial: Pose3::default(),
        params: &alias.params,
        prior_map: None,
    };
    assert_eq!(b.configured(EkfMlParams::default(), &crate::localizers::ekf_ml_params()).unwrap(), old);
    // Parameters without an alias travel in the spec and come back.
    let other = r.localizer("ekf-ml", &[("min_travel_m".to_string(), 2.5)].into()).unwrap();
    let spec = r.localizer_spec(&other);
    assert_eq!(spec, "ekf-ml(min_travel_m=2.5)");
    assert_eq!(r.localizer(&spec, &NavigatorParams::new()).unwrap().params, other.params);
    for name in ["dead-reckoning", "ekf", "ekf-ml"] {
        let l = r.build_localizer(name, &rover, Pose3::default(), &NavigatorParams::new()).unwrap();
        assert_eq!(l.name(), name);
    }
    // The localisation crate's name-only builder agrees with the registry on every name that
    // needs no orbital map.
    for name in r.localizer_names().into_iter().filter(|n| !r.localizer_needs_prior_map(n)) {
        let direct = rovernav_localization::localizer_by_name(name, &rover, Pose3::default());
        assert_eq!(direct.map(|l| l.name().to_string()).as_deref(), Some(name), "{name}");
    }
    assert!(rovernav_localization::localizer_by_name("gps", &rover, Pose3::default()).is_none());
}

#[test]
fn the_orbital_map_localizer_needs_a_prior_map_and_builds_with_one() {
    let r = Registry::builtin();
    let rover = RoverConfig::default();
    assert!(r.localizer_needs_prior_map("orbital-map"));
    assert!(!r.localizer_needs_prior_map("ekf-ml"));
    let none = r.build_localizer("orbital-map", &rover, Pose3::default(), &NavigatorParams::new());
    let err = none.err().expect("no prior map, no localiser").to_string();
    assert!(err.contains("orbital-map") && err.contains("orbital map"), "{err}");
    // A mission's checks pass on a stand-in map; parameters are checked as for any localiser.
    assert!(r.check_localizer("orbital-map", &[("fix_interval_m".to_string(), 50.0)].into()).is_ok());
    let bad = r.check_localizer("orbital-map", &[("fix_interval_m".to_string(), -1.0)].into());
    assert_eq!(bad.err().and_then(|e| e.param().map(str::to_string)).as_deref(), Some("fix_interval_m"));
    let geometry =
        rovernav_core::GridGeometry { cols: 20, rows: 20, resolution: 1.0, origin_x: -10.0, origin_y: -10.0 };
    let map = rovernav_core::Grid2::filled(geometry, 0.0f32);
    let params = NavigatorParams::new();
    let built = r.build_localizer_with_prior("orbital-map", &rover, Pose3::default(), &params, Some(&map));
    assert_eq!(built.map(|l| l.name().to_string()).ok().as_deref(), Some("orbital-map"));
    assert_eq!(r.decorated("astar-grid", "orbital-map"), "astar-grid+look-back");
}

#[test]
fn map_matching_localizers_decorate_the_navigator_with_the_look_back() {
    let r = Registry::builtin();
    assert_eq!(r.decorated("astar-grid", "ekf-ml"), "astar-grid+look-back");
    assert_eq!(r.decorated("mrpta+look-back", "ekf-ml-targets"), "mrpta+look-back");
    assert_eq!(r.decorated("gestalt+field-dstar", "ekf"), "gestalt+field-dstar");
    assert_eq!(r.decorated("warp-drive", "ekf-ml"), "warp-drive");
    assert_eq!(r.decorated("grid", "dead-reckoning"), "astar-grid");
}

#[test]
fn listed_defaults_read_as_written_in_degrees() {
    let r = Registry::builtin();
    let sr2 = r.navigators().iter().find(|e| e.name == "sr2").expect("sr2 is registered");
    let params = (sr2.params)();
    let get = |name: &str| params.iter().find(|p| p.name == name).map(|p| p.default);
    // Stored in radians, listed in degrees: the listing shows the round figure of the paper.
    assert_eq!(get("side_rotation_deg"), Some(30.0));
    assert_eq!(get("middle_rotation_deg"), Some(60.0));
    assert_eq!(get("max_tilt_deg"), Some(15.0));
    assert_eq!(to_twelve_digits(0.1 + 0.2), 0.3);
    assert_eq!(to_twelve_digits(-2.5e-7), -2.5e-7);
}
