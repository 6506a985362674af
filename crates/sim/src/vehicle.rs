//! The vehicle on 2.5D terrain: wheel contact, 3D attitude, wheel slip and hazards.
//!
//! A skid-steered six-wheel rover at Rocky 7 / SR2 scale (paper 000 section 1, paper 001
//! section 3). The body pose is found from terrain contact: the six wheel contact heights are
//! fitted with a least-squares plane, which gives the height of the body origin (on that plane,
//! under the body centre) and pitch and roll in REP 103 convention (positive pitch = nose down,
//! positive roll = left side up). The body frame origin is on the wheel-contact plane, so sensor
//! heights of [`RoverConfig`] are heights in the body frame.
//!
//! Hazards (what the evaluation counts as a contact with the true terrain):
//! - a step at a wheel: the terrain within one wheel radius ahead of a wheel (in its direction of
//!   motion) rises or drops by more than the belly clearance relative to the wheel's contact;
//! - belly contact: a terrain point under the body, between the wheel rows, higher than the wheel
//!   plane plus the clearance;
//! - tilt: the body tilt exceeds `RoverConfig::max_tilt`.
//!
//! Slip model (an assumption at MER-like magnitudes, not given by the five papers): the
//! longitudinal slip ratio `i = (wheel travel - true travel) / wheel travel` is
//! `base + uphill_gain * max(0, sin(grade)) + downhill_gain * max(0, -sin(grade))` (clamped to
//! `max`), where `grade` is the climb angle of the direction of motion. Descending slips less
//! (smaller gain). On cross-slopes the body also creeps sideways downhill by
//! `lateral_gain * sin(cross-slope angle)` per metre of true travel. Skid-steer turning scrubs:
//! the wheels travel `(1 + turn_scrub)` times the ideal differential-drive distance of the
//! rotation. Encoders count wheel travel, so they over-read true travel by `1 / (1 - i)`.

use rovernav_core::{Point2, Pose2, Pose3, RoverConfig};
use rovernav_terrain::Dem;

/// Wheel radius (m): Rocky 7 class wheels, also the look-ahead window of the step check.
pub const WHEEL_RADIUS: f64 = 0.1;
/// Largest spacing of the belly sample grid (m).
const BELLY_SPACING: f64 = 0.05;
/// Half-width of one wheel (m); the belly spans between the inner faces of the wheel rows.
pub const WHEEL_HALF_WIDTH: f64 = 0.07;

/// Wheel-terrain slip parameters (see the module documentation for the formulas).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SlipModel {
    /// Slip ratio on level ground (dimensionless).
    pub base: f64,
    /// Added slip ratio per unit sine of the uphill grade.
    pub uphill_gain: f64,
    /// Added slip ratio per unit sine of the downhill grade.
    pub downhill_gain: f64,
    /// Upper bound of the slip ratio.
    pub max: f64,
    /// Sideways creep (m per m of travel) per unit sine of the cross-slope.
    pub lateral_gain: f64,
    /// Extra wheel travel of a skid-steer rotation, as a fraction of the ideal.
    pub turn_scrub: f64,
    /// Standard deviation of a random slip offset drawn once per drive command.
    pub per_command_sigma: f64,
}

impl Default for SlipModel {
    fn default() -> Self {
        Self {
            base: 0.02,
            uphill_gain: 1.0,
            downhill_gain: 0.2,
            max: 0.9,
            lateral_gain: 0.1,
            turn_scrub: 0.1,
            per_command_sigma: 0.01,
        }
    }
}

impl SlipModel {
    /// Longitudinal slip ratio for a climb angle of the direction of motion (rad, positive
    /// uphill), before the per-command random offset.
    pub fn slip_ratio(&self, grade: f64) -> f64 {
        let s = grade.sin();
        (self.base + self.uphill_gain * s.max(0.0) + self.downhill_gain * (-s).max(0.0)).clamp(0.0, self.max)
    }
}

/// Where the wheels and the belly are, in the body frame.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleGeometry {
    /// Wheel contact points (body x, y), front to back, left then right.
    pub wheels: Vec<Point2>,
    /// Sample points of the belly between the wheel rows (body x, y).
    pub belly: Vec<Point2>,
    /// Corners of the belly sample grid.
    pub belly_corners: [Point2; 4],
    /// Belly clearance above the wheel plane (m).
    pub clearance: f64,
    /// Tilt limit (rad).
    pub max_tilt: f64,
    /// Distance between the wheel rows (m).
    pub track: f64,
}

impl VehicleGeometry {
    /// Six wheels (front, middle, rear on each side) and a belly grid for a rover.
    pub fn new(rover: &RoverConfig) -> Self {
        let half_len = 0.5 * rover.length;
        let wheel_x = (half_len - WHEEL_RADIUS).max(0.0);
        let half_track = 0.5 * rover.track;
        let wheels = [wheel_x, 0.0, -wheel_x]
            .iter()
            .flat_map(|&x| [Point2::new(x, half_track), Point2::new(x, -half_track)])
            .collect();
        let belly_half_width = (half_track - WHEEL_HALF_WIDTH).max(0.0);
        // Samples at most 5 cm apart so that no rock worth a hazard slips between them.
        let nx = (rover.length / BELLY_SPACING).ceil() as usize + 1;
        let ny = ((2.0 * belly_half_width / BELLY_SPACING).ceil() as usize + 1) | 1;
        let spread = |k: usize, n: usize, half: f64| {
            if n > 1 { -half + 2.0 * half * k as f64 / (n - 1) as f64 } else { 0.0 }
        };
        let mut belly = Vec::with_capacity(nx * ny);
        for ix in 0..nx {
            for iy in 0..ny {
                belly.push(Point2::new(spread(ix, nx, half_len), spread(iy, ny, belly_half_width)));
            }
        }
        let belly_corners = [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
            .map(|(sx, sy)| Point2::new(sx * half_len, sy * belly_half_width));
        Self {
            wheels,
            belly,
            belly_corners,
            clearance: rover.clearance,
            max_tilt: rover.max_tilt,
            track: rover.track,
        }
    }
}

impl VehicleGeometry {
    /// Whether the wheel and belly layouts are symmetric under a half turn, so that headings
    /// `yaw` and `yaw + pi` put the same points on the ground.
    pub fn is_half_turn_symmetric(&self) -> bool {
        let has_mirror = |set: &[Point2]| {
            set.iter().all(|p| set.iter().any(|q| (q.x + p.x).abs() < 1e-12 && (q.y + p.y).abs() < 1e-12))
        };
        has_mirror(&self.wheels) && has_mirror(&self.belly)
    }
}

/// The rover resting on the terrain at a planar pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// The 3D body pose (origin on the wheel plane under the body centre).
    pub pose: Pose3,
    /// Wheel contact world positions (planar), in `VehicleGeometry::wheels` order.
    pub wheel_positions: Vec<Point2>,
    /// Terrain height at each wheel contact (m).
    pub wheel_heights: Vec<f64>,
    /// Wheel-plane coefficients: height = a + b * body_x + c * body_y.
    plane: [f64; 3],
}

impl Contact {
    /// Height of the wheel plane under a body-frame planar point (m).
    pub fn plane_height(&self, p: Point2) -> f64 {
        let [a, b, c] = self.plane;
        a + b * p.x + c * p.y
    }
}

/// Why a pose is unsafe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hazard {
    /// The terrain ahead of a wheel changes height by more than the clearance.
    Step {
        /// Wheel index.
        wheel: usize,
        /// Signed height change (m).
        height: f64,
    },
    /// Terrain under the belly above the wheel plane plus clearance.
    Belly {
        /// Height of the highest belly-point terrain above the wheel plane (m).
        height: f64,
    },
    /// Body tilt beyond the limit.
    Tilt {
        /// Tilt (rad).
        tilt: f64,
    },
}

impl std::fmt::Display for Hazard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Hazard::Step { wheel, height } => {
                write!(f, "hazard: step of {height:.3} m at wheel {wheel}")
            }
            Hazard::Belly { height } => {
                write!(f, "hazard: belly contact, terrain {height:.3} m above the wheel plane")
            }
            Hazard::Tilt { tilt } => {
                write!(f, "hazard: tilt {:.1} deg beyond the limit", tilt.to_degrees())
            }
        }
    }
}

/// The true pose of a rover placed at `start`: settled on the terrain (the rule of
/// `Simulator::new`), or the bare start pose where it cannot settle (off the DEM).
pub fn settled_pose(dem: &Dem, rover: &RoverConfig, start: Pose2) -> Pose3 {
    let start = Pose2::new(start.x, start.y, rovernav_core::wrap_angle(start.yaw));
    settle(dem, &VehicleGeometry::new(rover), start)
        .map_or(Pose3 { x: start.x, y: start.y, yaw: start.yaw, ..Default::default() }, |c| c.pose)
}

/// Settles the rover on the terrain at a planar pose; `None` when a wheel or belly point is
/// outside the DEM or over nodata.
pub fn settle(dem: &Dem, geom: &VehicleGeometry, pose: Pose2) -> Option<Contact> {
    let wheel_positions: Vec<Point2> = geom.wheels.iter().map(|&w| pose.transform(w)).collect();
    let wheel_heights = wheel_positions.iter().map(|p| dem.height(p.x, p.y)).collect::<Option<Vec<f64>>>()?;
    // The DEM's domain is a rectangle, so the belly's corners decide whether the body is over
    // it; nodata holes are found by the wheels and the belly check.
    if geom.belly_corners.iter().any(|&b| {
        let p = pose.transform(b);
        dem.height(p.x, p.y).is_none()
    }) {
        return None;
    }
    let plane = fit_plane(&geom.wheels, &wheel_heights)?;
    let [a, b, c] = plane;
    let pitch = (-b).atan();
    let roll = (c / (1.0 + b * b + c * c).sqrt()).asin();
    Some(Contact {
        pose: Pose3 { x: pose.x, y: pose.y, z: a, roll, pitch, yaw: pose.yaw },
        wheel_positions,
        wheel_heights,
        plane,
    })
}

/// Least-squares plane `z = a + b x + c y` through body-frame points and heights.
pub(crate) fn fit_plane(points: &[Point2], z: &[f64]) -> Option<[f64; 3]> {
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(sx, sy), p| (sx + p.x / n, sy + p.y / n));
    let mz = z.iter().sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, &h) in points.iter().zip(z) {
        let (dx, dy, dz) = (p.x - mx, p.y - my, h - mz);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
        sxz += dx * dz;
        syz += dy * dz;
    }
    let det = sxx * syy - sxy * sxy;
    if det.abs() < 1e-12 {
        return None;
    }
    let b = (sxz * syy - syz * sxy) / det;
    let c = (syz * sxx - sxz * sxy) / det;
    Some([mz - b * mx - c * my, b, c])
}

/// Belly and tilt hazards of a settled pose.
pub fn body_hazard(dem: &Dem, geom: &VehicleGeometry, contact: &Contact) -> Option<Hazard> {
    let tilt = contact.pose.tilt();
    if tilt > geom.max_tilt {
        return Some(Hazard::Tilt { tilt });
    }
    let pose2 = contact.pose.pose2();
    let [a, b, c] = contact.plane;
    let mut worst = f64::NEG_INFINITY;
    for &p in &geom.belly {
        let w = pose2.transform(p);
        if let Some(ground) = dem.height(w.x, w.y) {
            worst = worst.max(ground - (a + b * p.x + c * p.y));
        }
    }
    (worst > geom.clearance).then_some(Hazard::Belly { height: worst })
}

/// Step hazard at a wheel: terrain within one wheel radius along `direction` (unit, world)
/// differs from the wheel's contact height by more than the clearance.
pub fn wheel_step(
    dem: &Dem,
    geom: &VehicleGeometry,
    contact: &Contact,
    wheel: usize,
    direction: Point2,
) -> Option<Hazard> {
    let p = contact.wheel_positions[wheel];
    let h0 = contact.wheel_heights[wheel];
    const SAMPLES: usize = 4;
    for k in 1..=SAMPLES {
        let q = p.add(direction.scale(WHEEL_RADIUS * k as f64 / SAMPLES as f64));
        if let Some(h) = dem.height(q.x, q.y)
            && (h - h0).abs() > geom.clearance
        {
            return Some(Hazard::Step { wheel, height: h - h0 });
        }
    }
    None
}

/// Step hazards for a motion from `before` to `after`: each wheel looks ahead along its own
/// direction of travel.
pub fn motion_step_hazard(
    dem: &Dem,
    geom: &VehicleGeometry,
    before: &Contact,
    after: &Contact,
) -> Option<Hazard> {
    (0..geom.wheels.len()).find_map(|i| {
        let d = after.wheel_positions[i].sub(before.wheel_positions[i]);
        let n = d.norm();
        (n > 1e-12).then(|| wheel_step(dem, geom, after, i, d.scale(1.0 / n))).flatten()
    })
}

/// Any hazard at a pose for motion in any direction: body hazards, or a step within one wheel
/// radius of a wheel in any of eight directions.
pub fn static_hazard(dem: &Dem, geom: &VehicleGeometry, contact: &Contact) -> Option<Hazard> {
    body_hazard(dem, geom, contact).or_else(|| {
        (0..geom.wheels.len()).find_map(|i| {
            (0..8).find_map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                wheel_step(dem, geom, contact, i, Point2::new(a.cos(), a.sin()))
            })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Grid2, GridGeometry};

    fn plane_dem(gx: f64, gy: f64) -> Dem {
        let geometry = GridGeometry { cols: 80, rows: 80, resolution: 0.05, origin_x: 0.0, origin_y: 0.0 };
        let mut grid = Grid2::filled(geometry, 0.0f32);
        for r in 0..80 {
            for c in 0..80 {
                let (x, y) = geometry.center(c, r);
                *grid.get_mut(c, r) = (gx * x + gy * y) as f32;
            }
        }
        Dem::from_grid(grid)
    }

    #[test]
    fn climbing_a_slope_pitches_the_nose_up_and_sideslope_rolls() {
        let geom = VehicleGeometry::new(&RoverConfig::default());
        // Terrain rising to the east by tan(10 deg); rover facing east: nose up = negative pitch.
        let g = 10f64.to_radians().tan();
        let dem = plane_dem(g, 0.0);
        let c = settle(&dem, &geom, Pose2::new(2.0, 2.0, 0.0)).expect("on terrain");
        assert!((c.pose.pitch + 10f64.to_radians()).abs() < 1e-4, "{}", c.pose.pitch);
        assert!(c.pose.roll.abs() < 1e-6);
        assert!((c.pose.z - 2.0 * g).abs() < 1e-4);
        // Facing north on the same slope: east (uphill) is to the right, so the left side is
        // down: negative roll of 10 deg.
        let c = settle(&dem, &geom, Pose2::new(2.0, 2.0, std::f64::consts::FRAC_PI_2)).expect("on");
        assert!((c.pose.roll + 10f64.to_radians()).abs() < 1e-4, "{}", c.pose.roll);
        assert!(c.pose.pitch.abs() < 1e-6);
        // The body z axis must be the terrain normal (-g, 0, 1) / |.|.
        let o = c.pose.transform([0.0; 3]);
        let up = c.pose.transform([0.0, 0.0, 1.0]);
        let nn = (g * g + 1.0).sqrt();
        let normal = [-g / nn, 0.0, 1.0 / nn];
        for k in 0..3 {
            assert!((up[k] - o[k] - normal[k]).abs() < 1e-4, "axis {k}");
        }
    }

    #[test]
    fn slip_ratio_follows_the_documented_formula() {
        let m =
            SlipModel { base: 0.02, uphill_gain: 1.0, downhill_gain: 0.2, max: 0.9, ..Default::default() };
        let up = 10f64.to_radians();
        assert!((m.slip_ratio(up) - (0.02 + up.sin())).abs() < 1e-12);
        assert!((m.slip_ratio(-up) - (0.02 + 0.2 * up.sin())).abs() < 1e-12);
        assert!((m.slip_ratio(1.5) - 0.9).abs() < 1e-12);
    }

    #[test]
    fn leaving_the_dem_has_no_contact() {
        let geom = VehicleGeometry::new(&RoverConfig::default());
        let dem = plane_dem(0.0, 0.0);
        assert!(settle(&dem, &geom, Pose2::new(0.2, 2.0, 0.0)).is_none());
        assert!(settle(&dem, &geom, Pose2::new(1.0, 2.0, 0.0)).is_some());
    }
}
