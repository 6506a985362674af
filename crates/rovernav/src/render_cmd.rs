//! `rovernav render [MISSION.toml] --camera NAME --out DIR`: what one of the rover's cameras
//! sees of the mission's true world at the start pose, written as `DIR/NAME.png` (and the stereo
//! partner's `DIR/PARTNER.png` for a camera of a pair).

use anyhow::Context;
use rovernav_core::Pose3;
use rovernav_executive::Mission;
use rovernav_harness::build_world;
use rovernav_sim::render::{Atmosphere, CAMERA_NAMES, RenderSettings, Rig, Scene, Sun, render};
use std::path::{Path, PathBuf};

/// Options of `rovernav render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Mission file (TOML); omit for the built-in default mission.
    mission: Option<PathBuf>,
    /// Camera: navcam_left, navcam_right, hazcam_front_left, hazcam_front_right,
    /// hazcam_rear_left, hazcam_rear_right, lander, descent.
    #[arg(long)]
    camera: String,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Override the mission's seed (the terrain and the image noise).
    #[arg(long)]
    seed: Option<u64>,
    /// Navcam head pan (deg, positive to the left of the rover's heading).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pan: f64,
    /// Navcam head tilt (deg, positive up).
    #[arg(long, default_value_t = -15.0, allow_hyphen_values = true)]
    tilt: f64,
    /// Local true solar time, HH:MM.
    #[arg(long, default_value = "14:00")]
    time: String,
    /// Site latitude (deg; default Gusev crater, Spirit's site).
    #[arg(long, default_value_t = -14.6, allow_hyphen_values = true)]
    latitude: f64,
    /// Season: areocentric solar longitude Ls (deg).
    #[arg(long, default_value_t = 0.0)]
    ls: f64,
    /// Dust optical depth.
    #[arg(long, default_value_t = 0.5)]
    tau: f64,
    /// Image size (pixels, square).
    #[arg(long, default_value_t = 1024)]
    size: usize,
    /// Sub-pixel rays per side (1 or more; 2 = 2x2 anti-aliasing, 4x the time).
    #[arg(long, default_value_t = 1)]
    supersample: usize,
    /// JPEG-like compression quality (1..100); uncompressed when omitted.
    #[arg(long)]
    jpeg_quality: Option<u8>,
    /// Write 16-bit PNGs holding the 12-bit DN instead of 8-bit ones for people.
    #[arg(long)]
    raw16: bool,
}

/// Runs `rovernav render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let (mut mission, origin) = match &args.mission {
        Some(path) => (Mission::from_file(path)?, path.display().to_string()),
        None => (Mission::default_mission(), "built-in default mission".to_string()),
    };
    if let Some(seed) = args.seed {
        mission.seed = seed;
    }
    let hours = parse_time(&args.time)?;
    if !(args.tau.is_finite() && (0.0..=10.0).contains(&args.tau)) {
        anyhow::bail!("--tau {}: must be in [0, 10]", args.tau);
    }
    if !args.latitude.is_finite() || args.latitude.abs() > 90.0 {
        anyhow::bail!("--latitude {}: must be in [-90, 90] deg", args.latitude);
    }
    if !(16..=8192).contains(&args.size) {
        anyhow::bail!("--size {}: must be in 16..=8192 pixels", args.size);
    }
    if !(1..=4).contains(&args.supersample) {
        anyhow::bail!("--supersample {}: must be 1 to 4", args.supersample);
    }
    if args.jpeg_quality.is_some_and(|q| !(1..=100).contains(&q)) {
        anyhow::bail!("--jpeg-quality: must be 1 to 100");
    }
    if !(args.pan.is_finite() && args.tilt.is_finite() && args.tilt.abs() <= 90.0) {
        anyhow::bail!("--pan/--tilt: must be finite degrees, tilt within [-90, 90]");
    }
    let rig = Rig::new(&rovernav_harness::rover_config(&mission)).with_size(args.size);
    let (pan, tilt) = (args.pan.to_radians(), args.tilt.to_radians());
    let Some(camera) = rig.camera(&args.camera, pan, tilt) else {
        anyhow::bail!("--camera: unknown camera `{}` (known: {})", args.camera, CAMERA_NAMES.join(", "));
    };
    let world = build_world(&mission, &origin)?;
    let truth = rovernav_sim::vehicle::settled_pose(&world.terrain.dem, &world.rover, world.start);
    let site =
        Pose3 { x: world.start.x, y: world.start.y, z: truth.z, yaw: world.start.yaw, ..Default::default() };
    let field = rovernav_sim::HeightField::new(&world.terrain.dem);
    let sun = Sun::on_mars(hours, args.latitude, args.ls);
    let atmosphere = Atmosphere { tau: args.tau, ..Atmosphere::default() };
    let scene = Scene::new(&world.terrain, &field, &sun, atmosphere).with_rover(&world.rover, &truth, pan);
    let mut settings = RenderSettings { supersample: args.supersample, ..RenderSettings::default() };
    settings.sensor.jpeg_quality = args.jpeg_quality;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create the folder", args.out.display()))?;
    let mut names = vec![camera.name];
    names.extend(camera.partner);
    for name in names {
        let cam = rig.camera(name, pan, tilt).expect("a rig camera's partner is a rig camera");
        let image = render(&scene, &cam.in_world(&truth, &site), name, &settings, mission.seed);
        let path = args.out.join(format!("{name}.png"));
        save(&image, &path, args.raw16)?;
        println!(
            "{}: {}x{} px, exposure {:.0} DN per unit I/F, sun azimuth {:.1} deg elevation {:.1} deg",
            path.display(),
            image.image.width(),
            image.image.height(),
            image.exposure,
            sun.azimuth.to_degrees(),
            sun.elevation.to_degrees()
        );
    }
    Ok(())
}

fn save(image: &rovernav_sim::render::RenderedImage, path: &Path, raw16: bool) -> anyhow::Result<()> {
    let result = if raw16 { image.image.save(path) } else { image.to_8bit().save(path) };
    result.with_context(|| format!("{}: cannot write the image", path.display()))
}

/// Local solar time `HH:MM` as hours.
fn parse_time(text: &str) -> anyhow::Result<f64> {
    let bad = || anyhow::anyhow!("--time `{text}`: expected local solar time HH:MM (00:00 to 23:59)");
    let (h, m) = text.split_once(':').ok_or_else(bad)?;
    let (h, m): (u32, u32) = (h.trim().parse().map_err(|_| bad())?, m.trim().parse().map_err(|_| bad())?);
    if h > 23 || m > 59 {
        return Err(bad());
    }
    Ok(h as f64 + m as f64 / 60.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_parses_and_bad_times_are_named() {
        assert_eq!(parse_time("13:30").unwrap(), 13.5);
        assert!(parse_time("25:00").unwrap_err().to_string().contains("--time"));
        assert!(parse_time("noon").is_err());
    }
}
