//! Loader scenarios: the real Gale, MOLA and Navcam files against their published values, and
//! synthetic files (written here) for every layout and for corrupt input.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use rovernav_core::data_file_or_skip;
use rovernav_terrain::io::{self, GlobalDem, Pds3Image, Pds3Label};
use rovernav_terrain::{Dem, LoadError};
use tiff::encoder::{TiffEncoder, colortype};
use tiff::tags::Tag;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-terrain-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Curiosity's sol-1051 (easting, northing, elevation) from the GeoJSON next to the DEM.
fn curiosity_sol1051() -> Option<(f64, f64, f64)> {
    let path = data_file_or_skip("gale/waypoints_sol1051.geojson")?;
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let p = &json["features"][0]["properties"];
    Some((p["easting_m"].as_f64()?, p["northing_m"].as_f64()?, p["elev_m"].as_f64()?))
}

#[test]
fn gale_dem_matches_published_values() {
    let Some(path) = data_file_or_skip("gale/missionDEM.tif") else { return };
    let dem = io::load_geotiff(&path).unwrap();
    let g = dem.geometry();
    assert_eq!((g.cols, g.rows), (348, 337));
    assert_eq!(g.resolution, 1.0);
    assert_eq!(dem.nodata, Some(-32767.0));
    // The NW corner of the top-left pixel is the tiepoint (E 8142406, N -276455).
    let (e, n) = dem.to_projected(0.0, g.height_m());
    assert!((e - 8_142_406.0).abs() < 1e-6 && (n + 276_455.0).abs() < 1e-6, "{e} {n}");
    let (lo, hi) = dem.min_max().unwrap();
    assert!((lo + 4472.7).abs() < 0.05 && (hi + 4437.9).abs() < 0.05, "{lo} {hi}");

    let Some((easting, northing, elevation)) = curiosity_sol1051() else { return };
    let (x, y) = dem.to_local(easting, northing);
    let z = dem.height(x, y).unwrap();
    assert!((z + 4446.8).abs() < 0.1, "DEM reads {z} at the rover");
    assert!((z - elevation).abs() < 0.1, "rover localised at {elevation}, DEM {z}");
}

#[test]
fn gale_slope_statistics_match_published_values() {
    // The data README gives slope mean 8 deg, p95 17.9 deg, max 40 deg.
    let Some(path) = data_file_or_skip("gale/missionDEM.tif") else { return };
    let dem = io::load_geotiff(&path).unwrap();
    let mut slopes: Vec<f64> =
        dem.slope_grid().data.iter().filter(|s| s.is_finite()).map(|&s| (s as f64).to_degrees()).collect();
    slopes.sort_by(f64::total_cmp);
    let mean = slopes.iter().sum::<f64>() / slopes.len() as f64;
    let p95 = slopes[(0.95 * slopes.len() as f64) as usize];
    let max = *slopes.last().unwrap();
    // Rounded published figures; Horn's method as in common GIS tools.
    assert!((mean - 8.0).abs() < 0.3, "mean {mean}");
    assert!((p95 - 17.9).abs() < 0.5, "p95 {p95}");
    assert!((max - 40.0).abs() < 1.5, "max {max}");
    // A point query agrees with the grid where the surface is smooth enough.
    let (x, y) = (170.0, 100.0);
    let (c, r) = dem.geometry().cell_of(x, y).unwrap();
    let point = dem.slope(dem.geometry().center(c, r).0, dem.geometry().center(c, r).1).unwrap();
    assert!((point - *dem.slope_grid().get(c, r) as f64).abs() < 0.1);
}

#[test]
fn gale_crop_keeps_the_georeference() {
    let Some(path) = data_file_or_skip("gale/missionDEM.tif") else { return };
    let Some((easting, northing, _)) = curiosity_sol1051() else { return };
    let dem = io::load_geotiff(&path).unwrap();
    let (x, y) = dem.to_local(easting, northing);
    let crop = dem.crop(rovernav_terrain::LocalRect::centered(x, y, 10.0)).unwrap();
    let fine = crop.resample(0.25).unwrap().rebased();
    let (fx, fy) = fine.to_local(easting, northing);
    let z = fine.height(fx, fy).unwrap();
    assert!((z - dem.height(x, y).unwrap()).abs() < 0.05, "{z}");
}

#[test]
fn mola_reads_olympus_mons_and_label_extremes() {
    let Some(lbl) = data_file_or_skip("mola/megt90n000cb.lbl") else { return };
    let mola = GlobalDem::open(&lbl).unwrap();
    assert_eq!((mola.image.lines, mola.image.line_samples), (720, 1440));
    assert_eq!(mola.pixels_per_degree, 4.0);
    let olympus = mola.height_at_latlon(18.65, 226.2).unwrap();
    assert!((olympus - 20009.0).abs() < 500.0, "Olympus Mons {olympus}");
    // Longitude wraps: 226.2 E is -133.8 E.
    assert_eq!(mola.height_at_latlon(18.65, -133.8), Some(olympus));
    // The label states the extremes in its IMAGE description.
    let description = mola.image.label.block("IMAGE").unwrap().get_str("DESCRIPTION").unwrap();
    let tail =
        description.split("maximum topography observations for the entire data set are").nth(1).unwrap();
    let words: Vec<&str> = tail.split_whitespace().collect();
    let (label_min, label_max): (f32, f32) = (words[0].parse().unwrap(), words[2].parse().unwrap());
    assert_eq!((label_min, label_max), (-8068.0, 21134.0));
    assert_eq!(mola.min_max(), Some((label_min, label_max)));
    assert_eq!(mola.image.label_min_max(), None); // no MINIMUM/MAXIMUM keywords in this label
    // The pole rows exist; latitudes past them do not.
    assert!(mola.height_at_latlon(90.0, 0.0).is_some());
    assert!(mola.height_at_latlon(90.5, 0.0).is_none());
}

#[test]
fn navcam_image_and_camera_model() {
    let Some(path) = data_file_or_skip("gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG") else {
        return;
    };
    let image = Pds3Image::open(&path).unwrap();
    assert_eq!((image.lines, image.line_samples, image.sample_bits), (1024, 1024, 16));
    let (lo, hi) = image.min_max().unwrap();
    assert!(lo >= 0.0 && hi <= 4095.0, "12-bit range: {lo}..{hi}");
    assert!(hi > 255.0, "more than 8 bits used: {hi}");
    assert_eq!(image.label.get("RECORD_BYTES").and_then(|v| v.as_f64()), Some(2048.0));
    assert_eq!(image.label.get("^IMAGE").and_then(|v| v.as_f64()), Some(23.0));
    let flat = image.label.flatten();
    assert!(flat.iter().any(|(k, v)| k == "IMAGE.SAMPLE_TYPE" && v.as_str() == Some("MSB_INTEGER")));
    let cahvor = image.label.cahvor().unwrap();
    // A is a unit vector and the image centre (H.A, V.A) lies near the middle of the frame.
    let a = cahvor.a;
    assert!(((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt() - 1.0).abs() < 1e-4);
    let (hc, vc) = cahvor.image_centre();
    assert!((hc - 511.5).abs() < 30.0 && (vc - 511.5).abs() < 30.0, "{hc} {vc}");
    let p = [cahvor.c[0] + 5.0 * a[0], cahvor.c[1] + 5.0 * a[1], cahvor.c[2] + 5.0 * a[2]];
    let (s, l) = cahvor.project(p).unwrap();
    assert!((s - hc).abs() < 2.0 && (l - vc).abs() < 2.0);
}

/// A big-endian int16 3x2 image with values line*10 + sample - 5.
fn pds3_pixels() -> Vec<u8> {
    (0..2i16).flat_map(|l| (0..3i16).map(move |s| l * 10 + s - 5)).flat_map(|v| v.to_be_bytes()).collect()
}

const IMAGE_OBJECT: &str = "OBJECT = IMAGE\n LINES = 2\n LINE_SAMPLES = 3\n SAMPLE_TYPE = MSB_INTEGER\n \
                            SAMPLE_BITS = 16\n SCALING_FACTOR = 0.5\n OFFSET = 100\n MISSING_CONSTANT = 6\nEND_OBJECT = IMAGE\nEND\n";

fn assert_synthetic(image: &Pds3Image) {
    // value = raw * 0.5 + 100; raw 6 (line 1, sample 1) is missing.
    assert_eq!(image.value(0, 0), Some(-5.0 * 0.5 + 100.0));
    assert_eq!(image.value(1, 2), Some(7.0 * 0.5 + 100.0));
    assert!(image.value(1, 1).unwrap().is_nan());
    assert_eq!(image.value(2, 0), None);
}

#[test]
fn pds3_pointer_forms_and_case_insensitive_names() {
    let dir = scratch("pds3");
    // Detached label naming the data file in upper case; the file on disk is lower case.
    std::fs::write(dir.join("tile.img"), pds3_pixels()).unwrap();
    let label = format!("PDS_VERSION_ID = PDS3\nRECORD_BYTES = 6\n^IMAGE = \"TILE.IMG\"\n{IMAGE_OBJECT}");
    std::fs::write(dir.join("tile.lbl"), label).unwrap();
    assert_synthetic(&Pds3Image::open(dir.join("tile.lbl")).unwrap());

    // ("FILE", record): record 3 of 6 bytes starts at byte 12.
    let mut padded = vec![0xAB; 12];
    padded.extend(pds3_pixels());
    std::fs::write(dir.join("padded.dat"), &padded).unwrap();
    let label = format!("RECORD_BYTES = 6\n^IMAGE = (\"PADDED.DAT\", 3)\n{IMAGE_OBJECT}");
    std::fs::write(dir.join("rec.lbl"), label).unwrap();
    assert_synthetic(&Pds3Image::open(dir.join("rec.lbl")).unwrap());
    let label = format!("RECORD_BYTES = 6\n^IMAGE = (\"padded.dat\", 13 <BYTES>)\n{IMAGE_OBJECT}");
    std::fs::write(dir.join("bytes.lbl"), label).unwrap();
    assert_synthetic(&Pds3Image::open(dir.join("bytes.lbl")).unwrap());

    // Attached label: 2 label records of 128 bytes, image at record 3.
    let mut text =
        format!("PDS_VERSION_ID = PDS3\nRECORD_BYTES = 128\nLABEL_RECORDS = 2\n^IMAGE = 3\n{IMAGE_OBJECT}")
            .into_bytes();
    assert!(text.len() <= 256);
    text.resize(256, b' ');
    text.extend(pds3_pixels());
    std::fs::write(dir.join("attached.img"), &text).unwrap();
    assert_synthetic(&Pds3Image::open(dir.join("attached.img")).unwrap());
    // The same with a byte pointer (1-based: byte 257 is offset 256).
    let mut text = format!("PDS_VERSION_ID = PDS3\nRECORD_BYTES = 128\n^IMAGE = 257 <BYTES>\n{IMAGE_OBJECT}")
        .into_bytes();
    text.resize(256, b' ');
    text.extend(pds3_pixels());
    std::fs::write(dir.join("attached_bytes.img"), &text).unwrap();
    assert_synthetic(&Pds3Image::open(dir.join("attached_bytes.img")).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pds3_errors_name_file_and_field() {
    let dir = scratch("pds3-errors");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // Data file shorter than the label says.
    std::fs::write(dir.join("short.img"), &pds3_pixels()[..7]).unwrap();
    let p = write("short.lbl", &format!("RECORD_BYTES = 6\n^IMAGE = \"SHORT.IMG\"\n{IMAGE_OBJECT}"));
    let err = Pds3Image::open(&p).unwrap_err();
    assert!(matches!(err, LoadError::Truncated { needed: 12, actual: 7, .. }), "{err}");
    assert!(err.to_string().contains("short.img"), "{err}");
    // Missing keyword.
    let p =
        write("nolines.lbl", "^IMAGE = \"SHORT.IMG\"\nOBJECT = IMAGE\n LINE_SAMPLES = 3\nEND_OBJECT\nEND\n");
    let err = Pds3Image::open(&p).unwrap_err();
    assert!(err.to_string().contains("IMAGE.LINES"), "{err}");
    assert_eq!(err.file(), p.as_path());
    // Unknown sample type.
    let p = write(
        "vax.lbl",
        &format!("^IMAGE = \"SHORT.IMG\"\n{}", IMAGE_OBJECT.replace("MSB_INTEGER", "VAX_REAL")),
    );
    assert!(Pds3Image::open(&p).unwrap_err().to_string().contains("VAX_REAL"));
    // Missing data file.
    let p = write("gone.lbl", &format!("^IMAGE = \"GONE.IMG\"\n{IMAGE_OBJECT}"));
    assert!(Pds3Image::open(&p).unwrap_err().to_string().contains("GONE.IMG"));
    // Record pointer without RECORD_BYTES.
    let p = write("norec.lbl", &format!("^IMAGE = 2\n{IMAGE_OBJECT}"));
    assert!(Pds3Image::open(&p).unwrap_err().to_string().contains("RECORD_BYTES"));
    // Garbage bytes are a syntax error, not a panic.
    std::fs::write(dir.join("garbage.img"), [0x93u8, 0xff, 0x00, 0x3d, 0x3d, 0x28, 0x22]).unwrap();
    assert!(Pds3Label::open(dir.join("garbage.img")).is_err());
    assert!(matches!(Pds3Image::open(dir.join("nothing.img")), Err(LoadError::Io { .. })));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A GeoTIFF of `rows` x `cols` samples written with the tiff crate's encoder.
fn write_tiff<C: colortype::ColorType>(
    cols: u32,
    rows: u32,
    data: &[C::Inner],
    geo: bool,
    nodata: Option<&str>,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut buf = Cursor::new(Vec::new());
    let mut enc = TiffEncoder::new(&mut buf).unwrap();
    let mut image = enc.new_image::<C>(cols, rows).unwrap();
    image.rows_per_strip(1).unwrap(); // one strip per row: many strips
    if geo {
        image.encoder().write_tag(Tag::ModelPixelScaleTag, &[0.5f64, 0.5, 0.0][..]).unwrap();
        image
            .encoder()
            .write_tag(Tag::ModelTiepointTag, &[0.0f64, 0.0, 0.0, 1000.0, 2000.0, 0.0][..])
            .unwrap();
    }
    if let Some(nd) = nodata {
        image.encoder().write_tag(Tag::GdalNodata, nd).unwrap();
    }
    image.write_data(data).unwrap();
    buf.into_inner()
}

#[test]
fn geotiff_rows_flip_and_georeference_for_each_sample_type() {
    // Image row 0 (north) holds 0, 1, 2; row 1 holds 10, 11, 12.
    let check = |dem: Dem| {
        assert_eq!((dem.geometry().cols, dem.geometry().rows), (3, 2));
        assert_eq!(*dem.heights.get(0, 1), 0.0); // north row is grid row 1
        assert_eq!(*dem.heights.get(2, 0), 12.0);
        // NW corner of the image is E 1000, N 2000; the SW corner is 1 m (2 rows) further south.
        assert_eq!((dem.geo.easting, dem.geo.northing), (1000.0, 1999.0));
        assert_eq!(dem.resolution(), 0.5);
    };
    let f: Vec<f32> = vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0];
    let bytes = write_tiff::<colortype::Gray32Float>(3, 2, &f, true, None);
    check(io::parse_geotiff(Path::new("f32.tif"), &bytes).unwrap());
    let i: Vec<i16> = vec![0, 1, 2, 10, 11, 12];
    let bytes = write_tiff::<colortype::GrayI16>(3, 2, &i, true, None);
    check(io::parse_geotiff(Path::new("i16.tif"), &bytes).unwrap());
    let u: Vec<u16> = vec![0, 1, 2, 10, 11, 12];
    let bytes = write_tiff::<colortype::Gray16>(3, 2, &u, true, None);
    check(io::parse_geotiff(Path::new("u16.tif"), &bytes).unwrap());

    // GDAL_NODATA samples become NaN.
    let with_hole: Vec<i16> = vec![0, -32767, 2, 10, 11, 12];
    let bytes = write_tiff::<colortype::GrayI16>(3, 2, &with_hole, true, Some("-32767"));
    let dem = io::parse_geotiff(Path::new("nodata.tif"), &bytes).unwrap();
    assert!(dem.heights.get(1, 1).is_nan());
    assert_eq!(dem.min_max(), Some((0.0, 12.0)));
}

#[test]
fn geotiff_without_georeference_names_the_tag() {
    let f: Vec<f32> = vec![1.0; 4];
    let bytes = write_tiff::<colortype::Gray32Float>(2, 2, &f, false, None);
    let err = io::parse_geotiff(Path::new("missionDEM.tif"), &bytes).unwrap_err();
    assert_eq!(err.to_string(), "missionDEM.tif: GeoTIFF tag ModelPixelScale (33550) missing");
}

#[test]
fn corrupt_geotiffs_give_errors_not_panics() {
    let original = match data_file_or_skip("gale/missionDEM.tif") {
        Some(p) => std::fs::read(p).unwrap(),
        None => write_tiff::<colortype::Gray32Float>(64, 64, &vec![1.0f32; 64 * 64], true, None),
    };
    let name = Path::new("corrupt.tif");
    // Garbage.
    assert!(io::parse_geotiff(name, b"this is not a tiff at all").is_err());
    assert!(io::parse_geotiff(name, &[]).is_err());
    // Truncations at many lengths, through the header, directory and strips.
    for cut in (0..original.len()).step_by(original.len() / 97 + 1).chain([8, 16, original.len() - 1]) {
        assert!(io::parse_geotiff(name, &original[..cut]).is_err(), "cut at {cut} loaded");
    }
    // Seeded byte flips: any outcome but a panic.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..200 {
        let mut bytes = original.clone();
        for _ in 0..8 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let at = (state % 4096.min(bytes.len() as u64)) as usize;
            bytes[at] ^= (state >> 32) as u8 | 1;
        }
        let _ = io::parse_geotiff(name, &bytes);
    }
    // Via the file path, the error names the file.
    let dir = scratch("tiff");
    let path = dir.join("truncated.tif");
    std::fs::write(&path, &original[..original.len() / 2]).unwrap();
    let err = io::load_geotiff(&path).unwrap_err();
    assert!(err.to_string().contains("truncated.tif"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn npy_round_trip_and_hand_written_headers() {
    let dir = scratch("npy");
    // Hand-built version-1 big-endian file: 2 rows x 3 cols, array row 0 = north.
    let header = "{'descr': '>f4', 'fortran_order': False, 'shape': (2, 3), }";
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    let pad = 64 - (10 + header.len() + 1) % 64;
    bytes.extend_from_slice(&((header.len() + pad + 1) as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend(std::iter::repeat_n(b' ', pad));
    bytes.push(b'\n');
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    let path = dir.join("hand.npy");
    std::fs::write(&path, &bytes).unwrap();
    let dem = io::load_npy(&path, 0.25).unwrap();
    assert_eq!((dem.geometry().cols, dem.geometry().rows, dem.resolution()), (3, 2, 0.25));
    assert_eq!(dem.heights.data, vec![4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);

    // Version 2 header (4-byte length), little-endian.
    let mut v2 = b"\x93NUMPY\x02\x00".to_vec();
    let header = header.replace(">f4", "<f4");
    v2.extend_from_slice(&(header.len() as u32 + 1).to_le_bytes());
    v2.extend_from_slice(header.as_bytes());
    v2.push(b'\n');
    for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
        v2.extend_from_slice(&v.to_le_bytes());
    }
    let dem2 = io::parse_npy(Path::new("v2.npy"), &v2, 0.25).unwrap();
    assert_eq!(dem2.heights.data, dem.heights.data);

    // Our writer and reader agree.
    let mut grid = Dem::flat(5, 4, 0.1, 0.0);
    for (i, h) in grid.heights.data.iter_mut().enumerate() {
        *h = i as f32 * 0.5 - 3.0;
    }
    let out = dir.join("round.npy");
    io::save_npy(&out, &grid).unwrap();
    assert_eq!(io::load_npy(&out, 0.1).unwrap(), grid);

    // Errors: truncated data, wrong dtype, 3-D, Fortran order, garbage.
    let name = Path::new("bad.npy");
    let msg = |b: &[u8]| io::parse_npy(name, b, 1.0).unwrap_err().to_string();
    // Same-length edits of the header keep its declared length valid.
    let edit = |from: &str, to: &str| {
        assert_eq!(from.len(), to.len());
        let at = bytes.windows(from.len()).position(|w| w == from.as_bytes()).unwrap();
        let mut b = bytes.clone();
        b[at..at + to.len()].copy_from_slice(to.as_bytes());
        b
    };
    assert!(msg(&bytes[..bytes.len() - 1]).contains("truncated"));
    assert!(msg(&edit(">f4", "<i2")).contains("<i2"));
    assert!(msg(&edit("(2, 3)", "(6,)  ")).contains("2-D"));
    assert!(msg(&edit("False", "True ")).contains("fortran"));
    assert!(msg(b"garbage garbage").contains("magic"));
    assert!(msg(&bytes[..9]).contains("magic"));
    let _ = std::fs::remove_dir_all(&dir);
}
