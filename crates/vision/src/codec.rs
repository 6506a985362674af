//! Image files: PDS3 EDR IMG (through the terrain crate's PDS3 reader), PNG, JPEG and PGM/PPM
//! (through the `image` crate) read into [`Grey8`], [`Grey16`] or [`Rgb8`]; PNG written.
//!
//! Every error names the file.

use std::path::{Path, PathBuf};

use ::image::{DynamicImage, ImageFormat, ImageReader};
use rovernav_terrain::io::{LoadError, Pds3Image, SampleType};
use thiserror::Error;

use crate::image::{Grey8, Grey16, GreyF32, Luma, Rgb8};

/// Why an image file could not be read or written.
#[derive(Debug, Error)]
pub enum CodecError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", .file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The `image` crate could not decode or encode the file.
    #[error("{}: {source}", .file.display())]
    Image {
        /// The file.
        file: PathBuf,
        /// The codec's error.
        source: ::image::ImageError,
    },
    /// The PDS3 reader rejected the file (its message names the file and field).
    #[error(transparent)]
    Pds3(#[from] LoadError),
    /// The file decodes, but to pixels this crate does not represent.
    #[error("{}: unsupported image: {what}", .file.display())]
    Unsupported {
        /// The file.
        file: PathBuf,
        /// What is unsupported.
        what: String,
    },
}

/// A decoded image of one of the pixel types rovernav uses.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyImage {
    /// 8-bit grey.
    Grey8(Grey8),
    /// Grey of up to 16 bits, with the number of significant bits (12 for the Navcam).
    Grey16 {
        /// The pixels.
        image: Grey16,
        /// Significant bits per pixel (values lie below 2^bits).
        bits: u32,
    },
    /// 8-bit RGB.
    Rgb8(Rgb8),
}

impl AnyImage {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        match self {
            Self::Grey8(i) => i.width(),
            Self::Grey16 { image, .. } => image.width(),
            Self::Rgb8(i) => i.width(),
        }
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        match self {
            Self::Grey8(i) => i.height(),
            Self::Grey16 { image, .. } => image.height(),
            Self::Rgb8(i) => i.height(),
        }
    }

    /// Significant bits per channel.
    pub fn bits(&self) -> u32 {
        match self {
            Self::Grey16 { bits, .. } => *bits,
            _ => 8,
        }
    }

    /// Grey values as floats on the image's own scale (RGB by Rec. 601 luma weights).
    pub fn to_grey_f32(&self) -> GreyF32 {
        match self {
            Self::Grey8(i) => {
                GreyF32::from_fn(i.width(), i.height(), |x, y| Luma([i.get_pixel(x, y)[0] as f32]))
            }
            Self::Grey16 { image, .. } => GreyF32::from_fn(image.width(), image.height(), |x, y| {
                Luma([image.get_pixel(x, y)[0] as f32])
            }),
            Self::Rgb8(i) => GreyF32::from_fn(i.width(), i.height(), |x, y| {
                let [r, g, b] = i.get_pixel(x, y).0;
                Luma([0.299 * r as f32 + 0.587 * g as f32 + 0.114 * b as f32])
            }),
        }
    }

    /// Grey values as 16-bit integers on the image's own scale (RGB by Rec. 601 luma).
    pub fn to_grey16(&self) -> Grey16 {
        match self {
            Self::Grey16 { image, .. } => image.clone(),
            other => {
                let f = other.to_grey_f32();
                Grey16::from_fn(f.width(), f.height(), |x, y| Luma([f.get_pixel(x, y)[0].round() as u16]))
            }
        }
    }

    /// An 8-bit grey version (16-bit images shifted down by `bits - 8`), for display.
    pub fn to_grey8(&self) -> Grey8 {
        match self {
            Self::Grey8(i) => i.clone(),
            Self::Grey16 { image, bits } => {
                let shift = bits.saturating_sub(8);
                Grey8::from_fn(image.width(), image.height(), |x, y| {
                    Luma([(image.get_pixel(x, y)[0] >> shift).min(255) as u8])
                })
            }
            Self::Rgb8(_) => {
                let f = self.to_grey_f32();
                Grey8::from_fn(f.width(), f.height(), |x, y| Luma([f.get_pixel(x, y)[0].round() as u8]))
            }
        }
    }
}

/// Reads an image file: `.img` (any case) as a PDS3 product, anything else by its content
/// (PNG, JPEG, PGM/PPM). Alpha is dropped; 16-bit RGB is reduced to 8 bits.
pub fn read_image(path: impl AsRef<Path>) -> Result<AnyImage, CodecError> {
    let path = path.as_ref();
    let is_pds = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("img"));
    if is_pds {
        let (image, bits) = read_pds3_grey16(path)?;
        return Ok(AnyImage::Grey16 { image, bits });
    }
    let reader = ImageReader::open(path).map_err(|source| CodecError::Io { file: path.into(), source })?;
    let reader =
        reader.with_guessed_format().map_err(|source| CodecError::Io { file: path.into(), source })?;
    let decoded = reader.decode().map_err(|source| CodecError::Image { file: path.into(), source })?;
    Ok(match decoded {
        DynamicImage::ImageLuma8(i) => AnyImage::Grey8(i),
        DynamicImage::ImageLumaA8(_) => AnyImage::Grey8(decoded.to_luma8()),
        DynamicImage::ImageLuma16(i) => AnyImage::Grey16 { image: i, bits: 16 },
        DynamicImage::ImageLumaA16(_) => AnyImage::Grey16 { image: decoded.to_luma16(), bits: 16 },
        DynamicImage::ImageRgb8(i) => AnyImage::Rgb8(i),
        DynamicImage::ImageRgba8(_) | DynamicImage::ImageRgb16(_) | DynamicImage::ImageRgba16(_) => {
            AnyImage::Rgb8(decoded.to_rgb8())
        }
        other => {
            return Err(CodecError::Unsupported {
                file: path.into(),
                what: format!("pixel type {:?}", other.color()),
            });
        }
    })
}

/// Reads the IMAGE object of a PDS3 product (attached or detached label) as 16-bit grey, with
/// its significant bits (from SAMPLE_BIT_MASK, else SAMPLE_BITS). Missing samples become 0.
pub fn read_pds3_grey16(path: impl AsRef<Path>) -> Result<(Grey16, u32), CodecError> {
    let path = path.as_ref();
    let pds = Pds3Image::open(path)?;
    let unsupported = |what: String| CodecError::Unsupported { file: path.into(), what };
    if matches!(pds.sample_type, SampleType::Float { .. }) || pds.sample_bits > 16 {
        return Err(unsupported(format!("IMAGE.SAMPLE_BITS {} of {:?}", pds.sample_bits, pds.sample_type)));
    }
    let mask = pds.label.block("IMAGE").and_then(|b| b.get_f64("SAMPLE_BIT_MASK"));
    let bits = match mask {
        Some(m) if (1.0..65536.0).contains(&m) => 32 - (m as u32).leading_zeros(),
        _ => pds.sample_bits,
    };
    let (w, h) = (pds.line_samples as u32, pds.lines as u32);
    let mut pixels = Vec::with_capacity(pds.values.len());
    for (k, &v) in pds.values.iter().enumerate() {
        if v.is_nan() {
            pixels.push(0);
        } else if (0.0..=65535.0).contains(&v) && v.fract() == 0.0 {
            pixels.push(v as u16);
        } else {
            let (line, sample) = (k / pds.line_samples.max(1), k % pds.line_samples.max(1));
            return Err(unsupported(format!(
                "IMAGE value {v} at line {line} sample {sample} is not a 16-bit DN"
            )));
        }
    }
    let image = Grey16::from_raw(w, h, pixels).ok_or_else(|| unsupported("IMAGE size".into()))?;
    Ok((image, bits))
}

/// Writes an image as PNG (16-bit grey stays 16-bit).
pub fn write_png(path: impl AsRef<Path>, image: &AnyImage) -> Result<(), CodecError> {
    let path = path.as_ref();
    let result = match image {
        AnyImage::Grey8(i) => i.save_with_format(path, ImageFormat::Png),
        AnyImage::Grey16 { image, .. } => image.save_with_format(path, ImageFormat::Png),
        AnyImage::Rgb8(i) => i.save_with_format(path, ImageFormat::Png),
    };
    result.map_err(|source| CodecError::Image { file: path.into(), source })
}

/// Writes a 16-bit grey image as a 16-bit PNG.
pub fn write_png_grey16(path: impl AsRef<Path>, image: &Grey16) -> Result<(), CodecError> {
    let path = path.as_ref();
    image
        .save_with_format(path, ImageFormat::Png)
        .map_err(|source| CodecError::Image { file: path.into(), source })
}

/// Writes an 8-bit grey image as PNG.
pub fn write_png_grey8(path: impl AsRef<Path>, image: &Grey8) -> Result<(), CodecError> {
    let path = path.as_ref();
    image
        .save_with_format(path, ImageFormat::Png)
        .map_err(|source| CodecError::Image { file: path.into(), source })
}

/// Writes an 8-bit RGB image as PNG.
pub fn write_png_rgb8(path: impl AsRef<Path>, image: &Rgb8) -> Result<(), CodecError> {
    let path = path.as_ref();
    image
        .save_with_format(path, ImageFormat::Png)
        .map_err(|source| CodecError::Image { file: path.into(), source })
}
