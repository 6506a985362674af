//! Image types shared by the renderer, stereo and the tracking and science algorithms.
//!
//! rovernav uses the `image` crate's buffers rather than its own: a grey image of up to 16 bits
//! (rovers' cameras are 12-bit) is [`Grey16`], an 8-bit one [`Grey8`], a float one [`GreyF32`].

pub use ::image::{ImageBuffer, Luma, Rgb};

/// A grey image with up to 16 bits per pixel (12-bit Navcam data is stored in the low bits).
pub type Grey16 = ImageBuffer<Luma<u16>, Vec<u16>>;
/// An 8-bit grey image.
pub type Grey8 = ImageBuffer<Luma<u8>, Vec<u8>>;
/// A floating-point grey image.
pub type GreyF32 = ImageBuffer<Luma<f32>, Vec<f32>>;
/// An 8-bit RGB image.
pub type Rgb8 = ImageBuffer<Rgb<u8>, Vec<u8>>;
