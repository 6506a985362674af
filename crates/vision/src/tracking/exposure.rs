//! Auto exposure over a subframe (paper 003 section 3, improvement 2: "auto exposure over a
//! subframe image").
//!
//! MER's auto exposure picks the exposure from the pixels of a subframe rather than the whole
//! image, so that a target against bright sky or dark shadow is still well exposed. Here the
//! subframe is the template's neighbourhood and the result is a gain and offset mapping its
//! mean and standard deviation to chosen values (v' = gain v + offset), plus the factor by
//! which a linear camera's exposure time would change to bring the subframe's mean (above the
//! dark level) to the target mean. NCC itself is invariant to gain and offset; the mapping
//! serves display, telemetry and the next image's exposure time.

use super::TrackError;
use crate::image::GreyF32;

/// A linear grey mapping v' = gain v + offset, and the exposure-time factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposure {
    /// Multiplier on the grey values.
    pub gain: f32,
    /// Added after the gain.
    pub offset: f32,
    /// Factor on the exposure time that brings the subframe mean above `dark` to the target.
    pub time_factor: f32,
}

impl Exposure {
    /// Applies the mapping to a whole image.
    pub fn apply(&self, image: &GreyF32) -> GreyF32 {
        let mut out = image.clone();
        out.pixels_mut().for_each(|p| p[0] = self.gain * p[0] + self.offset);
        out
    }
}

/// The mapping that gives the subframe (x0, y0, width, height) the mean `target_mean` and
/// standard deviation `target_std`; `dark` is the sensor's dark level for `time_factor`.
pub fn auto_exposure(
    image: &GreyF32,
    subframe: (u32, u32, u32, u32),
    target_mean: f32,
    target_std: f32,
    dark: f32,
) -> Result<Exposure, TrackError> {
    let (x0, y0, w, h) = subframe;
    if w == 0 || h == 0 || x0 + w > image.width() || y0 + h > image.height() {
        return Err(TrackError::Parameter(format!(
            "subframe {w}x{h} at ({x0}, {y0}) is not inside the {}x{} image",
            image.width(),
            image.height()
        )));
    }
    let n = (w * h) as f64;
    let (mut s, mut ss) = (0.0f64, 0.0f64);
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let v = image.get_pixel(x, y)[0] as f64;
            s += v;
            ss += v * v;
        }
    }
    let mean = s / n;
    let std = (ss / n - mean * mean).max(0.0).sqrt();
    if std <= 1e-9 * mean.abs().max(1.0) {
        return Err(TrackError::Textureless);
    }
    let gain = target_std as f64 / std;
    let above_dark = mean - dark as f64;
    let time_factor = if above_dark > 0.0 { (target_mean - dark) as f64 / above_dark } else { f64::INFINITY };
    Ok(Exposure {
        gain: gain as f32,
        offset: (target_mean as f64 - gain * mean) as f32,
        time_factor: time_factor as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn hand_worked_subframe() {
        // Subframe values 10 and 30 in equal numbers: mean 20, std 10. Target mean 100, std 20:
        // gain 2, offset 60; with dark level 5 the exposure time scales by (100-5)/(20-5).
        let img = GreyF32::from_fn(8, 8, |x, y| {
            Luma([if x >= 4 {
                1000.0
            } else if (x + y) % 2 == 0 {
                10.0
            } else {
                30.0
            }])
        });
        let e = auto_exposure(&img, (0, 0, 4, 8), 100.0, 20.0, 5.0).unwrap();
        assert!((e.gain - 2.0).abs() < 1e-6 && (e.offset - 60.0).abs() < 1e-4);
        assert!((e.time_factor - 95.0 / 15.0).abs() < 1e-5);
        assert_eq!(e.apply(&img).get_pixel(1, 0)[0], 120.0);
        assert!(auto_exposure(&img, (6, 0, 4, 8), 100.0, 20.0, 5.0).is_err());
        assert_eq!(auto_exposure(&img, (4, 0, 4, 8), 100.0, 20.0, 5.0), Err(TrackError::Textureless));
    }
}
