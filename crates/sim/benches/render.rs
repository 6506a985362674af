//! Renderer speed: a 1024 x 1024 Navcam image of a 30 m Mars yard, with and without shadow
//! rays, against the baseline of casting the same primary rays alone with the plain reference
//! caster (`HeightField::cast_reference`: corners of every visited patch, bisection; no
//! shading, no sensor), and the same primary rays with the caster the renderer uses; all on
//! the rayon pool of the machine, the full render also on one thread.

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
    let primary = |reference: bool| {
        (0..world.height())
            .into_par_iter()
            .map(|row| {
                (0..world.width())
                    .filter_map(|col| {
                        let ray = world.unproject(&Point2::new(col as f64, row as f64));
                        let (o, d) = (ray.origin.coords.into(), ray.direction.into_inner().into());
                        if reference {
                            field.cast_reference(&terrain.dem, o, d, 1e5)
                        } else {
                            field.cast(&terrain.dem, o, d, 1e5)
                        }
                    })
                    .count()
            })
            .sum::<usize>()
    };
    group.bench_function("baseline: primary ray casts only, reference caster", |b| b.iter(|| primary(true)));
    group.bench_function("primary ray casts only", |b| b.iter(|| primary(false)));
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
