//! The renderer against independent truths: projected geometry, shadow geometry, the sky and
//! haze formulas, the noise model, determinism and the rover seen from the lander.

use nalgebra::{Point2, Point3, Vector3};
use rovernav_core::{Pose3, RoverConfig};
use rovernav_sim::HeightField;
use rovernav_sim::render::{
    Atmosphere, Exposure, Label, RenderSettings, RenderedImage, Rig, Scene, Sensor, Sun, Volume, VolumeShape,
    render,
};
use rovernav_terrain::{Dem, Rock, Terrain};
use rovernav_vision::camera::Cahvor;
use rovernav_vision::{Cahv, CameraModel};

fn flat(size_m: f64, res: f64) -> Terrain {
    let n = (size_m / res).round() as usize;
    Terrain { dem: Dem::flat(n, n, res, 0.0), rocks: Vec::new() }
}

fn camera(centre: [f64; 3], axis: [f64; 3], right: [f64; 3], fov_deg: f64, size: usize) -> Cahv {
    let f = 0.5 * size as f64 / (0.5 * fov_deg.to_radians()).tan();
    let c = 0.5 * (size as f64 - 1.0);
    Cahv::from_intrinsics(centre.into(), axis.into(), right.into(), f, f, c, c, size, size)
}

fn noiseless() -> RenderSettings {
    let sensor = Sensor { noise: false, dead_pixels: 0, ..Sensor::default() };
    RenderSettings { sensor, ..RenderSettings::default() }
}

fn sun() -> Sun {
    Sun::on_mars(14.0, -14.6, 0.0)
}

/// The silhouette of the rover's solar deck seen from straight above lies where the camera
/// model projects the deck's corners: every row's edge estimate within 0.5 px, unbiased.
#[test]
fn rover_silhouette_lands_on_the_projected_corners() {
    let terrain = flat(6.0, 0.05);
    let field = HeightField::new(&terrain.dem);
    let rover = RoverConfig::default();
    let pose = Pose3 { x: 3.0, y: 3.0, z: 0.0, yaw: 0.37, ..Default::default() };
    let scene = Scene::new(&terrain, &field, &sun(), Atmosphere::default()).with_rover(&rover, &pose, 0.0);
    let cam = camera([3.05, 2.97, 3.5], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], 40.0, 300);
    let img = render(&scene, &cam, "test", &noiseless(), 1);
    // The deck plate's top face: half extents l/2 + 0.02 by w/2 + 0.02 at clearance + 0.24.
    let (hx, hy, z) = (0.5 * rover.length + 0.02, 0.5 * rover.width + 0.02, rover.clearance + 0.24);
    let corners: Vec<Point2<f64>> = [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)]
        .iter()
        .map(|&(x, y)| {
            let p = pose.transform([x, y, z]);
            cam.project(&Point3::from(p)).expect("in front")
        })
        .collect();
    let (ymin, ymax) =
        corners.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
    let w = cam.width();
    let mut errors = Vec::new();
    for row in (ymin.ceil() as usize + 2)..=(ymax.floor() as usize - 2) {
        let y = row as f64;
        // Crossings of the row with the quadrilateral's edges.
        let mut xs: Vec<f64> = (0..4)
            .filter_map(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % 4]);
                ((a.y - y) * (b.y - y) < 0.0).then(|| a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y))
            })
            .collect();
        xs.sort_by(f64::total_cmp);
        let mask: Vec<usize> = (0..w).filter(|&c| img.labels[row * w + c] == Label::Rover).collect();
        let (first, last) = (*mask.first().unwrap() as f64, *mask.last().unwrap() as f64);
        errors.push(first - 0.5 - xs[0]);
        errors.push(last + 0.5 - xs[xs.len() - 1]);
    }
    assert!(errors.len() > 100);
    let worst = errors.iter().fold(0f64, |m, e| m.max(e.abs()));
    let bias = errors.iter().sum::<f64>() / errors.len() as f64;
    assert!(worst <= 0.5 + 1e-6, "worst edge error {worst} px");
    assert!(bias.abs() < 0.1, "edge bias {bias} px");
}

/// A world point on the ground projects to a sub-pixel position where the range image,
/// interpolated, equals the point's distance from the camera (a half-pixel shift would be
/// ~5 mm here).
#[test]
fn projected_ground_points_meet_the_rendered_range() {
    let terrain = flat(12.0, 0.05);
    let field = HeightField::new(&terrain.dem);
    let scene = Scene::new(&terrain, &field, &sun(), Atmosphere::default());
    let d = 30f64.to_radians();
    let linear =
        camera([1.0, 1.0, 1.2], [d.cos() * 0.8, d.cos() * 0.6, -d.sin()], [0.6, -0.8, 0.0], 45.0, 256);
    check_projected_ground_range(&scene, &linear);
    // A lens with radial distortion (CAHVOR, R terms of a wide lens) renders through the same
    // call and meets the same test.
    let distorted = Cahvor::new(linear, linear.a, Vector3::new(0.0, -0.08, 0.02));
    let shift = [(2.2, 3.1), (4.1, 3.3), (3.6, 4.0)]
        .iter()
        .map(|&(x, y)| {
            let p = Point3::new(x, y, 0.0);
            (distorted.project(&p).unwrap() - linear.project(&p).unwrap()).norm()
        })
        .fold(0f64, f64::max);
    assert!(shift > 1.0, "the distortion moves points by {shift} px");
    check_projected_ground_range(&scene, &distorted);
}

fn check_projected_ground_range(scene: &Scene, cam: &dyn CameraModel) {
    let img = render(scene, cam, "test", &noiseless(), 1);
    let w = cam.width();
    let mut checked = 0;
    for (x, y) in [(3.0, 2.5), (2.2, 3.1), (4.1, 3.3), (2.9, 1.9), (3.6, 4.0)] {
        let p = Point3::new(x, y, 0.0);
        let px = cam.project(&p).expect("in front");
        if !(px.x >= 1.0 && px.y >= 1.0 && px.x < w as f64 - 2.0 && px.y < w as f64 - 2.0) {
            continue;
        }
        let (c0, r0) = (px.x.floor() as usize, px.y.floor() as usize);
        let (tx, ty) = (px.x - c0 as f64, px.y - r0 as f64);
        let r = |c: usize, r: usize| img.range[r * w + c] as f64;
        let interp = (r(c0, r0) * (1.0 - tx) + r(c0 + 1, r0) * tx) * (1.0 - ty)
            + (r(c0, r0 + 1) * (1.0 - tx) + r(c0 + 1, r0 + 1) * tx) * ty;
        let truth = (p - cam.centre()).norm();
        assert!((interp - truth).abs() < 1e-3, "{x},{y}: {interp} vs {truth}");
        checked += 1;
    }
    assert!(checked >= 4);
}

/// A rock on flat ground under a low eastern sun: the ground west of it (away from the sun)
/// is in shadow, the ground east of it is lit, and shadowed ground keeps the diffuse sky light.
#[test]
fn shadows_fall_away_from_the_sun() {
    let mut terrain = flat(8.0, 0.02);
    let rock = Rock { x: 4.0, y: 4.0, diameter: 0.6, height: 0.4 };
    let g = *terrain.dem.geometry();
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (x, y) = g.center(c, r);
            let q = 2.0 * (x - rock.x).hypot(y - rock.y) / rock.diameter;
            if q < 1.0 {
                *terrain.dem.heights.get_mut(c, r) = (rock.height * (1.0 - q * q).sqrt()) as f32;
            }
        }
    }
    terrain.rocks.push(rock);
    let field = HeightField::new(&terrain.dem);
    // Morning on the equator on the equinox: the sun due east, 30 deg up.
    let sun = Sun::at(8.0, 0.0, 0.0);
    assert!(sun.direction()[0] > 0.8);
    let scene = Scene::new(&terrain, &field, &sun, Atmosphere::default());
    let cam = camera([4.0, 4.0, 6.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], 30.0, 256);
    let img = render(&scene, &cam, "test", &noiseless(), 1);
    let unshadowed = render(&scene, &cam, "test", &RenderSettings { shadows: false, ..noiseless() }, 1);
    // Radiance relative to the same pixel without shadow rays: 1 where lit, the diffuse share
    // of the light in shadow.
    let at = |x: f64, y: f64| {
        let p = cam.project(&Point3::new(x, y, 0.0)).unwrap();
        let i = p.y.round() as usize * cam.width() + p.x.round() as usize;
        img.radiance[i] as f64 / unshadowed.radiance[i] as f64
    };
    let l = &scene.lighting;
    let sky_share = l.diffuse / (l.diffuse + l.direct * l.sun[2]);
    // Shadow length: 0.4 m / tan(30 deg) = 0.69 m behind the rock's top, which sits at its centre.
    for dy in [-0.1, 0.0, 0.1] {
        let (west, east) = (at(4.0 - 0.5, 4.0 + dy), at(4.0 + 0.5, 4.0 + dy));
        assert!((west - sky_share).abs() < 1e-3, "west {west}, diffuse share {sky_share}");
        assert!((east - 1.0).abs() < 1e-6, "east {east}");
        assert!(sky_share > 0.1 && sky_share < 0.6);
        // Beyond the shadow's end the ground is lit again.
        let far_west = at(4.0 - 0.9, 4.0 + dy);
        assert!((far_west - 1.0).abs() < 1e-6, "far west {far_west}");
    }
}

/// Every ray above the horizon sees sky (there is nothing above flat ground), and the sky's
/// brightness falls with elevation looking away from the sun.
#[test]
fn sky_above_the_horizon_darkens_with_elevation() {
    let terrain = flat(20.0, 0.1);
    let field = HeightField::new(&terrain.dem);
    let sun = sun();
    let scene = Scene::new(&terrain, &field, &sun, Atmosphere::default());
    let s = sun.direction();
    let away = Vector3::new(-s[0], -s[1], 0.0).normalize();
    let axis = away + Vector3::new(0.0, 0.0, 0.35);
    let right = away.cross(&Vector3::z());
    let cam = Cahv::from_intrinsics(
        Vector3::new(10.0, 10.0, 1.5),
        axis,
        right,
        300.0,
        300.0,
        127.5,
        127.5,
        256,
        256,
    );
    let img = render(&scene, &cam, "test", &noiseless(), 1);
    let w = cam.width();
    let mut row_means = Vec::new();
    for row in 0..w {
        let mut sky = Vec::new();
        for col in 0..w {
            let dir = cam.unproject(&Point2::new(col as f64, row as f64)).direction;
            let label = img.labels[row * w + col];
            if dir.z > 1e-3 {
                assert_eq!(label, Label::Sky, "pixel {col},{row} above the horizon");
            }
            if dir.z < -1e-3 {
                assert_ne!(label, Label::Sky, "pixel {col},{row} below the horizon");
            }
            if label == Label::Sky && (100..156).contains(&col) {
                sky.push(img.radiance[row * w + col] as f64);
            }
        }
        if sky.len() == 56 {
            row_means.push(sky.iter().sum::<f64>() / sky.len() as f64);
        }
    }
    assert!(row_means.len() > 50);
    // Rows go down the image, so elevation falls and brightness rises along the list.
    assert!(row_means.windows(2).all(|p| p[1] >= p[0]), "{row_means:?}");
    assert!(row_means.last().unwrap() > &(1.5 * row_means[0]));
}

/// Dust washes out distant ground: the texture contrast of a render with aerial perspective,
/// relative to the same render without it, follows exp(-tau d / H) and falls with range.
#[test]
fn dust_washes_out_far_terrain() {
    let terrain = flat(20.0, 0.1);
    let field = HeightField::new(&terrain.dem);
    let tau = 1.0;
    let hazy = Atmosphere { tau, scale_height_m: 1000.0, ..Atmosphere::default() };
    let clear = Atmosphere { scale_height_m: f64::INFINITY, ..hazy };
    let cam = camera([10.0, 10.0, 2.0], [1.0, 0.0, -0.02], [0.0, -1.0, 0.0], 30.0, 256);
    let a = render(&Scene::new(&terrain, &field, &sun(), hazy), &cam, "t", &noiseless(), 1);
    let b = render(&Scene::new(&terrain, &field, &sun(), clear), &cam, "t", &noiseless(), 1);
    let w = cam.width();
    let lighting = Scene::new(&terrain, &field, &sun(), hazy).lighting;
    // Contrast of the ground against the horizon sky behind it, along a row.
    let contrast = |img: &RenderedImage, row: usize| {
        (0..w)
            .map(|c| {
                let d = cam.unproject(&Point2::new(c as f64, row as f64)).direction;
                let h = Vector3::new(d.x, d.y, 0.0).normalize();
                (img.radiance[row * w + c] as f64 - lighting.sky([h.x, h.y, 0.0])).abs()
            })
            .sum::<f64>()
    };
    let mut last = f64::INFINITY;
    let mut rows = 0;
    for row in (0..w).rev().step_by(2) {
        let d = img_range(&a, row * w + w / 2);
        if !(d.is_finite() && d > 30.0) || a.labels[row * w + w / 2] == Label::Sky {
            continue;
        }
        let ratio = contrast(&a, row) / contrast(&b, row);
        let expected = (-tau * d / 1000.0).exp();
        assert!((ratio - expected).abs() < 0.05 + 0.1 * expected, "row {row} d {d}: {ratio} vs {expected}");
        assert!(ratio <= last + 1e-3);
        last = ratio;
        rows += 1;
    }
    assert!(rows >= 5 && last < 0.5, "{rows} rows, last ratio {last}");
}

fn img_range(img: &RenderedImage, i: usize) -> f64 {
    img.range[i] as f64
}

/// The sensor's noise on a uniform patch: variance = DN / gain + read noise^2 (+ 1/12 from
/// rounding), mean unbiased, at several signal levels.
#[test]
fn noise_variance_follows_the_photon_transfer_model() {
    let sensor = Sensor { exposure: Exposure::Fixed(1.0), dead_pixels: 0, ..Sensor::default() };
    let n = 200 * 200;
    for level in [50.0, 400.0, 1500.0, 3500.0] {
        let dn = sensor.expose(&vec![level as f32; n], 200, 1.0, 5, "flat");
        let m = dn.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
        let var = dn.iter().map(|&v| (v as f64 - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        let expected = level / sensor.gain_e_per_dn + sensor.read_noise_dn.powi(2) + 1.0 / 12.0;
        assert!((m - level).abs() < 4.0 * (expected / n as f64).sqrt(), "mean {m} at {level}");
        assert!((var / expected - 1.0).abs() < 0.05, "variance {var} vs {expected} at {level}");
    }
}

/// Same seed, same image; another seed, other noise; dead pixels stay where they are.
#[test]
fn rendering_is_deterministic_for_a_seed() {
    let terrain = flat(10.0, 0.05);
    let field = HeightField::new(&terrain.dem);
    let scene = Scene::new(&terrain, &field, &sun(), Atmosphere::default());
    let cam = camera([5.0, 5.0, 1.2], [1.0, 0.0, -0.5], [0.0, -1.0, 0.0], 45.0, 96);
    let s = RenderSettings::default();
    let (a, b, c) = (
        render(&scene, &cam, "x", &s, 7),
        render(&scene, &cam, "x", &s, 7),
        render(&scene, &cam, "x", &s, 8),
    );
    assert_eq!(a, b);
    assert_ne!(a.image, c.image);
    let dead = |img: &RenderedImage| {
        img.image.pixels().enumerate().filter(|(_, p)| p.0[0] == 0).map(|(i, _)| i).collect::<Vec<_>>()
    };
    assert_eq!(dead(&a), dead(&c));
    assert!(!dead(&a).is_empty());
}

/// The lander camera of the default rig sees the rover at the mission start.
#[test]
fn the_lander_sees_the_rover() {
    let terrain = flat(30.0, 0.05);
    let field = HeightField::new(&terrain.dem);
    let rover = RoverConfig::default();
    let site = Pose3 { x: 12.0, y: 9.0, z: 0.0, yaw: 0.8, ..Default::default() };
    let scene = Scene::new(&terrain, &field, &sun(), Atmosphere::default()).with_rover(&rover, &site, 0.0);
    let rig = Rig::new(&rover).with_size(256);
    let lander = rig.camera("lander", 0.0, 0.0).unwrap();
    let cam = lander.in_world(&site, &site);
    let img = render(&scene, &cam, "lander", &noiseless(), 1);
    let rover_pixels = img.labels.iter().filter(|l| **l == Label::Rover).count();
    assert!(rover_pixels > 300, "{rover_pixels} rover pixels");
    // The mast head projects onto a rover pixel.
    let head = cam.project(&Point3::from(site.transform([0.0, 0.0, rover.mast_height]))).unwrap();
    let i = head.y.round() as usize * 256 + head.x.round() as usize;
    assert_eq!(img.labels[i], Label::Rover);
}

/// A dust devil between the camera and the sky changes exactly the pixels whose rays cross it,
/// towards its own single-scattered brightness.
#[test]
fn a_dust_devil_changes_the_pixels_it_covers() {
    let terrain = flat(20.0, 0.1);
    let field = HeightField::new(&terrain.dem);
    let base = Scene::new(&terrain, &field, &sun(), Atmosphere::default());
    let mut scene = base.clone();
    scene.volumes.push(Volume {
        shape: VolumeShape::Column { radius: 3.0, height: 300.0 },
        position: [60.0, 10.0, 0.0],
        velocity: [0.0, 2.0, 0.0],
        density: 0.05,
        albedo: 0.6,
    });
    scene.time = 1.0;
    let cam = camera([10.0, 10.0, 1.5], [1.0, 0.0, 0.05], [0.0, -1.0, 0.0], 40.0, 128);
    let (a, b) = (render(&base, &cam, "t", &noiseless(), 1), render(&scene, &cam, "t", &noiseless(), 1));
    let mut changed = 0;
    for i in 0..a.radiance.len() {
        let ray = cam.unproject(&Point2::new((i % 128) as f64, (i / 128) as f64));
        let o = [ray.origin.x, ray.origin.y, ray.origin.z];
        let d = ray.direction.into_inner();
        let chord = scene.volumes[0]
            .chord(o, [d.x, d.y, d.z], 1.0)
            .map_or(0.0, |(t0, t1)| t1.min(a.range[i] as f64) - t0);
        if chord > 0.5 {
            assert!((a.radiance[i] - b.radiance[i]).abs() > 1e-4, "pixel {i} unchanged");
            changed += 1;
        } else if chord <= 0.0 {
            assert_eq!(a.radiance[i], b.radiance[i]);
        }
    }
    assert!(changed > 200, "{changed}");
}
