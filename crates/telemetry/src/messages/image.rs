//! `/camera/NAME`: camera images as Foxglove's `foxglove.RawImage`, so Foxglove's Image panel
//! shows them without a converter.
//!
//! The rover's cameras are 12-bit; the log stores them losslessly as `mono16` with the DN
//! shifted to the top of the 16 bits, which is how a 16-bit viewer expects the full scale.

use crate::base64;
use rovernav_bus::schema::titled_schema_of;
use rovernav_core::CameraImage;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The topic of a camera's images.
pub fn camera_topic(camera: &str) -> String {
    format!("/camera/{camera}")
}

/// A time as Foxglove's schemas write it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct TimeMsg {
    /// Whole seconds.
    pub sec: u32,
    /// Nanoseconds within the second.
    pub nsec: u32,
}

/// `foxglove.RawImage`: one uncompressed image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RawImageMsg {
    /// Time of exposure (simulation time).
    pub timestamp: TimeMsg,
    /// The camera's frame (its name).
    pub frame_id: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel encoding: `mono16`, little-endian.
    pub encoding: String,
    /// Bytes per row.
    pub step: u32,
    /// Pixel bytes, base64.
    #[schemars(extend("contentEncoding" = "base64"))]
    pub data: String,
}

impl RawImageMsg {
    /// The message of a camera image.
    pub fn of(image: &CameraImage) -> Self {
        let t = image.t.max(0.0);
        let shift = 16u32.saturating_sub(u32::from(image.bits.clamp(1, 16)));
        let raw: Vec<u8> = image
            .pixels
            .iter()
            .flat_map(|&v| (u32::from(v) << shift).min(65535).to_le_bytes()[..2].to_vec())
            .collect();
        Self {
            timestamp: TimeMsg { sec: t.floor() as u32, nsec: ((t - t.floor()) * 1e9) as u32 },
            frame_id: image.camera.clone(),
            width: image.width,
            height: image.height,
            encoding: "mono16".into(),
            step: image.width * 2,
            data: base64::encode(&raw),
        }
    }

    /// The 16-bit pixel values back, row-major; the error names the field that does not fit.
    pub fn pixels(&self) -> Result<Vec<u16>, String> {
        if self.encoding != "mono16" {
            return Err(format!("field `encoding`: expected mono16, found {}", self.encoding));
        }
        let raw = base64::decode(&self.data).map_err(|e| format!("field `data`: {e}"))?;
        let expected = self.step as usize * self.height as usize;
        if raw.len() != expected || self.step != self.width * 2 {
            return Err(format!(
                "field `data`: {} bytes for {}x{} mono16",
                raw.len(),
                self.width,
                self.height
            ));
        }
        Ok(raw.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect())
    }

    /// The JSON Schema, derived, under Foxglove's well-known name `foxglove.RawImage` (the
    /// fields are Foxglove's, so its Image panel shows the channel natively).
    pub fn schema() -> Value {
        titled_schema_of::<Self>("foxglove.RawImage")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::schema::check;

    #[test]
    fn twelve_bit_images_round_trip_at_full_scale_and_match_the_schema() {
        let image = CameraImage {
            camera: "navcam_left".into(),
            t: 12.25,
            width: 3,
            height: 2,
            bits: 12,
            pixels: vec![0, 1, 4095, 2048, 7, 100],
            ..CameraImage::default()
        };
        let msg = RawImageMsg::of(&image);
        assert_eq!((msg.timestamp.sec, msg.timestamp.nsec), (12, 250_000_000));
        let back = msg.pixels().unwrap();
        assert_eq!(back, image.pixels.iter().map(|&v| v << 4).collect::<Vec<_>>());
        let value = serde_json::to_value(&msg).unwrap();
        check(&RawImageMsg::schema(), &value).unwrap();
        let mut short = msg.clone();
        short.height = 3;
        assert!(short.pixels().unwrap_err().contains("data"));
    }
}
