//! The detectors on real Mars images from `../shared/data` (skipped with a message when the
//! data are absent; failing then when ROVERNAV_REQUIRE_DATA=1).

use rovernav_science::{CloudParams, SkyParams, detect_clouds, segment_sky};
use rovernav_vision::codec::read_image;
use std::path::PathBuf;

fn data(path: &str) -> Option<PathBuf> {
    let p = rovernav_core::data_dir().join(path);
    if p.exists() {
        return Some(p);
    }
    if std::env::var("ROVERNAV_REQUIRE_DATA").is_ok_and(|v| v == "1") {
        panic!("{}: missing and ROVERNAV_REQUIRE_DATA=1", p.display());
    }
    eprintln!("skipping: {} not found", p.display());
    None
}

/// The Gale Navcam mosaic (sol 1051, 7696x1800, cylindrical: elevation 0 at row 379.759,
/// 0.0469 deg per row). The skyline a person traces runs near elevation 0 on the plains and up
/// to about 11 deg (row ~145) over Mount Sharp's distant peaks; the sky above it is brighter
/// than the ground below it.
#[test]
fn pano_sky_lies_above_the_skyline() {
    let Some(path) = data("gale/navcam_pano/N_L000_1051_ILT048CYL_S_2470_UNCORM1.jpg") else { return };
    let image = read_image(&path).unwrap().to_grey_f32();
    let mask = segment_sky(&image, &SkyParams::default());
    let elevation_zero = 379.759;
    let deg_per_row = (17.7171 + 66.5118) / 1800.0;
    let mut with_sky = 0;
    let (mut sky_sum, mut sky_n, mut ground_sum, mut ground_n) = (0f64, 0f64, 0f64, 0f64);
    for x in 0..mask.width {
        let (top, h) = (mask.top[x as usize], mask.horizon[x as usize]);
        // Elevation of the skyline: between -3 deg (the plain below the rover's hill) and 12 deg.
        let elevation = (elevation_zero - h as f64) * deg_per_row;
        assert!((-3.0..=12.0).contains(&elevation), "column {x}: horizon row {h} = {elevation:.1} deg");
        if h > top + 20 {
            with_sky += 1;
            for y in top..h {
                sky_sum += image.get_pixel(x, y)[0] as f64;
                sky_n += 1.0;
            }
            for y in h..(h + 40).min(mask.height) {
                ground_sum += image.get_pixel(x, y)[0] as f64;
                ground_n += 1.0;
            }
        }
    }
    assert!(with_sky as f64 > 0.95 * mask.width as f64, "only {with_sky} columns with sky");
    let (sky, ground) = (sky_sum / sky_n, ground_sum / ground_n);
    assert!(sky > ground + 20.0, "sky {sky:.0} vs ground below {ground:.0}");
    // No sky in the lower half of the mosaic.
    assert!(mask.horizon.iter().all(|&h| h < 900));
    // The sky's data start below the fill, also under the fill's printed labels (glyphs a few
    // rows tall that once started the sky at row 2 and read as a cloud at x 4284..4536).
    let fill_rows = (4480..4520).filter(|&x| mask.top[x] < 20).count();
    assert_eq!(fill_rows, 0, "tops {:?}", &mask.top[4480..4520]);
    // The sol-1051 sky is clear to a person: no cloud, also across the frames' seams.
    let clouds = detect_clouds(&image, &mask, &CloudParams::default());
    assert!(!clouds.cloud, "{clouds:?}");
}

/// The MSL Navcam EDR looks down at a gravel plain: a person sees at most a strip of sky at the
/// very top, and there is no cloud.
#[test]
fn navcam_edr_ground_is_not_sky() {
    let Some(path) = data("gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG") else { return };
    let image = read_image(&path).unwrap().to_grey_f32();
    let mask = segment_sky(&image, &SkyParams::default());
    assert!(mask.fraction() < 0.02, "sky fraction {}", mask.fraction());
    assert!(!detect_clouds(&image, &mask, &CloudParams::default()).cloud);
}
