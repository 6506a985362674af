//! How the core types cross a wire (the bus, the MCAP log): serde field codecs and their JSON
//! Schema forms, used by the `Serialize`, `Deserialize` and `JsonSchema` derives of the types.
//!
//! - JSON has no NaN or infinity: serde_json writes a non-finite `f64` as `null`, and the fields
//!   that may hold one (a faulty compass reads NaN, an unknown covariance is infinite) read
//!   `null` back as NaN with [`nan_from_null`]; their schema is "number or null".
//! - Point clouds and pixels travel as base64 of their little-endian bytes ([`points_base64`],
//!   [`pixels_base64`]): exact, a third larger than the bytes where a JSON number array is
//!   about three times larger; the schema marks them `contentEncoding: base64` as Foxglove's
//!   schemas mark bytes.

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use serde::{Deserialize, Deserializer, Serializer};

/// Reads a number, or `null` as NaN (the form serde_json writes a non-finite number in).
pub fn nan_from_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// [`nan_from_null`] for a 3x3 matrix.
pub fn nan_from_null_matrix<'de, D: Deserializer<'de>>(d: D) -> Result<[[f64; 3]; 3], D::Error> {
    let rows = <[[Option<f64>; 3]; 3]>::deserialize(d)?;
    Ok(rows.map(|row| row.map(|v| v.unwrap_or(f64::NAN))))
}

fn decode_base64<E: serde::de::Error>(text: &str, item_bytes: usize, what: &str) -> Result<Vec<u8>, E> {
    let bytes =
        STANDARD.decode(text.as_bytes()).map_err(|e| E::custom(format!("{what}: bad base64 ({e})")))?;
    if bytes.len() % item_bytes != 0 {
        return Err(E::custom(format!(
            "{what}: {} bytes is not a whole number of {item_bytes}-byte items",
            bytes.len()
        )));
    }
    Ok(bytes)
}

/// Points `[x, y, z]` (f32) as base64 of little-endian f32 triples, 12 bytes a point.
pub mod points_base64 {
    use super::*;

    /// Writes the points.
    pub fn serialize<S: Serializer>(points: &[[f32; 3]], s: S) -> Result<S::Ok, S::Error> {
        let bytes: Vec<u8> = points.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&STANDARD.encode(bytes))
    }

    /// Reads the points; the error says what does not fit.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f32; 3]>, D::Error> {
        let bytes = decode_base64(&String::deserialize(d)?, 12, "points")?;
        let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        Ok(bytes.chunks_exact(12).map(|p| [f(&p[0..4]), f(&p[4..8]), f(&p[8..12])]).collect())
    }
}

/// 16-bit pixels as base64 of their little-endian bytes.
pub mod pixels_base64 {
    use super::*;

    /// Writes the pixels.
    pub fn serialize<S: Serializer>(pixels: &[u16], s: S) -> Result<S::Ok, S::Error> {
        let bytes: Vec<u8> = pixels.iter().flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&STANDARD.encode(bytes))
    }

    /// Reads the pixels; the error says what does not fit.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u16>, D::Error> {
        let bytes = decode_base64(&String::deserialize(d)?, 2, "pixels")?;
        Ok(bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect())
    }
}

#[cfg(test)]
mod tests {
    use crate::{CameraImage, CameraKind, ImuSample, PointCloud, Wedge};

    #[test]
    fn points_and_pixels_keep_every_bit_and_nan_comes_back_from_null() {
        let cloud = PointCloud {
            camera: CameraKind::Lidar,
            origin: [0.1, 0.2, 0.3],
            wedge: Wedge { bearing: 0.5, half_angle: 0.3, min_range: 1.0, max_range: 4.0 },
            points: vec![[1.0 / 3.0, -f32::MIN_POSITIVE, f32::MAX], [0.1, 1e-40, -0.0]],
        };
        let text = serde_json::to_string(&cloud).unwrap();
        let back: PointCloud = serde_json::from_str(&text).unwrap();
        let bits = |c: &PointCloud| c.points.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&cloud));
        assert_eq!(back, cloud);
        let image = CameraImage {
            camera: "c".into(),
            t: 1.0,
            width: 2,
            height: 1,
            bits: 12,
            pixels: vec![0, 65535],
            pan: 0.5,
            tilt: -0.25,
        };
        let back: CameraImage = serde_json::from_str(&serde_json::to_string(&image).unwrap()).unwrap();
        assert_eq!(back, image);
        let imu = ImuSample { compass_yaw: f64::NAN, sun_yaw: Some(0.25), ..Default::default() };
        let text = serde_json::to_string(&imu).unwrap();
        assert!(text.contains("\"compass_yaw\":null"), "{text}");
        let back: ImuSample = serde_json::from_str(&text).unwrap();
        assert!(back.compass_yaw.is_nan());
        assert_eq!(back.sun_yaw, Some(0.25));
    }

    #[test]
    fn a_byte_count_that_is_not_whole_points_is_an_error_naming_the_field() {
        let text = r#"{"camera":"mast","origin":[0,0,0],"wedge":{"bearing":0,"half_angle":0,"min_range":0,"max_range":1},"points":"AAAAAA=="}"#;
        let err = serde_json::from_str::<PointCloud>(text).unwrap_err().to_string();
        assert!(err.contains("points: 4 bytes"), "{err}");
        let bad = text.replace("AAAAAA==", "A!");
        let err = serde_json::from_str::<PointCloud>(&bad).unwrap_err().to_string();
        assert!(err.contains("points: bad base64"), "{err}");
    }
}
