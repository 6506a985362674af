//! Scenario (paper 003 section 4.2: "treating this lack of data as a lack of obstacles could be
//! mission-ending"): a stereo dropout hides a rock standing in the arm's path to a visible
//! target. A planner that takes the missing data for free space plans straight through the rock;
//! AutoPlace refuses, for collision, and moves nothing. With the rock and the dropout gone, the
//! same target is placed.
//!
//! The views are synthetic and exact: level ground sampled every centimetre, seen by a
//! Hazcam-like pair and a Navcam-like pair; a point is in a camera's view unless the rock hides
//! it from that camera or it lies in the dropout.

use nalgebra::Vector3;
use rovernav_core::RoverConfig;
use rovernav_manipulation::feasibility::interpolate;
use rovernav_manipulation::{
    Arm, AutoPlaceParams, Outcome, Reason, View, autoplace, place_with, terrain_model,
};

type V3 = Vector3<f64>;

/// A vertical cylinder standing on the ground.
#[derive(Clone, Copy)]
struct Rock {
    centre: [f64; 2],
    radius: f64,
    height: f64,
}

impl Rock {
    /// Whether the segment a-b passes through the cylinder (sampled every 2 mm).
    fn blocks(&self, a: &V3, b: &V3) -> bool {
        let n = ((b - a).norm() / 0.002).ceil() as usize;
        (0..=n).any(|i| {
            let p = a + (b - a) * (i as f64 / n as f64);
            (p.x - self.centre[0]).hypot(p.y - self.centre[1]) < self.radius && p.z < self.height
        })
    }

    /// Whether a point lies inside.
    fn contains(&self, p: &V3, margin: f64) -> bool {
        (p.x - self.centre[0]).hypot(p.y - self.centre[1]) < self.radius + margin
            && p.z < self.height + margin
    }
}

/// One view per camera: the ground points (and the rock's top and sides) it sees.
fn views(rock: Option<Rock>, hole: Option<([f64; 2], f64)>) -> Vec<(Vec<V3>, Vec<[f32; 3]>)> {
    let cameras = [
        V3::new(0.43, 0.05, 0.35),
        V3::new(0.43, -0.05, 0.35),
        V3::new(0.0, 0.1, 1.2),
        V3::new(0.0, -0.1, 1.2),
    ];
    let mut surface = Vec::new();
    for i in 0..170 {
        for j in 0..150 {
            let (x, y) = (0.40 + i as f64 * 0.01, -0.75 + j as f64 * 0.01);
            let z = match rock {
                Some(r) if (x - r.centre[0]).hypot(y - r.centre[1]) < r.radius => r.height,
                _ => 0.0,
            };
            surface.push(V3::new(x, y, z));
        }
    }
    cameras
        .iter()
        .map(|c| {
            let seen = surface
                .iter()
                .filter(|p| hole.is_none_or(|(h, r)| (p.x - h[0]).hypot(p.y - h[1]) >= r))
                .filter(|p| rock.is_none_or(|r| !r.blocks(c, &(*p + (c - *p).normalize() * 0.003))))
                .map(|p| [p.x as f32, p.y as f32, p.z as f32])
                .collect();
            (vec![*c], seen)
        })
        .collect()
}

fn as_views(v: &[(Vec<V3>, Vec<[f32; 3]>)]) -> Vec<View<'_>> {
    v.iter().map(|(c, p)| View { cameras: c, points: p }).collect()
}

#[test]
fn a_dropout_hiding_a_rock_in_the_arms_path_makes_autoplace_refuse() {
    let arm = Arm::new(&RoverConfig::default());
    let params = AutoPlaceParams::default();
    let target = V3::new(1.0, -0.05, 0.0);

    // The clear scene: placed.
    let clear = views(None, None);
    let (outcome, _) = autoplace(&arm, &as_views(&clear), &clear[0].1, None, &target, &params);
    let Outcome::Placed { plan, .. } = outcome else { panic!("clear scene refused: {outcome:?}") };

    // The rock goes under the lowest point of that path more than 15 cm from the target,
    // rising 5 cm above it; the dropout covers it.
    let mut low = [0.0, 0.0, f64::INFINITY];
    for w in plan.via.windows(2) {
        for q in interpolate(&arm, &w[0], &w[1], 0.01) {
            for c in arm.capsules(&q) {
                for p in c.cover(0.01) {
                    if (p.xy() - target.xy()).norm() > 0.15 && p.x > 0.62 && p.z - c.radius < low[2] {
                        low = [p.x, p.y, p.z - c.radius];
                    }
                }
            }
        }
    }
    assert!(low[2] < 0.5, "the path passes low somewhere: {low:?}");
    let rock = Rock { centre: [low[0], low[1]], radius: 0.05, height: low[2] + 0.05 };
    let hidden = views(Some(rock), Some((rock.centre, 0.11)));
    let hidden_views = as_views(&hidden);

    // Missing data taken as free space: a path through the rock.
    let naive_tree = terrain_model(&arm, &hidden_views, &params.octree).unknown_as_free();
    let naive = place_with(&arm, &naive_tree, &hidden[0].1, None, &target, &params);
    let Outcome::Placed { plan: naive_plan, .. } = naive else {
        panic!("the naive planner refused: {naive:?}")
    };
    let through_rock = naive_plan.via.windows(2).any(|w| {
        interpolate(&arm, &w[0], &w[1], 0.01)
            .iter()
            .any(|q| arm.capsules(q).iter().any(|c| c.cover(0.005).any(|p| rock.contains(&p, c.radius))))
    });
    assert!(through_rock, "the naive path meets the hidden rock");

    // AutoPlace: refused for collision, nothing moves.
    let (outcome, tree) = autoplace(&arm, &hidden_views, &hidden[0].1, None, &target, &params);
    assert_eq!(outcome.reason(), Some(Reason::Collision), "{outcome:?}");
    // The rock's volume is not free in the model.
    let inside = V3::new(rock.centre[0], rock.centre[1], 0.5 * rock.height);
    assert_ne!(tree.at(&inside), rovernav_manipulation::Cell::Free);
}
