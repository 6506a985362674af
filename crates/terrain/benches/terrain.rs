//! Speed of procedural generation, rock sampling and DEM loading.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_terrain::procedural::{self, MarsYardParams, RockFieldParams, RockyRegionParams};
use rovernav_terrain::{LocalRect, io};

fn generation(c: &mut Criterion) {
    let mut group = c.benchmark_group("procedural");
    group.sample_size(10);
    let yard = MarsYardParams::with_seed(1);
    group.bench_function("generate 30 m x 30 m at 5 cm", |b| {
        b.iter(|| procedural::generate(black_box(&yard)))
    });
    let area = LocalRect::from_corner_size(0.0, 0.0, 200.0, 200.0);
    group.bench_function("sample rocks 200 m x 200 m", |b| {
        b.iter(|| procedural::sample_rocks_seeded(&RockFieldParams::default(), black_box(area), &[], 3))
    });
    if let Some(path) = rovernav_core::data_file_or_skip("gale/missionDEM.tif") {
        let gale = io::load_geotiff(&path).expect("Gale DEM loads");
        group.bench_function("load Gale GeoTIFF", |b| b.iter(|| io::load_geotiff(black_box(&path))));
        let (x, y) = gale.to_local(8_142_579.427, -276_693.318);
        let params = RockyRegionParams::around(x, y, 15.0, 3);
        group.bench_function("rocky Gale region 30 m at 5 cm", |b| {
            b.iter(|| procedural::rocky_region(black_box(&gale), &params))
        });
    }
    group.finish();
}

criterion_group!(benches, generation);
criterion_main!(benches);
