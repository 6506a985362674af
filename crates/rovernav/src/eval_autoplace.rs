//! `rovernav eval autoplace`: AutoPlace (paper 003 section 4, `rovernav_manipulation`) on
//! generated scenes, scored against the simulator's truth.
//!
//! Each trial generates a scene ([`scene`]: rocks of different sizes and tilts in front of the
//! rover, a commanded target on a rock, on soil or at the edge of the arm's reach, the sun at
//! any hour from 8 to 17, stereo dropouts over the target, or a dropout hiding a rock in the
//! arm's path), renders and correlates the stereo pairs ([`sensing`]), runs AutoPlace on what
//! the cameras saw, and executes a placement against the true terrain ([`truth`]).
//!
//! For the hidden-rock scenes the rock is put where it matters: the scene is first sensed
//! without it, a planner that treats missing data as free space plans on it, and the rock rises
//! 5 cm above that plan's lowest arm point over the hole's centre (at least 15 cm from the
//! target). Both AutoPlace and that naive planner then run on the images with the rock; the
//! report counts AutoPlace's refusals and the naive planner's collisions in truth.
//!
//! Figures: `trials`, `placed`, `refused` (`total` and a count per reason: `no_data`, `normal`,
//! `roughness`, `reach`, `collision`), `collisions` (a placement's
//! arm meeting terrain, rock, rover or itself in truth), `max_normal_error_deg` (approach
//! against the true surface normal over every placement), `contacts_missed`,
//! `hidden_obstacle_scenes` and `refused_on_hidden_obstacle`, and per scene kind.

mod scene;
mod sensing;

use nalgebra::Vector3;
use rayon::prelude::*;
use rovernav_core::RoverConfig;
use rovernav_manipulation::execution as truth;
use rovernav_manipulation::feasibility::interpolate;
use rovernav_manipulation::{Arm, AutoPlaceParams, Outcome, Reason, View, autoplace, place_with};
use scene::Kind;
use serde::Serialize;
use std::collections::BTreeMap;

/// Options of `rovernav eval autoplace`.
#[derive(clap::Args, Debug)]
pub struct EvalAutoplaceArgs {
    /// Number of generated scenes.
    #[arg(long, default_value_t = 100)]
    pub trials: usize,
    /// Seed of the first scene (the others follow).
    #[arg(long, default_value_t = 1)]
    pub first_seed: u64,
    /// Image width and height of every camera (pixels).
    #[arg(long, default_value_t = 512)]
    pub width: usize,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One trial's result.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Trial {
    /// Scene seed.
    pub seed: u64,
    /// Scene kind.
    pub kind: Kind,
    /// "placed" or the refusal reason.
    pub outcome: String,
    /// Candidates examined.
    pub examined: usize,
    /// Points each stereo pair sensed.
    pub points: BTreeMap<String, usize>,
    /// Chosen target (body frame, m), if placed.
    pub target: Option<[f64; 3]>,
    /// Its estimated normal, if placed.
    pub normal: Option<[f64; 3]>,
    /// The approach direction, if placed.
    pub axis: Option<[f64; 3]>,
    /// Where the contact face stopped in truth, if placed.
    pub stop: Option<[f64; 3]>,
    /// What the arm met in truth, if anything.
    pub collision: Option<&'static str>,
    /// Whether the contact face met the surface.
    pub contact: bool,
    /// Contact angle error against the true normal (deg), if placed.
    pub normal_error_deg: Option<f64>,
    /// Hidden-rock scenes: what the planner treating missing data as free did ("placed",
    /// "collided" when its placement met something in truth, or its refusal reason).
    pub naive: Option<String>,
}

/// Counts for one scene kind.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct KindCounts {
    /// Trials.
    pub trials: usize,
    /// Placements.
    pub placed: usize,
    /// Refusals.
    pub refused: usize,
}

/// The figures of `rovernav eval autoplace`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct AutoplaceEvaluation {
    /// Trials run.
    pub trials: usize,
    /// Placements made.
    pub placed: usize,
    /// Refusals: `total` and a count per reason.
    pub refused: BTreeMap<&'static str, usize>,
    /// Placements whose arm met terrain, rock, rover or itself in truth.
    pub collisions: usize,
    /// Largest angle between a placement's approach and the true surface normal (deg).
    pub max_normal_error_deg: f64,
    /// Mean of the same angle (deg).
    pub mean_normal_error_deg: f64,
    /// Placements whose contact face never met the surface.
    pub contacts_missed: usize,
    /// Scenes where a dropout hides a rock in the arm's path.
    pub hidden_obstacle_scenes: usize,
    /// Of those, the ones AutoPlace refused.
    pub refused_on_hidden_obstacle: usize,
    /// Of those, the ones where a planner treating missing data as free collided in truth.
    pub hidden_obstacle_naive_collisions: usize,
    /// Per scene kind.
    pub by_kind: BTreeMap<&'static str, KindCounts>,
    /// Every trial.
    pub trial_results: Vec<Trial>,
}

/// Runs the evaluation and prints it.
pub fn run(args: EvalAutoplaceArgs) -> anyhow::Result<()> {
    crate::output::print_evaluation(args.json, &evaluate(&args)?, print_table)
}

/// Runs the trials (in parallel) and pools them.
pub fn evaluate(args: &EvalAutoplaceArgs) -> anyhow::Result<AutoplaceEvaluation> {
    anyhow::ensure!(args.trials > 0, "--trials must be at least 1");
    anyhow::ensure!((64..=1024).contains(&args.width), "--width {} must be 64..1024", args.width);
    let imaging = sensing::Imaging { width: args.width, ..sensing::Imaging::default() };
    let seeds: Vec<u64> = (0..args.trials as u64).map(|i| args.first_seed.wrapping_add(i)).collect();
    let trials: Vec<Trial> = seeds.par_iter().map(|&s| trial(s, &imaging)).collect();
    Ok(pool(trials))
}

/// The views of the sensed pairs.
fn views(pairs: &[sensing::Pair]) -> Vec<View<'_>> {
    pairs.iter().map(|p| View { cameras: &p.cameras, points: &p.points }).collect()
}

/// The lowest point of the arm's planned path more than 15 cm (horizontally) from the target
/// and ahead of the body: (x, y, z) of the lowest capsule bottom.
fn lowest_path_point(
    arm: &Arm,
    plan: &rovernav_manipulation::feasibility::Plan,
    target: &Vector3<f64>,
) -> Option<[f64; 3]> {
    let mut best: Option<[f64; 3]> = None;
    let poses = plan.via.windows(2).flat_map(|w| interpolate(arm, &w[0], &w[1], 0.01));
    for q in poses {
        for c in arm.capsules(&q) {
            for p in c.cover(0.01) {
                let far = (p.xy() - target.xy()).norm() > 0.15 && p.x > 0.62;
                let z = p.z - c.radius;
                if far && best.is_none_or(|b| z < b[2]) {
                    best = Some([p.x, p.y, z]);
                }
            }
        }
    }
    best
}

/// One trial.
fn trial(seed: u64, imaging: &sensing::Imaging) -> Trial {
    let rover = RoverConfig::default();
    let arm = Arm::new(&rover);
    let params = AutoPlaceParams::default();
    let base = [arm.geometry.base.x, arm.geometry.base.y];
    let mut scene = scene::generate(seed, base);
    let mut hidden_ready = false;
    if scene.kind == Kind::HiddenRock {
        // Sense without the rock and let the naive planner choose its path.
        let terrain = scene.terrain();
        let pairs = sensing::sense(&scene, &terrain, &rover, &arm.rover, imaging);
        let tree =
            rovernav_manipulation::terrain_model(&arm, &views(&pairs), &params.octree).unknown_as_free();
        if let Outcome::Placed { plan, .. } =
            place_with(&arm, &tree, &pairs[0].points, Some(&pairs[2].points), &scene.target, &params)
            && let Some(p) = lowest_path_point(&arm, &plan, &scene.target)
        {
            scene::hide_rock(&mut scene, p, 0.05);
            hidden_ready = true;
        }
    }
    let terrain = scene.terrain();
    let pairs = sensing::sense(&scene, &terrain, &rover, &arm.rover, imaging);
    let (outcome, tree) =
        autoplace(&arm, &views(&pairs), &pairs[0].points, Some(&pairs[2].points), &scene.target, &params);
    let naive = hidden_ready.then(|| {
        match place_with(
            &arm,
            &tree.unknown_as_free(),
            &pairs[0].points,
            Some(&pairs[2].points),
            &scene.target,
            &params,
        ) {
            Outcome::Placed { plan, .. } => {
                let e = truth::execute(&arm, &|x, y| terrain.dem.height(x, y), &plan);
                if e.collision.is_some() { "collided".to_string() } else { "placed".to_string() }
            }
            Outcome::Refused { reason, .. } => reason.name().to_string(),
        }
    });
    // A hidden-rock scene whose naive planner found no path has no rock in any path: score it
    // as the target kind it really is.
    let points = pairs.iter().map(|p| (p.name.clone(), p.points.len())).collect();
    let kind = if scene.kind == Kind::HiddenRock && !hidden_ready { Kind::Soil } else { scene.kind };
    match outcome {
        Outcome::Placed { target, plan, examined } => {
            let e = truth::execute(&arm, &|x, y| terrain.dem.height(x, y), &plan);
            Trial {
                seed,
                kind,
                outcome: "placed".into(),
                examined,
                points,
                target: Some(target.point),
                normal: Some(target.normal),
                axis: Some(plan.axis),
                stop: Some(e.stop),
                collision: e.collision,
                contact: e.contact,
                normal_error_deg: e.normal_error_deg.is_finite().then_some(e.normal_error_deg),
                naive,
            }
        }
        Outcome::Refused { reason, examined } => Trial {
            seed,
            kind,
            outcome: reason.name().into(),
            examined,
            points,
            target: None,
            normal: None,
            axis: None,
            stop: None,
            collision: None,
            contact: false,
            normal_error_deg: None,
            naive,
        },
    }
}

/// Pools the trials.
fn pool(trials: Vec<Trial>) -> AutoplaceEvaluation {
    let placed: Vec<&Trial> = trials.iter().filter(|t| t.outcome == "placed").collect();
    let mut refused: BTreeMap<&'static str, usize> = Reason::ALL.iter().map(|r| (r.name(), 0)).collect();
    for t in &trials {
        if let Some(r) = Reason::ALL.iter().find(|r| r.name() == t.outcome) {
            *refused.entry(r.name()).or_default() += 1;
        }
    }
    refused.insert("total", trials.len() - placed.len());
    let errors: Vec<f64> = placed.iter().filter_map(|t| t.normal_error_deg).collect();
    let hidden: Vec<&Trial> = trials.iter().filter(|t| t.kind == Kind::HiddenRock).collect();
    let mut by_kind: BTreeMap<&'static str, KindCounts> = BTreeMap::new();
    for t in &trials {
        let k = by_kind.entry(t.kind.name()).or_default();
        k.trials += 1;
        if t.outcome == "placed" {
            k.placed += 1;
        } else {
            k.refused += 1;
        }
    }
    AutoplaceEvaluation {
        trials: trials.len(),
        placed: placed.len(),
        refused,
        collisions: placed.iter().filter(|t| t.collision.is_some()).count(),
        max_normal_error_deg: errors.iter().copied().fold(0.0, f64::max),
        mean_normal_error_deg: if errors.is_empty() {
            0.0
        } else {
            errors.iter().sum::<f64>() / errors.len() as f64
        },
        contacts_missed: placed.iter().filter(|t| !t.contact && t.collision.is_none()).count(),
        hidden_obstacle_scenes: hidden.len(),
        refused_on_hidden_obstacle: hidden.iter().filter(|t| t.outcome != "placed").count(),
        hidden_obstacle_naive_collisions: hidden
            .iter()
            .filter(|t| t.naive.as_deref() == Some("collided"))
            .count(),
        by_kind,
        trial_results: trials,
    }
}

fn print_table(e: &AutoplaceEvaluation) {
    println!("AutoPlace on {} generated scenes", e.trials);
    println!("  placed   {:>4}  ({:.0} %)", e.placed, 100.0 * e.placed as f64 / e.trials.max(1) as f64);
    println!("  refused  {:>4}", e.refused["total"]);
    for (r, n) in e.refused.iter().filter(|(r, _)| **r != "total") {
        println!("    {r:<10} {n:>4}");
    }
    println!("  collisions in truth            {}", e.collisions);
    println!(
        "  contact angle error (deg)      max {:.1}, mean {:.1}",
        e.max_normal_error_deg, e.mean_normal_error_deg
    );
    println!("  contacts missed                {}", e.contacts_missed);
    println!(
        "  hidden obstacle scenes         {} (AutoPlace refused {}, missing-data-as-free planner collided {})",
        e.hidden_obstacle_scenes, e.refused_on_hidden_obstacle, e.hidden_obstacle_naive_collisions
    );
    println!("  {:<14} {:>6} {:>6} {:>7}", "kind", "trials", "placed", "refused");
    for (k, c) in &e.by_kind {
        println!("  {k:<14} {:>6} {:>6} {:>7}", c.trials, c.placed, c.refused);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// End to end on rendered images: a dropout hides a rock in the arm's path. A planner that
    /// takes the missing data for free space collides with it in truth; AutoPlace refuses.
    /// (Seed 7 is a hidden-rock scene; 320-pixel images keep the test short.)
    #[test]
    fn a_rock_hidden_by_a_dropout_in_the_arms_path_is_refused_end_to_end() {
        let imaging = sensing::Imaging { width: 320, ..sensing::Imaging::default() };
        let t = trial(7, &imaging);
        assert_eq!(t.kind, Kind::HiddenRock);
        assert_eq!(t.naive.as_deref(), Some("collided"), "{t:?}");
        assert_ne!(t.outcome, "placed", "{t:?}");
        assert!(Reason::ALL.iter().any(|r| r.name() == t.outcome), "a named reason: {t:?}");
    }

    #[test]
    fn pooling_counts_every_refusal_under_its_reason() {
        let mk = |seed, kind, outcome: &str, err| Trial {
            seed,
            kind,
            outcome: outcome.into(),
            examined: 1,
            points: BTreeMap::new(),
            target: None,
            normal: None,
            axis: None,
            stop: None,
            collision: None,
            contact: outcome == "placed",
            normal_error_deg: err,
            naive: (kind == Kind::HiddenRock).then(|| "collided".to_string()),
        };
        let e = pool(vec![
            mk(1, Kind::Rock, "placed", Some(4.0)),
            mk(2, Kind::Soil, "placed", Some(2.0)),
            mk(3, Kind::Dropout, "no_data", None),
            mk(4, Kind::HiddenRock, "collision", None),
        ]);
        assert_eq!((e.trials, e.placed, e.refused["total"]), (4, 2, 2));
        assert_eq!(e.refused["no_data"], 1);
        assert_eq!(e.refused["collision"], 1);
        assert_eq!(e.refused.iter().filter(|(k, _)| **k != "total").map(|(_, n)| n).sum::<usize>(), 2);
        assert_eq!(
            (e.hidden_obstacle_scenes, e.refused_on_hidden_obstacle, e.hidden_obstacle_naive_collisions),
            (1, 1, 1)
        );
        assert_eq!(e.max_normal_error_deg, 4.0);
        assert_eq!(e.mean_normal_error_deg, 3.0);
    }
}
