//! `rovernav eval terrain`: terrain assessment against simulator truth on the default Mars yard.
//!
//! For each seed the rover stands at the mission start and images a full circle with the mast
//! (eight 45 deg wedges) and both body pairs; the navigators' terrain evaluator turns the points
//! into elevation and hazard layers, placed with the pose the operators gave the rover. Recall of
//! hazard rocks (taller than the true clearance) within 5 m, the false-hazard rate over truly
//! safe sensed cells and the elevation RMSE are pooled over all seeds. Hazard cells include the
//! uncertain ones (raised to within far-range noise of the clearance), which the navigators
//! never drive over before a closer look has settled them.
//!
//! `--model` picks the hazard model: the grid navigators' (default), or one of RoverBug's two,
//! the cell-mean model its C-obstacles come from and its safety layer on top heights (before
//! the layer's own confirmation against the ground around each cell).

use anyhow::Context;
use rovernav_core::{NavCommand, Point2, Pose3, PoseEstimate, SenseRequest};
use rovernav_executive::Mission;
use rovernav_harness::build_world;
use rovernav_navigation::params::configured;
use rovernav_navigation::roverbug::{RoverBugConfig, c_obstacle_terrain, safety_terrain};
use rovernav_navigation::{NavigatorParams, TerrainModel};
use rovernav_perception::TerrainConfig;
use rovernav_perception::TerrainEvaluator;
use rovernav_perception::evaluation::{TrueRock, evaluate_terrain};
use rovernav_sim::Simulator;

/// Options of `rovernav eval terrain`.
#[derive(clap::Args, Debug)]
pub struct EvalTerrainArgs {
    /// Seeds of the default Mars yard, as FIRST..LAST (inclusive).
    #[arg(long, default_value = "1..20")]
    pub seeds: String,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
    /// Hazard model to evaluate.
    #[arg(long, value_enum, default_value_t = HazardModel::Grid)]
    pub model: HazardModel,
    /// Set a RoverBug parameter for the RoverBug models, NAME=VALUE (repeatable; `rovernav
    /// navigators` lists them).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
}

/// The hazard models `rovernav eval terrain` can score.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum HazardModel {
    /// The grid navigators' model (top heights, uncertain hazards included).
    Grid,
    /// RoverBug's C-obstacle model (cell means over one sensing position's wedges).
    Roverbug,
    /// RoverBug's safety layer (top heights on finer cells).
    RoverbugSafety,
}

impl HazardModel {
    /// The name `--model` takes.
    fn name(self) -> String {
        clap::ValueEnum::to_possible_value(&self).map_or_else(String::new, |v| v.get_name().to_string())
    }

    /// The perception settings of this model for a rover, with RoverBug's parameters `params`
    /// (the grid model takes none).
    fn config(
        self,
        rover: &rovernav_core::RoverConfig,
        params: &NavigatorParams,
    ) -> anyhow::Result<TerrainConfig> {
        if self == HazardModel::Grid {
            anyhow::ensure!(
                params.is_empty(),
                "--param: the grid model takes no parameters (only the roverbug models)"
            );
            return Ok(TerrainModel::perception_config(rover, 0.1));
        }
        let roverbug = configured("roverbug", RoverBugConfig::default(), &RoverBugConfig::params(), params)
            .map_err(|e| anyhow::anyhow!("--param: {e}"))?;
        Ok(match self {
            HazardModel::Roverbug => c_obstacle_terrain(rover, &roverbug),
            _ => safety_terrain(rover, &roverbug),
        })
    }
}

/// Parses `A..B` (inclusive) or a single seed.
pub fn parse_seed_range(s: &str) -> anyhow::Result<std::ops::RangeInclusive<u64>> {
    let parse =
        |t: &str| t.trim().parse::<u64>().with_context(|| format!("--seeds: `{t}` is not a seed number"));
    match s.split_once("..") {
        Some((a, b)) => {
            let (a, b) = (parse(a)?, parse(b.trim_start_matches('='))?);
            anyhow::ensure!(a <= b, "--seeds: empty range `{s}`");
            Ok(a..=b)
        }
        None => {
            let a = parse(s)?;
            Ok(a..=a)
        }
    }
}

/// Runs the evaluation and prints the figures.
pub fn run(args: EvalTerrainArgs) -> anyhow::Result<()> {
    let seeds = parse_seed_range(&args.seeds)?;
    let mut params = NavigatorParams::new();
    for param in &args.params {
        let (name, value) = crate::parse_param(param)?;
        params.insert(name, value);
    }
    // Bad parameters fail before any seed is imaged.
    args.model.config(&rovernav_core::RoverConfig::default(), &params)?;
    let (mut rocks, mut detected, mut safe, mut false_hazards, mut cells, mut hazard_cells) =
        (0usize, 0usize, 0usize, 0usize, 0usize, 0usize);
    let mut sq_err_sum = 0.0;
    for seed in seeds.clone() {
        let mut mission = Mission::default_mission();
        mission.seed = seed;
        let world = build_world(&mission, "built-in default mission")?;
        let mut sim = Simulator::new(
            world.terrain.clone(),
            world.rover.clone(),
            world.sensor_model.clone(),
            world.start,
            seed,
        );
        let _ = sim.initial_frame();
        let mut requests: Vec<SenseRequest> =
            (0..8).map(|k| SenseRequest::Mast { pan: k as f64 * std::f64::consts::FRAC_PI_4 }).collect();
        requests.extend([SenseRequest::BodyFront, SenseRequest::BodyRear]);
        let frame = sim.execute(&NavCommand::Sense(requests));
        // The operators know the start pose (and its elevation, from the orbital DEM).
        let start = sim.truth();
        let estimate = PoseEstimate {
            pose: Pose3 {
                x: start.x,
                y: start.y,
                z: start.z,
                roll: start.roll,
                pitch: start.pitch,
                yaw: start.yaw,
            },
            covariance: [[0.0; 3]; 3],
        };
        let detector = args.model.config(&world.rover, &params)?;
        let resolution = detector.resolution;
        let mut evaluator = TerrainEvaluator::new(detector, world.start)?;
        let layers = evaluator.update(&frame.clouds, &estimate);
        let true_rocks: Vec<TrueRock> = world
            .terrain
            .rocks
            .iter()
            .map(|r| TrueRock { x: r.x, y: r.y, diameter: r.diameter, height: r.height })
            .collect();
        // Truth uses the rover's real limits, not the detector's margins.
        let truth_config = TerrainConfig { resolution, ..TerrainConfig::for_rover(&world.rover) };
        let dem = &world.terrain.dem;
        let f = evaluate_terrain(
            &true_rocks,
            |x, y| dem.height(x, y),
            &layers.map.elevation,
            &layers.hazard,
            Point2::new(start.x, start.y),
            &truth_config,
        )?;
        rocks += f.hazard_rocks;
        detected += f.hazard_rocks_detected;
        safe += f.truly_safe_cells;
        false_hazards += f.false_hazard_cells;
        cells += f.sensed_cells;
        hazard_cells += f.hazard_cells;
        if f.elevation_rmse_m.is_finite() {
            sq_err_sum += f.elevation_rmse_m.powi(2) * f.sensed_cells as f64;
        }
    }
    let recall = detected as f64 / rocks.max(1) as f64;
    let false_rate = false_hazards as f64 / safe.max(1) as f64;
    let rmse = (sq_err_sum / cells.max(1) as f64).sqrt();
    if args.json {
        let v = serde_json::json!({
            "seeds": format!("{}..{}", seeds.start(), seeds.end()),
            "model": args.model.name(),
            "hazard_recall": recall,
            "false_hazard_rate": false_rate,
            "elevation_rmse_m": rmse,
            "hazard_rocks": rocks,
            "hazard_rocks_detected": detected,
            "truly_safe_cells": safe,
            "false_hazard_cells": false_hazards,
            "sensed_cells": cells,
            "hazard_cells": hazard_cells,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "seeds {}..{}: hazard recall {:.3} ({detected}/{rocks} rocks), false hazard rate {:.4} ({false_hazards}/{safe} safe cells), elevation RMSE {:.3} m over {cells} cells ({} model)",
            seeds.start(),
            seeds.end(),
            recall,
            false_rate,
            rmse,
            args.model.name()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_ranges_parse_inclusively() {
        assert_eq!(parse_seed_range("1..20").unwrap(), 1..=20);
        assert_eq!(parse_seed_range("7").unwrap(), 7..=7);
        assert!(parse_seed_range("5..2").is_err());
        assert!(parse_seed_range("a..2").unwrap_err().to_string().contains("--seeds"));
    }
}
