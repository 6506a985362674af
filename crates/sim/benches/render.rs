//! Renderer speed: a 1024 x 1024 Navcam image of a 30 m Mars yard, with and without shadow
//! rays, against the baseline of casting the same primary rays alone (the range imager's ray
//! cast, no shading, no sensor), all on the rayon pool of the machine and on one thread.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nalgebra::Point2;
use rayon::prelude::*;
use rovernav_core::{Pose3, RoverConfig};
use rovernav_sim::HeightField;
use rovernav_sim::render::{Atmosphere, RenderSettings, Rig, Scene, Sun, render};
use rovernav_terrain::procedural::{MarsYardParams, generate};
use rovernav_vision::CameraModel;
use rovernav_vision::camera::Movable;

fn benches(c: &mut Criterion) {
    let terrain = generate(&MarsYardParams { seed: 3, ..Default::default() });
    let field = HeightField::new(&terrain.dem);
    let rover = RoverConfig::default();
    let z = terrain.dem.height(15.0, 15.0).unwrap_or(0.0);
    let pose = Pose3 { x: 15.0, y: 15.0, z, yaw: 0.4, ..Default::default() };
    let sun = Sun::on_mars(14.0, -14.6, 0.0);
    let scene = Scene::new(&terrain, &field, &sun, Atmosphere::default()).with_rover(&rover, &pose, 0.0);
    let rig = Rig::new(&rover);
    let cam = rig.camera("navcam_left", 0.0, -25f64.to_radians()).expect("known camera");
    let world = cam.model.moved(&rovernav_sim::render::pose_isometry(&pose));
    let settings = RenderSettings::default();
    let no_shadows = RenderSettings { shadows: false, ..RenderSettings::default() };
    let mut group = c.benchmark_group("render navcam 1024x1024");
    group.sample_size(10);
    // Throughput in pixels: criterion prints megapixels per second.
    group.throughput(Throughput::Elements((world.width() * world.height()) as u64));
    group.bench_function("baseline: primary ray casts only", |b| {
        b.iter(|| {
            (0..world.height())
                .into_par_iter()
                .map(|row| {
                    (0..world.width())
                        .filter_map(|col| {
                            let ray = world.unproject(&Point2::new(col as f64, row as f64));
                            let d = ray.direction.into_inner();
                            field.cast(&terrain.dem, ray.origin.coords.into(), d.into(), 1e5)
                        })
                        .count()
                })
                .sum::<usize>()
        })
    });
    group.bench_function("render without shadows", |b| {
        b.iter(|| render(&scene, &world, "navcam_left", &no_shadows, 1))
    });
    group.bench_function("render with shadows", |b| {
        b.iter(|| render(&scene, &world, "navcam_left", &settings, 1))
    });
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a thread pool");
    group.bench_function("render with shadows, one thread", |b| {
        b.iter(|| one.install(|| render(&scene, &world, "navcam_left", &settings, 1)))
    });
    group.finish();
}

criterion_group!(render_benches, benches);
criterion_main!(render_benches);
