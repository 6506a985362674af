//! NumPy `.npy` height arrays (format versions 1, 2 and 3; 2-D, C order; little- or big-endian
//! float32 or float64).
//!
//! Array row 0 is taken as the northern row, as in an image, so rows are flipped into `Grid2`
//! order (row 0 south); `save_npy` writes the same way round, north first.

use std::path::Path;

use rovernav_core::{Grid2, GridGeometry};

use super::{LoadError, read_file};
use crate::dem::Dem;

const MAGIC: &[u8] = b"\x93NUMPY";
/// Largest header accepted (bytes): real headers are a few hundred bytes.
const MAX_HEADER: usize = 1 << 20;

/// Loads a 2-D float `.npy` as a DEM with the given cell size (m); row 0 of the array is north.
pub fn load_npy(path: impl AsRef<Path>, resolution: f64) -> Result<Dem, LoadError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_npy(path, &bytes, resolution)
}

/// Parses `.npy` bytes held in memory; `file` is only used to name it in errors.
pub fn parse_npy(file: &Path, bytes: &[u8], resolution: f64) -> Result<Dem, LoadError> {
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(LoadError::invalid(file, "resolution", format!("{resolution} is not positive")));
    }
    if bytes.len() < 10 || &bytes[..6] != MAGIC {
        return Err(LoadError::invalid(file, "magic", "not a .npy file (no \\x93NUMPY prefix)"));
    }
    let major = bytes[6];
    let (header_len, header_start) = match major {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 => {
            let b = bytes.get(8..12).ok_or_else(|| truncated(file, "header length", 4, 8, bytes.len()))?;
            (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize, 12)
        }
        v => return Err(LoadError::unsupported(file, format!("format version {v}"))),
    };
    if header_len > MAX_HEADER {
        return Err(LoadError::invalid(file, "header length", format!("{header_len} bytes")));
    }
    let header = bytes
        .get(header_start..header_start + header_len)
        .ok_or_else(|| truncated(file, "header", header_len, header_start, bytes.len()))?;
    let header =
        std::str::from_utf8(header).map_err(|_| LoadError::invalid(file, "header", "not UTF-8 text"))?;

    let descr = dict_value(header, "descr").ok_or_else(|| LoadError::missing(file, "descr"))?;
    let descr = descr.trim().trim_matches(|c| c == '\'' || c == '"');
    let (big_endian, width) = match descr {
        "<f4" | "=f4" => (false, 4),
        ">f4" => (true, 4),
        "<f8" | "=f8" => (false, 8),
        ">f8" => (true, 8),
        other => return Err(LoadError::unsupported(file, format!("descr {other:?} (need f4 or f8)"))),
    };
    let fortran =
        dict_value(header, "fortran_order").ok_or_else(|| LoadError::missing(file, "fortran_order"))?;
    match fortran.trim() {
        "False" => {}
        "True" => return Err(LoadError::unsupported(file, "fortran_order True")),
        other => return Err(LoadError::invalid(file, "fortran_order", format!("{other:?}"))),
    }
    let shape = dict_value(header, "shape").ok_or_else(|| LoadError::missing(file, "shape"))?;
    let dims: Vec<usize> = shape
        .trim()
        .trim_start_matches('(')
        .trim_end_matches(')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| LoadError::invalid(file, "shape", format!("{shape:?} is not a tuple of sizes")))?;
    let [rows, cols] = dims[..] else {
        return Err(LoadError::unsupported(file, format!("shape {shape} (need 2-D)")));
    };
    if rows == 0 || cols == 0 {
        return Err(LoadError::invalid(file, "shape", format!("{shape} has no cells")));
    }
    rovernav_core::limits::checked_elements(&[rows as u64, cols as u64], 4, None)
        .map_err(|why| LoadError::invalid(file, "shape", why))?;
    let data_start = header_start + header_len;
    let needed = rows.checked_mul(cols).and_then(|n| n.checked_mul(width));
    let needed = needed.ok_or_else(|| LoadError::invalid(file, "shape", "size overflows"))?;
    let body = bytes
        .get(data_start..)
        .filter(|b| b.len() >= needed)
        .ok_or_else(|| truncated(file, "array data", needed, data_start, bytes.len()))?;

    let value = |i: usize| -> f32 {
        let b = &body[i * width..(i + 1) * width];
        match (width, big_endian) {
            (4, false) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            (4, true) => f32::from_be_bytes([b[0], b[1], b[2], b[3]]),
            (_, false) => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f32,
            (_, true) => f64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f32,
        }
    };
    let mut data = Vec::with_capacity(rows * cols);
    for array_row in (0..rows).rev() {
        data.extend((0..cols).map(|c| value(array_row * cols + c)));
    }
    let geometry = GridGeometry { cols, rows, resolution, origin_x: 0.0, origin_y: 0.0 };
    Ok(Dem::from_grid(Grid2 { geometry, data }))
}

/// The bytes of a version-1 little-endian float32 `.npy` of a DEM's heights, north row first.
pub fn to_npy_bytes(dem: &Dem) -> Vec<u8> {
    let g = dem.geometry();
    let dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}), }}", g.rows, g.cols);
    // Magic (6) + version (2) + length (2) + dict + newline, padded to a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    let padding = (64 - unpadded % 64) % 64;
    let header_len = dict.len() + padding + 1;
    let mut out = Vec::with_capacity(10 + header_len + 4 * g.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(header_len as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend(std::iter::repeat_n(b' ', padding));
    out.push(b'\n');
    for row in dem.heights.data.chunks_exact(g.cols.max(1)).rev() {
        for v in row {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Writes a DEM's heights as a float32 `.npy`, north row first.
pub fn save_npy(path: impl AsRef<Path>, dem: &Dem) -> Result<(), LoadError> {
    let path = path.as_ref();
    std::fs::write(path, to_npy_bytes(dem)).map_err(|e| LoadError::io(path, e))
}

fn truncated(file: &Path, what: &str, needed: usize, offset: usize, actual: usize) -> LoadError {
    LoadError::Truncated {
        file: file.to_path_buf(),
        what: what.into(),
        needed: needed as u64,
        offset: offset as u64,
        actual: actual as u64,
    }
}

/// The raw text of a key's value in a Python dict literal: up to the next top-level comma.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let at = header.find(&format!("'{key}'")).or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = &header[at + key.len() + 2..];
    let rest = rest.trim_start().strip_prefix(':')?;
    let mut depth = 0usize;
    for (i, ch) in rest.char_indices() {
        match ch {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            ',' | '}' if depth == 0 => return Some(&rest[..i]),
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dict_values_are_found_past_nested_commas() {
        let h = "{'descr': '>f4', 'fortran_order': False, 'shape': (3, 4), }";
        assert_eq!(dict_value(h, "descr").map(str::trim), Some("'>f4'"));
        assert_eq!(dict_value(h, "shape").map(str::trim), Some("(3, 4)"));
        assert_eq!(dict_value(h, "missing"), None);
    }

    #[test]
    fn written_header_is_64_byte_aligned() {
        let bytes = to_npy_bytes(&Dem::flat(3, 2, 1.0, 0.0));
        let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        assert_eq!(bytes[10 + header_len - 1], b'\n');
        assert_eq!(bytes.len(), 10 + header_len + 6 * 4);
    }
}
