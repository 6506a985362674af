//! Camera-model and rectification speed per megapixel. The baseline, measured in the same run,
//! is the linear CAHV unprojection: the ratios say what the distortion inversion costs.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Point2, Vector3};
use rovernav_vision::camera::{Cahv, Cahvor, Cahvore, CahvoreType, CameraModel};
use rovernav_vision::image::{Grey16, Luma};
use rovernav_vision::rectify::RectifyMap;

const SIZE: usize = 1024;

fn navcam_like() -> Cahv {
    Cahv::from_intrinsics(
        Vector3::new(1.0, 0.7, -1.9),
        Vector3::new(-0.065, 0.911, 0.406),
        Vector3::new(-1.0, 0.0, 0.0),
        1226.3,
        1226.0,
        503.5,
        506.5,
        SIZE,
        SIZE,
    )
}

/// Sum of ray x components over every pixel (keeps the work observable).
fn unproject_all(cam: &dyn CameraModel) -> f64 {
    let mut sum = 0.0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            sum += cam.unproject(&Point2::new(x as f64, y as f64)).direction.x;
        }
    }
    sum
}

fn bench(c: &mut Criterion) {
    let lin = navcam_like();
    let cahvor = Cahvor::new(lin, lin.a, Vector3::new(0.000274, -0.004951, 0.021485));
    let cahvore = Cahvore::new(
        Cahv::from_intrinsics(
            lin.c,
            lin.a,
            Vector3::new(-1.0, 0.0, 0.0),
            300.0,
            300.0,
            511.5,
            511.5,
            SIZE,
            SIZE,
        ),
        lin.a,
        Vector3::new(0.0, 0.03, -0.01),
        Vector3::new(0.01, 0.0, 0.0),
        CahvoreType::Fisheye,
    );
    let mut group = c.benchmark_group("unproject_1mpx");
    group.sample_size(10);
    group.bench_function("cahv_baseline", |b| b.iter(|| unproject_all(&lin)));
    group.bench_function("cahvor", |b| b.iter(|| unproject_all(&cahvor)));
    group.bench_function("cahvore_fisheye", |b| b.iter(|| unproject_all(&cahvore)));
    group.finish();

    let image = Grey16::from_fn(SIZE as u32, SIZE as u32, |x, y| Luma([((x * 7 + y * 13) % 4096) as u16]));
    let map = RectifyMap::new(&cahvor, &lin, 10.0);
    let mut group = c.benchmark_group("rectify_1mpx");
    group.sample_size(10);
    group.bench_function("map_cahvor", |b| b.iter(|| RectifyMap::new(&cahvor, &lin, 10.0)));
    group.bench_function("apply_grey16", |b| b.iter(|| map.apply_grey16(&image).unwrap()));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
