//! Fuzz targets (issue 44), property-based on stable Rust: the mission parser (and the world and
//! component graph of every mission it accepts), the command language, the MovingAI `.map` and
//! `.scen` parsers, the PGM reader and the npy, GeoTIFF and PDS3 loaders. Each target mutates
//! the files of its seed corpus (`tests/fuzz_corpus/<target>/` at the workspace root: the
//! shipped inputs and the hostile cases of the issue) byte by byte and with a dictionary of
//! hostile tokens, and requires no panic and, for text inputs, a one-line error.
//! `PROPTEST_CASES` sets the cases per target (CI runs a few hundred; a long run sets more).

use proptest::prelude::*;
use rovernav_executive::{Mission, Run, parse_command};
use rovernav_harness::JudgedRun;
use std::path::Path;

#[path = "../../../tests/fuzz_corpus/mutate.rs"]
mod mutate;

use mutate::input;

thread_local! {
    /// The case being run, printed by the panic hook.
    static CURRENT: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// Prints `text` with any panic of this case, at once: a case that aborts (or that proptest
/// shrinks for minutes) still shows its input.
fn show_on_panic(text: &str) {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            CURRENT.with(|c| eprintln!("fuzz input that panicked:\n{}\n---", c.borrow()));
            default(info);
        }));
    });
    CURRENT.with(|c| *c.borrow_mut() = text.to_string());
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fuzz_mission_parser_world_and_graph((path, bytes) in input("mission")) {
        let text = String::from_utf8_lossy(&bytes);
        show_on_panic(&text);
        match Mission::from_toml(&text, "fuzz.toml") {
            Err(e) => prop_assert!(!e.to_string().contains('\n'), "{}: {e}", path.display()),
            Ok(mission) => {
                // Small worlds only, so a case stays fast: the checks under test are the edge's.
                let small = match &mission.terrain {
                    rovernav_executive::mission::TerrainSpec::Procedural { size_m, resolution_m, .. } => {
                        (size_m / resolution_m).powi(2) <= 4.0e5
                    }
                    rovernav_executive::mission::TerrainSpec::Dem { .. } => true,
                    // A tiled world's overview spans the route: only short routes are small.
                    rovernav_executive::mission::TerrainSpec::Tiled(_) => false,
                };
                if small
                    && let Ok(run) = Run::mission(&mission, "fuzz.toml")
                {
                    let _ = run.graph();
                }
            }
        }
    }

    #[test]
    fn fuzz_command_language((_, bytes) in input("command")) {
        for line in String::from_utf8_lossy(&bytes).lines() {
            if let Err(e) = parse_command(line) {
                prop_assert!(!e.to_string().contains('\n'), "{line:?}: {e}");
            }
        }
    }

    #[test]
    fn fuzz_movingai_map_and_scen((_, map) in input("map"), (_, scen) in input("scen")) {
        let map = rovernav_planning::movingai::parse_map(&String::from_utf8_lossy(&map));
        let scen = rovernav_planning::movingai::parse_scenarios(&String::from_utf8_lossy(&scen));
        if let (Ok(map), Ok(scen)) = (map, scen) {
            let _ = rovernav_planning::benchmark::run_movingai(&map, "fuzz", &scen, "astar", 1);
        }
    }

    #[test]
    fn fuzz_pgm((_, bytes) in input("pgm")) {
        let _ = rovernav_planning::pgm::parse_cost_map(&bytes);
    }

    #[test]
    fn fuzz_npy((_, bytes) in input("npy"), resolution in prop_oneof![Just(0.5), any::<f64>()]) {
        let _ = rovernav_terrain::io::parse_npy(Path::new("fuzz.npy"), &bytes, resolution);
    }

    #[test]
    fn fuzz_geotiff((_, bytes) in input("tiff")) {
        let _ = rovernav_terrain::io::parse_geotiff(Path::new("fuzz.tif"), &bytes);
    }

    #[test]
    fn fuzz_pds3((_, bytes) in input("pds3")) {
        let dir = std::env::temp_dir().join(format!("rovernav-fuzz-pds3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join(format!("{:?}.img", std::thread::current().id()).replace(['(', ')'], ""));
        std::fs::write(&file, &bytes).unwrap();
        let _ = rovernav_terrain::io::Pds3Image::open(&file);
        let _ = std::fs::remove_file(&file);
    }
}
