//! `foxglove.CompressedImage` on `/camera/NAME`: camera images as lossless PNG, which Foxglove's
//! Image panel shows natively.
//!
//! The rover's cameras are 12-bit; the PNG is 16-bit greyscale with the DN shifted to the top of
//! the 16 bits, so a viewer shows the full scale and the DN comes back by shifting down.

use super::TimeMsg;
use crate::base64;
use rovernav_core::CameraImage;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The topic of a camera's images.
pub fn camera_topic(camera: &str) -> String {
    format!("/camera/{camera}")
}

/// `foxglove.CompressedImage`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CompressedImageMsg {
    /// Time of exposure (simulated).
    pub timestamp: TimeMsg,
    /// The camera (its name).
    pub frame_id: String,
    /// The PNG file, base64.
    #[schemars(extend("contentEncoding" = "base64"))]
    pub data: String,
    /// Image format: `png`.
    pub format: String,
}

impl CompressedImageMsg {
    /// The message of a camera image; the error says why it could not be encoded.
    pub fn of(image: &CameraImage) -> Result<Self, String> {
        let expected = image.width as usize * image.height as usize;
        if image.pixels.len() != expected || expected == 0 {
            return Err(format!(
                "camera `{}`: {} pixels for {}x{}",
                image.camera,
                image.pixels.len(),
                image.width,
                image.height
            ));
        }
        let shift = 16u32.saturating_sub(u32::from(image.bits.clamp(1, 16)));
        let samples: Vec<u8> = image
            .pixels
            .iter()
            .flat_map(|&v| ((u32::from(v) << shift).min(65535) as u16).to_be_bytes())
            .collect();
        let mut png_bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut png_bytes, image.width, image.height);
            encoder.set_color(png::ColorType::Grayscale);
            encoder.set_depth(png::BitDepth::Sixteen);
            let mut writer =
                encoder.write_header().map_err(|e| format!("camera `{}`: PNG: {e}", image.camera))?;
            writer.write_image_data(&samples).map_err(|e| format!("camera `{}`: PNG: {e}", image.camera))?;
        }
        Ok(Self {
            timestamp: TimeMsg::of_seconds(image.t),
            frame_id: image.camera.clone(),
            data: base64::encode(&png_bytes),
            format: "png".into(),
        })
    }

    /// The 16-bit pixel values back, row-major, with the width and height; the error names the
    /// field that does not decode.
    pub fn pixels(&self) -> Result<(u32, u32, Vec<u16>), String> {
        if self.format != "png" {
            return Err(format!("field `format`: expected png, found {}", self.format));
        }
        let bytes = base64::decode(&self.data).map_err(|e| format!("field `data`: {e}"))?;
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().map_err(|e| format!("field `data`: PNG: {e}"))?;
        let mut buf = vec![0; reader.output_buffer_size().ok_or("field `data`: PNG too large")?];
        let info = reader.next_frame(&mut buf).map_err(|e| format!("field `data`: PNG: {e}"))?;
        if info.bit_depth != png::BitDepth::Sixteen || info.color_type != png::ColorType::Grayscale {
            return Err(format!(
                "field `data`: {:?} {:?}, expected 16-bit greyscale",
                info.color_type, info.bit_depth
            ));
        }
        let pixels =
            buf[..info.buffer_size()].chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
        Ok((info.width, info.height, pixels))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::schema::{check, titled_schema_of};

    #[test]
    fn twelve_bit_images_round_trip_through_png_at_full_scale() {
        let image = CameraImage {
            camera: "navcam_left".into(),
            t: 12.25,
            width: 3,
            height: 2,
            bits: 12,
            pixels: vec![0, 1, 4095, 2048, 7, 100],
            ..CameraImage::default()
        };
        let msg = CompressedImageMsg::of(&image).unwrap();
        assert_eq!(msg.timestamp, TimeMsg { sec: 12, nsec: 250_000_000 });
        let (w, h, back) = msg.pixels().unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(back, image.pixels.iter().map(|&v| v << 4).collect::<Vec<_>>());
        // The PNG signature: any PNG reader opens it.
        let bytes = base64::decode(&msg.data).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        check(
            &titled_schema_of::<CompressedImageMsg>("foxglove.CompressedImage"),
            &serde_json::to_value(&msg).unwrap(),
        )
        .unwrap();
        let short = CameraImage { height: 3, ..image };
        assert!(CompressedImageMsg::of(&short).unwrap_err().contains("6 pixels for 3x3"));
    }
}
