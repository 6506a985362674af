//! Simulated sensors and their noise models.
//!
//! - Range imaging (paper 000 section 2: a mast stereo pair with a 30-45 deg field of view
//!   imaging a wedge out to ~5 m, fore and aft body pairs with 80-100 deg out to ~1.5 m; paper
//!   004 section 3.1/3.3: a nodding Hokuyo LIDAR covering ~6 m ahead): a grid of rays cast
//!   against the true height field with occlusion ([`crate::raycast`]). Each ray's range gets a
//!   Gaussian error along the ray with standard deviation `sigma_constant + sigma_quadratic *
//!   r^2` (stereo depth error grows with the square of range: `sigma_z = z^2 sigma_d / (f b)`;
//!   a small-baseline rover pair with ~300 px focal length, 0.1 m baseline and 0.3 px matching
//!   error gives `sigma_quadratic` ~ 0.004 /m for the mast, i.e. 4 mm at 1 m and 10 cm at 5 m) and drops out
//!   with a fixed probability (failed stereo matches, missed LIDAR returns). Points are reported
//!   in the body frame at capture.
//! - Proximity (paper 001 section 3 and 5.2): ten forward Sharp threshold detectors in left (0..3),
//!   middle (3..7, set back on the body so they trigger closer) and right (7..10) clusters,
//!   angled down so that level ground returns beyond the threshold. A sensor triggers when its
//!   (noisy) range is below `RoverConfig::proximity_range` (an obstacle) or when the expected
//!   ground return is missing (the ground drops away: a hole or cliff). The paper gives no mount
//!   or aim; it says the sensors tell "whether or not there was an obstacle in the robot's way"
//!   and that the rover makes its way *over* or around hazards. So each beam is aimed to reach the
//!   trigger range at 0.8 of the rover's belly clearance above the wheel plane
//!   (`ProximityModel::aim_fraction`): a rock the rover can drive over passes under the beam, one
//!   it cannot is seen; the 20 % margin covers range noise and the body's pitch over the terrain
//!   (aimed at the full clearance, SR2 touched rocks just over it in 22 of 100 yards). Departure
//!   from an earlier model here, a fixed 16 deg depression from a 0.25 m mount that triggered on
//!   anything taller than ~0.08 m at 0.58 m ahead, under half the 0.18 m clearance: at Pathfinder
//!   rock densities SR2 turned on the spot until it gave up
//!   (`docs/results/2026-11-28-sr2-proximity.md`). The mount (0.38 m, near the top of SR2's
//!   40 cm envelope; assumed) keeps the level-ground return plus the drop margin within the
//!   GP2Y0A02YK's 1.5 m range with that aim.
//! - Proprioception (paper 001 section 3: compass at +-0.5 deg and encoders; paper 004 section
//!   3.1-3.2: fibre-optic azimuth gyro, absolute inclinometer, odometry): sampled at 10 Hz while
//!   moving and once at rest after each command.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rovernav_core::{
    CameraKind, ImuSample, PointCloud, Pose3, ProximityReading, RoverConfig, Wedge, wrap_angle,
};
use rovernav_terrain::Dem;

use crate::raycast::HeightField;
use crate::stereo_range::{RangeSource, StereoImaging};
use crate::vehicle::SlipModel;

/// Parameters of one range imager: ray grid, coverage and noise.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RangeImagerModel {
    /// Rays across the image (columns).
    pub cols: usize,
    /// Rays down the image (rows).
    pub rows: usize,
    /// Ground range (m, from the sensor, level ground) imaged by the bottom row.
    pub near_range: f64,
    /// Elevation (rad) of the top row above the ray that meets level ground at the far range.
    pub up_margin: f64,
    /// Range-independent part of the range error standard deviation (m).
    pub sigma_constant: f64,
    /// Range error standard deviation per squared metre of range (1/m).
    pub sigma_quadratic: f64,
    /// Probability that a ray returns nothing.
    pub dropout: f64,
    /// Time one image takes, including pointing (s).
    pub capture_time: f64,
}

impl RangeImagerModel {
    /// Standard deviation of the range error at range `r` (m).
    pub fn sigma(&self, r: f64) -> f64 {
        self.sigma_constant + self.sigma_quadratic * r * r
    }
}

/// Nodding LIDAR mounting and coverage (paper 004 section 3.1: Hokuyo on a tilt unit).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct LidarModel {
    /// Ray grid and noise.
    pub imager: RangeImagerModel,
    /// Horizontal field of view (rad, full angle).
    pub fov: f64,
    /// Maximum planar range (m).
    pub range: f64,
    /// Mounting height above the wheel plane (m).
    pub height: f64,
    /// Mounting position along the body x axis (m).
    pub x_offset: f64,
}

/// The ten SR2 proximity threshold sensors (paper 001).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ProximityModel {
    /// Mounting height above the wheel plane (m).
    pub height: f64,
    /// Bearing of each beam in the body frame (rad), index 0 leftmost.
    pub bearings: [f64; 10],
    /// How far each sensor sits behind the front of the body (m); the middle cluster is set back.
    pub setback: [f64; 10],
    /// Height above the wheel plane at which each beam reaches the trigger range, as a fraction
    /// of the rover's belly clearance: below 1 so that a rock just taller than the clearance is
    /// seen despite range noise and the body's pitch over the terrain.
    pub aim_fraction: f64,
    /// A return farther than the expected ground return by more than this (or none) means the
    /// ground dropped away (m).
    pub drop_margin: f64,
    /// Range noise standard deviation (m).
    pub range_sigma: f64,
}

/// Every noise and mounting parameter of the simulated platform (serialized without the
/// renderer settings `stereo` and `navcam`, which read back as their defaults).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SensorModel {
    /// Mast stereo pair grid and noise (geometry from `RoverConfig`).
    pub mast: RangeImagerModel,
    /// Mast stereo pair at full resolution (`SenseRequest::MastFine`, for terrain matching).
    pub mast_fine: RangeImagerModel,
    /// Body stereo pairs grid and noise (geometry from `RoverConfig`).
    pub body: RangeImagerModel,
    /// Nodding LIDAR.
    pub lidar: LidarModel,
    /// Proximity sensors.
    pub proximity: ProximityModel,
    /// Compass heading noise (rad, 1 sigma); SR2's compass: +-0.5 deg (paper 001 section 3).
    pub compass_sigma: f64,
    /// Inclinometer roll and pitch noise (rad, 1 sigma); 0.2 deg (AMD900-class, paper 004).
    pub inclinometer_sigma: f64,
    /// Sun sensor heading noise (rad, 1 sigma); ~1 deg.
    pub sun_sigma: f64,
    /// Whether the sun is visible to the sun sensor.
    pub sun_visible: bool,
    /// Gyro turn-on bias (rad/s, 1 sigma), drawn once per run; 10 deg/h (fibre-optic class).
    pub gyro_bias_sigma: f64,
    /// Gyro bias random walk (rad/s per sqrt(s)); 1 deg/h per sqrt(h).
    pub gyro_bias_walk: f64,
    /// Gyro white rate noise density (rad/s per sqrt(Hz)); 4 deg/h/sqrt(Hz) (KVH DSP-3000 class,
    /// paper 004 section 3.1), i.e. an angle random walk of 0.067 deg/sqrt(h).
    pub gyro_noise_density: f64,
    /// Proprioceptive sample rate while moving (Hz); 10 Hz as MRPTA's components (paper 004).
    pub sample_rate: f64,
    /// Samples at rest produced by `Simulator::initial_frame`.
    pub initial_rest_samples: usize,
    /// Wheel-terrain slip (the encoder error model).
    pub slip: SlipModel,
    /// Where the stereo pairs' range comes from (the LIDAR is always ray cast).
    pub range_source: RangeSource,
    /// How the `stereo` range source images and correlates (also the sun and dust of every image).
    #[serde(skip)]
    pub stereo: StereoImaging,
    /// How the Navcam pair images on request.
    #[serde(skip)]
    pub navcam: crate::navcam::NavcamImaging,
    /// The solar panel, battery and loads (the mission's `[power]`).
    #[serde(skip)]
    pub power: crate::power::PowerConfig,
    /// A lander watching the rover's in-place turns (the mission's `[lander]`; none by default).
    #[serde(skip)]
    pub lander: Option<crate::lander_station::LanderStation>,
}

impl Default for SensorModel {
    fn default() -> Self {
        let deg = |d: f64| d.to_radians();
        let deg_per_hour = |d: f64| deg(d) / 3600.0;
        Self {
            // Paper 000 section 2: the mast wedge covers ~1-5 m (the mast cannot see obstacles
            // within ~1 m of the vehicle); ~2400 rays is a subsampled navigation image.
            mast: RangeImagerModel {
                cols: 60,
                rows: 40,
                near_range: 1.0,
                up_margin: deg(5.0),
                sigma_constant: 0.0,
                // sigma_r = r^2 * sigma_d / (b f): a ~0.2 m baseline, ~2 mrad pixels and 0.4 px
                // disparity error give 0.004 r^2, i.e. 4 mm at 1 m and 10 cm at 5 m.
                sigma_quadratic: 0.004,
                // Unmatched stereo pixels (assumed).
                dropout: 0.05,
                // Pointing the mast, imaging and stereo on a 1990s flight-class CPU (assumed).
                capture_time: 10.0,
            },
            // The same cameras' finer image for terrain matching: 4x the rays in each direction
            // (the navigation image is a subsample), the same range noise per metre (so the
            // localisation evaluation keeps the default stereo noise), twice the capture time.
            mast_fine: RangeImagerModel {
                cols: 240,
                rows: 160,
                near_range: 1.0,
                up_margin: deg(5.0),
                sigma_constant: 0.0,
                sigma_quadratic: 0.004,
                dropout: 0.05,
                capture_time: 20.0,
            },
            // Paper 000 section 2.2: body pairs see roughly 0-1.5 m from the vehicle.
            body: RangeImagerModel {
                cols: 60,
                rows: 40,
                near_range: 0.3,
                up_margin: deg(5.0),
                sigma_constant: 0.0,
                // Wider field of view and shorter baseline than the mast pair: 2.5x the mast's
                // coefficient (2 cm at 1.5 m).
                sigma_quadratic: 0.01,
                dropout: 0.05,
                capture_time: 5.0,
            },
            lidar: LidarModel {
                imager: RangeImagerModel {
                    cols: 121,
                    rows: 40,
                    near_range: 1.0,
                    up_margin: deg(5.0),
                    // Hokuyo-class time-of-flight: 1-2 cm, independent of range.
                    sigma_constant: 0.015,
                    sigma_quadratic: 0.0,
                    // Missed returns on dark or specular surfaces (assumed).
                    dropout: 0.02,
                    // One nod of the tilt unit (assumed).
                    capture_time: 8.0,
                },
                // Paper 004 section 3.3: coverage to a ~6 m horizon ahead; mount assumed.
                fov: deg(120.0),
                range: 8.0,
                height: 0.6,
                x_offset: 0.3,
            },
            // Paper 001 sections 3 and 5.2: ten Sharp GP2Y0A02YK detectors, three clusters over
            // about +-45 deg, the middle cluster set back; the 15 Hz Sharp sampling is noisy.
            // Mount assumed: see the module doc (beams aimed under the belly clearance).
            proximity: ProximityModel {
                height: 0.38,
                bearings: [45.0, 35.0, 25.0, 15.0, 5.0, -5.0, -15.0, -25.0, -35.0, -45.0].map(deg),
                setback: [0.0, 0.0, 0.0, 0.1, 0.1, 0.1, 0.1, 0.0, 0.0, 0.0],
                aim_fraction: 0.8,
                drop_margin: 0.35,
                range_sigma: 0.02,
            },
            compass_sigma: deg(0.5),
            inclinometer_sigma: deg(0.2),
            sun_sigma: deg(1.0),
            sun_visible: true,
            gyro_bias_sigma: deg_per_hour(10.0),
            gyro_bias_walk: deg_per_hour(1.0) / 60.0,
            gyro_noise_density: deg_per_hour(4.0),
            sample_rate: 10.0,
            initial_rest_samples: 20,
            slip: SlipModel::default(),
            range_source: RangeSource::default(),
            stereo: StereoImaging::default(),
            navcam: crate::navcam::NavcamImaging::default(),
            power: crate::power::PowerConfig::default(),
            lander: None,
        }
    }
}

/// A zero-mean Gaussian draw.
pub(crate) fn gaussian(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    let z: f64 = rng.sample(StandardNormal);
    z * sigma
}

/// Mounting and coverage of one range image.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeGeometry {
    /// Which sensor.
    pub camera: CameraKind,
    /// Sensor origin in the body frame (m).
    pub origin: [f64; 3],
    /// Bearing of the image centre in the body frame (rad).
    pub bearing: f64,
    /// Horizontal field of view (rad, full angle).
    pub fov: f64,
    /// Elevation of the bottom row (rad, negative below the horizon).
    pub elevation_min: f64,
    /// Elevation of the top row (rad).
    pub elevation_max: f64,
    /// Maximum planar range from the sensor (m).
    pub max_range: f64,
}

impl RangeGeometry {
    /// The geometry of an imager pointed at `bearing` from `origin`, covering ground ranges
    /// `near..far` on level ground.
    pub fn pointed(
        camera: CameraKind,
        origin: [f64; 3],
        bearing: f64,
        fov: f64,
        far: f64,
        imager: &RangeImagerModel,
    ) -> Self {
        let h = origin[2].max(1e-3);
        Self {
            camera,
            origin,
            bearing,
            fov,
            elevation_min: -(h / imager.near_range.max(1e-3)).atan(),
            elevation_max: -(h / far.max(1e-3)).atan() + imager.up_margin,
            max_range: far,
        }
    }

    /// The mast pair panned to `pan`.
    pub fn mast(rover: &RoverConfig, model: &SensorModel, pan: f64) -> Self {
        Self::mast_imaging(rover, &model.mast, pan)
    }

    /// The mast pair panned to `pan`, imaging at full resolution.
    pub fn mast_fine(rover: &RoverConfig, model: &SensorModel, pan: f64) -> Self {
        Self::mast_imaging(rover, &model.mast_fine, pan)
    }

    fn mast_imaging(rover: &RoverConfig, imager: &RangeImagerModel, pan: f64) -> Self {
        Self::pointed(
            CameraKind::Mast,
            [0.0, 0.0, rover.mast_height],
            pan,
            rover.mast_fov,
            rover.mast_range,
            imager,
        )
    }

    /// A body pair, front or rear.
    pub fn body(rover: &RoverConfig, model: &SensorModel, front: bool) -> Self {
        let (kind, x, bearing) = if front {
            (CameraKind::BodyFront, 0.5 * rover.length, 0.0)
        } else {
            (CameraKind::BodyRear, -0.5 * rover.length, std::f64::consts::PI)
        };
        Self::pointed(
            kind,
            [x, 0.0, rover.body_camera_height],
            bearing,
            rover.body_fov,
            rover.body_range,
            &model.body,
        )
    }

    /// The nodding LIDAR swept at `pan`.
    pub fn lidar(model: &SensorModel, pan: f64) -> Self {
        let l = &model.lidar;
        Self::pointed(CameraKind::Lidar, [l.x_offset, 0.0, l.height], pan, l.fov, l.range, &l.imager)
    }

    /// The body-frame wedge covered: ranges measured from the body origin along the bearing.
    pub fn wedge(&self, imager: &RangeImagerModel) -> Wedge {
        let along = self.origin[0] * self.bearing.cos() + self.origin[1] * self.bearing.sin();
        Wedge {
            bearing: wrap_angle(self.bearing),
            half_angle: 0.5 * self.fov,
            min_range: (along + imager.near_range).max(0.0),
            max_range: along + self.max_range,
        }
    }

    /// Unit ray direction (body frame) of image cell (col, row).
    pub fn ray(&self, imager: &RangeImagerModel, col: usize, row: usize) -> [f64; 3] {
        let az = self.bearing + self.fov * ((col as f64 + 0.5) / imager.cols as f64 - 0.5);
        let el = self.elevation_min
            + (self.elevation_max - self.elevation_min) * (row as f64 + 0.5) / imager.rows as f64;
        let (se, ce) = el.sin_cos();
        let (sa, ca) = az.sin_cos();
        [ce * ca, ce * sa, se]
    }
}

/// Rotates a body-frame vector into the world frame.
fn rotate(pose: &Pose3, v: [f64; 3]) -> [f64; 3] {
    let r = pose.rotation();
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2],
    ]
}

/// Takes one range image from the true pose: rays with occlusion, range noise and dropouts.
pub fn capture(
    dem: &Dem,
    field: &HeightField,
    truth: &Pose3,
    geometry: &RangeGeometry,
    imager: &RangeImagerModel,
    rng: &mut ChaCha8Rng,
) -> PointCloud {
    let origin_world = truth.transform(geometry.origin);
    let mut points = Vec::with_capacity(imager.cols * imager.rows);
    for row in 0..imager.rows {
        for col in 0..imager.cols {
            let d = geometry.ray(imager, col, row);
            let horizontal = d[0].hypot(d[1]).max(1e-6);
            let max_t = geometry.max_range / horizontal;
            // Draw the noise for every ray so the random stream does not depend on the scene.
            let dropped = rng.random::<f64>() < imager.dropout;
            let unit_noise: f64 = rng.sample(StandardNormal);
            let Some(hit) = field.cast(dem, origin_world, rotate(truth, d), max_t) else {
                continue;
            };
            let r = hit.range + unit_noise * imager.sigma(hit.range);
            if dropped || r <= 0.0 {
                continue;
            }
            let o = geometry.origin;
            points.push([(o[0] + d[0] * r) as f32, (o[1] + d[1] * r) as f32, (o[2] + d[2] * r) as f32]);
        }
    }
    PointCloud { camera: geometry.camera, origin: geometry.origin, wedge: geometry.wedge(imager), points }
}

/// Reads the ten proximity sensors at the true pose.
pub fn proximity(
    dem: &Dem,
    field: &HeightField,
    truth: &Pose3,
    rover: &RoverConfig,
    model: &ProximityModel,
    rng: &mut ChaCha8Rng,
) -> ProximityReading {
    let threshold = rover.proximity_range.max(1e-3);
    let depression = beam_depression(model.height, model.aim_fraction * rover.clearance, threshold);
    let ground_return = model.height / depression.sin();
    let listen = ground_return + model.drop_margin;
    let (sd, cd) = depression.sin_cos();
    let half_width = 0.5 * rover.width;
    let mut reading = ProximityReading::default();
    for (i, raw) in reading.raw.iter_mut().enumerate() {
        let y = half_width * (1.0 - 2.0 * i as f64 / 9.0);
        let origin = [0.5 * rover.length - model.setback[i], y, model.height];
        let (sb, cb) = model.bearings[i].sin_cos();
        let dir = [cd * cb, cd * sb, -sd];
        let noise = gaussian(rng, model.range_sigma);
        let hit = field.cast(dem, truth.transform(origin), rotate(truth, dir), listen);
        *raw = match hit {
            Some(h) => {
                let r = h.range + noise;
                r < threshold || r > listen
            }
            None => true,
        };
    }
    reading
}

/// Depression (rad) of a beam from `height` that reaches `threshold` slant range `aim` above the
/// wheel plane; an aim above half the mount is lowered to half of it (a beam near level would see
/// no ground, so every sensor would report a drop).
fn beam_depression(height: f64, aim: f64, threshold: f64) -> f64 {
    let height = height.max(1e-3);
    let aim = aim.clamp(0.0, 0.5 * height);
    ((height - aim) / threshold.max(1e-3)).clamp(1e-3, 1.0).asin()
}

/// The gyro's slowly varying bias and the proprioceptive noise stream.
#[derive(Clone, Debug)]
pub struct Proprioception {
    /// Current gyro bias (rad/s).
    bias: f64,
    rng: ChaCha8Rng,
}

impl Proprioception {
    /// Draws the turn-on bias.
    pub fn new(model: &SensorModel, mut rng: ChaCha8Rng) -> Self {
        let bias = gaussian(&mut rng, model.gyro_bias_sigma);
        Self { bias, rng }
    }

    /// Adds `delta` (rad/s) to the bias: a bias jump, as after a shock or a power glitch.
    pub fn jump_bias(&mut self, delta: f64) {
        self.bias += delta;
    }

    /// Lets the bias random-walk over `dt` seconds.
    pub fn elapse(&mut self, model: &SensorModel, dt: f64) {
        if dt > 0.0 {
            self.bias += gaussian(&mut self.rng, model.gyro_bias_walk * dt.sqrt());
        }
    }

    /// One sample of the attitude sensors at the true pose, with the true yaw rate averaged
    /// over the last sample period.
    pub fn sample(
        &mut self,
        model: &SensorModel,
        t: f64,
        truth: &Pose3,
        yaw_rate: f64,
        compass_failed: bool,
    ) -> ImuSample {
        let period = 1.0 / model.sample_rate.max(1e-3);
        let rng = &mut self.rng;
        let gyro_z = yaw_rate + self.bias + gaussian(rng, model.gyro_noise_density / period.sqrt());
        let compass = wrap_angle(truth.yaw + gaussian(rng, model.compass_sigma));
        let incl_roll = truth.roll + gaussian(rng, model.inclinometer_sigma);
        let incl_pitch = truth.pitch + gaussian(rng, model.inclinometer_sigma);
        let sun = wrap_angle(truth.yaw + gaussian(rng, model.sun_sigma));
        ImuSample {
            t,
            gyro_z,
            incl_roll,
            incl_pitch,
            compass_yaw: if compass_failed { f64::NAN } else { compass },
            sun_yaw: model.sun_visible.then_some(sun),
        }
    }

    /// The current gyro bias (rad/s), for tests and diagnostics.
    pub fn bias(&self) -> f64 {
        self.bias
    }
}
