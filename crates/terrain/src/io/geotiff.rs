//! GeoTIFF elevation models (single-band float or integer samples, strips or tiles).
//!
//! The georeference comes from ModelPixelScale (33550) + ModelTiepoint (33922), or from a
//! rotation-free ModelTransformation (34264); GeoKeyDirectory (34735) gives the raster type
//! (pixel-is-area or pixel-is-point) and a CRS description; GDAL_NODATA (42113) marks missing
//! samples, which become NaN. Image row 0 is north, so rows are flipped into `Grid2` order
//! (row 0 south), and the local frame's (0, 0) is the south-west corner of the image.

use std::io::Cursor;
use std::path::Path;

use rovernav_core::{Grid2, GridGeometry};
use tiff::ColorType;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

use super::{LoadError, read_file};
use crate::dem::{Dem, GeoReference};

const GT_RASTER_TYPE_KEY: u16 = 1025;
const GT_CITATION_KEY: u16 = 1026;
const GEOGRAPHIC_TYPE_KEY: u16 = 2048;
const PROJECTED_CS_TYPE_KEY: u16 = 3072;
const PCS_CITATION_KEY: u16 = 3073;
const RASTER_PIXEL_IS_POINT: u16 = 2;

/// Loads a GeoTIFF DEM from a file.
pub fn load_geotiff(path: impl AsRef<Path>) -> Result<Dem, LoadError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_geotiff(path, &bytes)
}

/// Parses a GeoTIFF DEM held in memory; `file` is only used to name it in errors.
pub fn parse_geotiff(file: &Path, bytes: &[u8]) -> Result<Dem, LoadError> {
    let tiff_err = |source| LoadError::Tiff { file: file.to_path_buf(), source };
    let mut decoder = Decoder::new(Cursor::new(bytes)).map_err(tiff_err)?;
    let (width, height) = decoder.dimensions().map_err(tiff_err)?;
    let (cols, rows) = (width as usize, height as usize);
    if cols == 0 || rows == 0 {
        return Err(LoadError::invalid(file, "ImageWidth/ImageLength", "image has no pixels"));
    }
    // The heights grid (f32) this header asks for, against the memory ceiling, before decoding.
    rovernav_core::limits::checked_elements(&[rows as u64, cols as u64], 4, None)
        .map_err(|why| LoadError::invalid(file, "ImageWidth/ImageLength", why))?;
    match decoder.colortype().map_err(tiff_err)? {
        ColorType::Gray(_) => {}
        other => {
            return Err(LoadError::unsupported(file, format!("{other:?} pixels (need one band)")));
        }
    }

    let geokeys =
        decoder.find_tag_unsigned_vec::<u16>(Tag::GeoKeyDirectoryTag).map_err(tiff_err)?.unwrap_or_default();
    let ascii_params = match decoder.find_tag(Tag::GeoAsciiParamsTag).map_err(tiff_err)? {
        Some(v) => v.into_string().unwrap_or_default(),
        None => String::new(),
    };
    let pixel_is_point = geokey_short(&geokeys, GT_RASTER_TYPE_KEY) == Some(RASTER_PIXEL_IS_POINT);
    let crs = crs_description(&geokeys, &ascii_params);

    // West edge of column 0 and north edge of row 0, and the pixel size.
    let (west, north, res) = georeference(file, &mut decoder)?;
    let (west, north) = if pixel_is_point { (west - 0.5 * res, north + 0.5 * res) } else { (west, north) };

    let nodata = match decoder.find_tag(Tag::GdalNodata).map_err(tiff_err)? {
        Some(v) => {
            let text = v
                .into_string()
                .map_err(|_| LoadError::invalid(file, "GDAL_NODATA (42113)", "not an ASCII string"))?;
            let text = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            let value: f64 = text.parse().map_err(|_| {
                LoadError::invalid(file, "GDAL_NODATA (42113)", format!("not a number: {text:?}"))
            })?;
            Some(value)
        }
        None => None,
    };

    let image = decoder.read_image().map_err(tiff_err)?;
    let samples = to_f32(file, image)?;
    if samples.len() < cols * rows {
        return Err(LoadError::Truncated {
            file: file.to_path_buf(),
            what: "image samples".into(),
            needed: (cols * rows) as u64,
            offset: 0,
            actual: samples.len() as u64,
        });
    }

    let nodata_f32 = nodata.map(|v| v as f32);
    let mut data = Vec::with_capacity(cols * rows);
    for image_row in (0..rows).rev() {
        let row = &samples[image_row * cols..(image_row + 1) * cols];
        data.extend(row.iter().map(|&v| if Some(v) == nodata_f32 { f32::NAN } else { v }));
    }
    let geometry = GridGeometry { cols, rows, resolution: res, origin_x: 0.0, origin_y: 0.0 };
    Ok(Dem {
        heights: Grid2 { geometry, data },
        nodata: nodata_f32,
        geo: GeoReference { crs, easting: west, northing: north - rows as f64 * res },
    })
}

/// (west edge of column 0, north edge of row 0, pixel size) from the georeferencing tags.
fn georeference<R: std::io::Read + std::io::Seek>(
    file: &Path,
    decoder: &mut Decoder<R>,
) -> Result<(f64, f64, f64), LoadError> {
    let tiff_err = |source| LoadError::Tiff { file: file.to_path_buf(), source };
    let read_f64s = |decoder: &mut Decoder<R>, tag: Tag| -> Result<Option<Vec<f64>>, LoadError> {
        match decoder.find_tag(tag).map_err(tiff_err)? {
            Some(v) => v
                .into_f64_vec()
                .map(Some)
                .map_err(|_| LoadError::invalid(file, tag_name(tag), "values are not numbers")),
            None => Ok(None),
        }
    };
    let scale = read_f64s(decoder, Tag::ModelPixelScaleTag)?;
    let tiepoint = read_f64s(decoder, Tag::ModelTiepointTag)?;
    let transform = read_f64s(decoder, Tag::ModelTransformationTag)?;

    if scale.is_none()
        && tiepoint.is_none()
        && let Some(m) = transform
    {
        return from_transformation(file, &m);
    }
    let scale = scale.ok_or(LoadError::MissingTag {
        file: file.to_path_buf(),
        name: "ModelPixelScale",
        code: 33550,
    })?;
    let tiepoint = tiepoint.ok_or(LoadError::MissingTag {
        file: file.to_path_buf(),
        name: "ModelTiepoint",
        code: 33922,
    })?;
    if scale.len() < 2 {
        return Err(LoadError::invalid(
            file,
            "ModelPixelScale (33550)",
            format!("{} values, need 3", scale.len()),
        ));
    }
    if tiepoint.len() < 6 {
        return Err(LoadError::invalid(
            file,
            "ModelTiepoint (33922)",
            format!("{} values, need 6", tiepoint.len()),
        ));
    }
    let (sx, sy) = (scale[0], scale[1]);
    check_square(file, "ModelPixelScale (33550)", sx, sy)?;
    if tiepoint.iter().take(6).any(|v| !v.is_finite()) {
        return Err(LoadError::invalid(file, "ModelTiepoint (33922)", "non-finite value"));
    }
    let (i, j, x, y) = (tiepoint[0], tiepoint[1], tiepoint[3], tiepoint[4]);
    Ok((x - i * sx, y + j * sy, sx))
}

/// Georeference from a 4x4 ModelTransformation without rotation.
fn from_transformation(file: &Path, m: &[f64]) -> Result<(f64, f64, f64), LoadError> {
    const FIELD: &str = "ModelTransformation (34264)";
    if m.len() < 16 {
        return Err(LoadError::invalid(file, FIELD, format!("{} values, need 16", m.len())));
    }
    if m[1] != 0.0 || m[4] != 0.0 {
        return Err(LoadError::unsupported(file, "rotated ModelTransformation (34264)"));
    }
    let (sx, sy) = (m[0], -m[5]);
    check_square(file, FIELD, sx, sy)?;
    if !(m[3].is_finite() && m[7].is_finite()) {
        return Err(LoadError::invalid(file, FIELD, "non-finite translation"));
    }
    Ok((m[3], m[7], sx))
}

fn check_square(file: &Path, field: &str, sx: f64, sy: f64) -> Result<(), LoadError> {
    if !(sx.is_finite() && sx > 0.0 && sy.is_finite() && sy > 0.0) {
        return Err(LoadError::invalid(file, field, format!("pixel size ({sx}, {sy}) not positive")));
    }
    if (sx - sy).abs() > 1e-9 * sx {
        return Err(LoadError::unsupported(file, format!("non-square pixels ({sx} x {sy}) in {field}")));
    }
    Ok(())
}

fn tag_name(tag: Tag) -> &'static str {
    match tag {
        Tag::ModelPixelScaleTag => "ModelPixelScale (33550)",
        Tag::ModelTiepointTag => "ModelTiepoint (33922)",
        Tag::ModelTransformationTag => "ModelTransformation (34264)",
        _ => "GeoTIFF tag",
    }
}

/// The SHORT value of a key in a GeoKeyDirectory (stored inline, location 0).
fn geokey_short(dir: &[u16], key: u16) -> Option<u16> {
    geokey_entry(dir, key).and_then(|e| (e[1] == 0).then_some(e[3]))
}

/// The ASCII value of a key (stored in GeoAsciiParams, location 34737).
fn geokey_ascii<'a>(dir: &[u16], key: u16, ascii: &'a str) -> Option<&'a str> {
    let e = geokey_entry(dir, key)?;
    if e[1] != 34737 {
        return None;
    }
    let (count, offset) = (e[2] as usize, e[3] as usize);
    let s = ascii.get(offset..offset + count)?;
    Some(s.trim_end_matches(['|', '\0']))
}

/// The 4-short entry (key, location, count, value/offset) of a key.
fn geokey_entry(dir: &[u16], key: u16) -> Option<&[u16]> {
    let n = *dir.get(3)? as usize;
    dir.get(4..)?.chunks_exact(4).take(n).find(|e| e[0] == key)
}

fn crs_description(dir: &[u16], ascii: &str) -> String {
    for key in [PCS_CITATION_KEY, GT_CITATION_KEY] {
        if let Some(s) = geokey_ascii(dir, key, ascii).filter(|s| !s.is_empty()) {
            return s.to_string();
        }
    }
    match (geokey_short(dir, PROJECTED_CS_TYPE_KEY), geokey_short(dir, GEOGRAPHIC_TYPE_KEY)) {
        (Some(code), _) if code != 32767 => format!("EPSG:{code}"),
        (_, Some(code)) if code != 32767 => format!("EPSG:{code}"),
        _ => "unknown".into(),
    }
}

fn to_f32(file: &Path, image: DecodingResult) -> Result<Vec<f32>, LoadError> {
    Ok(match image {
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::U32(v) => v.into_iter().map(|x| x as f32).collect(),
        other => {
            let kind = format!("{other:?}");
            let kind = kind.split('(').next().unwrap_or("unknown");
            return Err(LoadError::unsupported(file, format!("{kind} samples")));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geokey_lookup_reads_inline_and_ascii_keys() {
        // Header (version 1.1.0, 2 keys), then GTRasterType = 2 inline and a citation of
        // 5 characters at offset 0 of GeoAsciiParams.
        let dir = [1, 1, 0, 2, 1025, 0, 1, 2, 1026, 34737, 5, 0];
        assert_eq!(geokey_short(&dir, 1025), Some(2));
        assert_eq!(geokey_ascii(&dir, 1026, "Mars|"), Some("Mars"));
        assert_eq!(geokey_short(&dir, 3072), None);
        // A directory claiming more keys than it holds is read only as far as it goes.
        assert_eq!(geokey_short(&[1, 1, 0, 9, 1025, 0, 1, 1], 1025), Some(1));
        assert_eq!(crs_description(&dir, "Mars|"), "Mars");
    }
}
