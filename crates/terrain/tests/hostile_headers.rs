//! Elevation-model headers that ask for more than the file holds or than memory allows are
//! refused with one line naming the file and the field, before anything that size is allocated.

use rovernav_terrain::io::parse_geotiff;
use std::path::Path;

/// A little-endian TIFF of one f32 band whose header declares `side` x `side` pixels in one
/// 4-byte strip.
fn tiff_declaring(side: u32) -> Vec<u8> {
    let entries: [(u16, u16, u32); 9] = [
        (256, 4, side),               // ImageWidth, LONG
        (257, 4, side),               // ImageLength
        (258, 3, 32),                 // BitsPerSample, SHORT
        (259, 3, 1),                  // Compression: none
        (262, 3, 1),                  // PhotometricInterpretation: black is zero
        (273, 4, 8 + 2 + 9 * 12 + 4), // StripOffsets: just after the IFD
        (277, 3, 1),                  // SamplesPerPixel
        (278, 4, side),               // RowsPerStrip
        (279, 4, 4),                  // StripByteCounts
    ];
    let mut b = b"II*\0".to_vec();
    b.extend_from_slice(&8u32.to_le_bytes());
    b.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, kind, value) in entries {
        b.extend_from_slice(&tag.to_le_bytes());
        b.extend_from_slice(&kind.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        if kind == 3 {
            b.extend_from_slice(&(value as u16).to_le_bytes());
            b.extend_from_slice(&[0, 0]);
        } else {
            b.extend_from_slice(&value.to_le_bytes());
        }
    }
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&1.5f32.to_le_bytes());
    b
}

#[test]
fn a_geotiff_declaring_a_huge_image_is_refused_before_decoding() {
    let e = parse_geotiff(Path::new("huge.tif"), &tiff_declaring(100_000)).expect_err("refused").to_string();
    assert!(e.contains("huge.tif") && e.contains("memory ceiling") && !e.contains('\n'), "{e}");
}

#[test]
fn the_same_header_at_a_sane_size_is_not_refused_for_its_size() {
    // One pixel: whatever else is wrong (no georeference), the size check passes.
    let e = parse_geotiff(Path::new("one.tif"), &tiff_declaring(1)).map(|_| ()).unwrap_err().to_string();
    assert!(!e.contains("memory ceiling"), "{e}");
}
