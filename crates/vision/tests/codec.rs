//! Image files: the real 12-bit Navcam EDR, and PNG / PGM / PPM / JPEG round trips.

use std::path::PathBuf;

use image::{ImageFormat, Luma, Rgb};
use rovernav_vision::codec::{self, AnyImage, CodecError};
use rovernav_vision::image::{Grey8, Grey16, Rgb8};

const NAVCAM: &str = "gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG";

use rovernav_core::data_file_or_skip as data_file;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-vision-codec-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A deterministic pseudo-random sequence (SplitMix64).
fn noise(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[test]
fn navcam_edr_decodes_to_12_bit_1024_square() {
    let Some(path) = data_file(NAVCAM) else { return };
    let AnyImage::Grey16 { image, bits } = codec::read_image(&path).unwrap() else { panic!("not grey16") };
    assert_eq!((image.width(), image.height(), bits), (1024, 1024, 12));
    let values: Vec<u16> = image.pixels().map(|p| p[0]).collect();
    let max = *values.iter().max().unwrap();
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
    let sd = (values.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt();
    eprintln!("navcam: max {max} mean {mean:.1} sd {sd:.1}");
    assert!(max < 4096, "12-bit values");
    assert!((200.0..4000.0).contains(&mean), "plausible exposure");
    assert!(sd > 20.0, "a scene, not a constant frame");
    // Independent decode of the same bytes: the label puts the image at record 23 of 2048
    // bytes, 1024 x 1024 big-endian 16-bit samples masked to 12 bits.
    let bytes = std::fs::read(&path).unwrap();
    let start = 22 * 2048;
    for &(line, sample) in &[(0usize, 0usize), (17, 900), (511, 511), (1023, 1023), (800, 3)] {
        let k = start + 2 * (line * 1024 + sample);
        let raw = u16::from_be_bytes([bytes[k], bytes[k + 1]]) & 0x0FFF;
        assert_eq!(image.get_pixel(sample as u32, line as u32)[0], raw, "line {line} sample {sample}");
    }
    // The 8-bit display version keeps the top 8 of the 12 bits.
    let grey8 = AnyImage::Grey16 { image: image.clone(), bits }.to_grey8();
    assert_eq!(grey8.get_pixel(511, 511)[0] as u16, image.get_pixel(511, 511)[0] >> 4);
}

#[test]
fn png_round_trips_are_lossless() {
    let dir = temp_dir("png");
    let mut next = noise(7);
    let g16 = Grey16::from_fn(37, 23, |_, _| Luma([next() as u16]));
    let g8 = Grey8::from_fn(31, 19, |_, _| Luma([next() as u8]));
    let rgb = Rgb8::from_fn(17, 29, |_, _| Rgb([next() as u8, next() as u8, next() as u8]));
    codec::write_png_grey16(dir.join("g16.png"), &g16).unwrap();
    codec::write_png_grey8(dir.join("g8.png"), &g8).unwrap();
    codec::write_png_rgb8(dir.join("rgb.png"), &rgb).unwrap();
    assert_eq!(
        codec::read_image(dir.join("g16.png")).unwrap(),
        AnyImage::Grey16 { image: g16.clone(), bits: 16 }
    );
    assert_eq!(codec::read_image(dir.join("g8.png")).unwrap(), AnyImage::Grey8(g8.clone()));
    assert_eq!(codec::read_image(dir.join("rgb.png")).unwrap(), AnyImage::Rgb8(rgb.clone()));
    // The generic writer too.
    codec::write_png(dir.join("any.png"), &AnyImage::Grey16 { image: g16.clone(), bits: 12 }).unwrap();
    assert_eq!(codec::read_image(dir.join("any.png")).unwrap().to_grey16(), g16);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn pnm_and_jpeg_read() {
    let dir = temp_dir("pnm");
    let mut next = noise(11);
    let g8 = Grey8::from_fn(33, 21, |_, _| Luma([next() as u8]));
    let g16 = Grey16::from_fn(12, 9, |_, _| Luma([next() as u16]));
    let rgb = Rgb8::from_fn(20, 14, |_, _| Rgb([next() as u8, next() as u8, next() as u8]));
    g8.save_with_format(dir.join("a.pgm"), ImageFormat::Pnm).unwrap();
    g16.save_with_format(dir.join("b.pgm"), ImageFormat::Pnm).unwrap();
    rgb.save_with_format(dir.join("c.ppm"), ImageFormat::Pnm).unwrap();
    assert_eq!(codec::read_image(dir.join("a.pgm")).unwrap(), AnyImage::Grey8(g8));
    assert_eq!(codec::read_image(dir.join("b.pgm")).unwrap(), AnyImage::Grey16 { image: g16, bits: 16 });
    assert_eq!(codec::read_image(dir.join("c.ppm")).unwrap(), AnyImage::Rgb8(rgb));
    // JPEG is lossy: a smooth gradient comes back within a few grey levels.
    let smooth = Rgb8::from_fn(64, 48, |x, y| Rgb([(x * 3) as u8, (y * 4) as u8, 128]));
    smooth.save_with_format(dir.join("d.jpg"), ImageFormat::Jpeg).unwrap();
    let AnyImage::Rgb8(back) = codec::read_image(dir.join("d.jpg")).unwrap() else { panic!("not rgb") };
    let err: f64 =
        smooth.pixels().zip(back.pixels()).map(|(a, b)| (a[0] as f64 - b[0] as f64).abs()).sum::<f64>()
            / (64.0 * 48.0);
    assert!(err < 4.0, "mean JPEG error {err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn errors_name_the_file() {
    let dir = temp_dir("err");
    let missing = dir.join("nothing.png");
    let err = codec::read_image(&missing).unwrap_err();
    assert!(matches!(err, CodecError::Io { .. }) && err.to_string().contains("nothing.png"), "{err}");
    std::fs::write(dir.join("junk.png"), b"not an image at all").unwrap();
    let err = codec::read_image(dir.join("junk.png")).unwrap_err();
    assert!(err.to_string().contains("junk.png"), "{err}");
    std::fs::write(dir.join("junk.IMG"), b"PDS_VERSION_ID = PDS3\nEND\n").unwrap();
    let err = codec::read_image(dir.join("junk.IMG")).unwrap_err();
    assert!(err.to_string().contains("junk.IMG") && err.to_string().contains("IMAGE"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}
