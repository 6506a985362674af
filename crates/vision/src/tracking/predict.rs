//! Search windows predicted from the rover's motion estimate (paper 003 section 3: VTT runs
//! after visual odometry or the IMU/wheel estimator, and searches where the motion says the
//! target went).
//!
//! The target's site-frame position is projected through the camera model predicted for the
//! next image (the mounted camera moved by the estimated rover pose). The window's half-size is
//! `gate` standard deviations of the pixel error that the pose uncertainty causes: a camera
//! position error σ_p moves the target in the image by at most ‖J‖ σ_p pixels, with J the 2x3
//! projection Jacobian at the target (‖J‖ ≈ f / depth: the pixels per metre at that range), and
//! an attitude error σ_θ by f σ_θ pixels, f ≈ ‖J‖ · depth; the two add as independent errors.

use nalgebra::Point3;

use super::TrackError;
use crate::camera::CameraModel;

/// Where to look for the target in the next image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction {
    /// Predicted column (sample) of the target.
    pub x: f64,
    /// Predicted row (line) of the target.
    pub y: f64,
    /// Predicted range from the camera centre to the target (m).
    pub range_m: f64,
    /// Standard deviation (px) of the prediction.
    pub sigma_px: f64,
    /// Half-size (px) of the square search window.
    pub half_window: usize,
}

/// How the window is sized.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowParams {
    /// Window half-size in standard deviations of the prediction.
    pub gate: f64,
    /// Smallest half-size (px).
    pub min_half: usize,
    /// Largest half-size (px).
    pub max_half: usize,
}

impl Default for WindowParams {
    fn default() -> Self {
        Self { gate: 3.0, min_half: 4, max_half: 80 }
    }
}

/// Projects `target` (site frame) through the predicted `camera` (site frame) and sizes the
/// window from the camera position (`position_sigma_m`, m) and attitude
/// (`attitude_sigma_rad`, rad) standard deviations.
pub fn predict_window(
    camera: &dyn CameraModel,
    target: &Point3<f64>,
    position_sigma_m: f64,
    attitude_sigma_rad: f64,
    params: &WindowParams,
) -> Result<Prediction, TrackError> {
    if !(position_sigma_m >= 0.0 && attitude_sigma_rad >= 0.0) {
        return Err(TrackError::Parameter(format!(
            "pose sigmas must be >= 0 (position {position_sigma_m} m, attitude {attitude_sigma_rad} rad)"
        )));
    }
    let (pixel, jac) = camera.project_jacobian(target).ok_or(TrackError::OutOfView)?;
    if !camera.contains(&pixel) {
        return Err(TrackError::OutOfView);
    }
    let range_m = (target - camera.centre()).norm();
    // Spectral norm of J: the largest pixel shift per metre of displacement.
    let per_metre = (jac * jac.transpose()).symmetric_eigenvalues().max().max(0.0).sqrt();
    let focal_px = per_metre * range_m;
    let sigma_px = ((per_metre * position_sigma_m).powi(2) + (focal_px * attitude_sigma_rad).powi(2)).sqrt();
    let half = (params.gate * sigma_px).ceil();
    let half_window = if half.is_finite() {
        (half as usize).clamp(params.min_half, params.max_half)
    } else {
        params.max_half
    };
    Ok(Prediction { x: pixel.x, y: pixel.y, range_m, sigma_px, half_window })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Cahv;
    use nalgebra::Vector3;

    #[test]
    fn window_from_pixels_per_metre_hand_worked() {
        // Camera at the origin looking along +x, f = 500 px, centre (256, 256). A target 10 m
        // ahead sits on the centre; 1 m of position error is 50 px at 10 m (f / z, for a
        // displacement across the view); 3 sigma of 4 cm is 6 px.
        let cam = Cahv::from_intrinsics(
            Vector3::zeros(),
            Vector3::x(),
            -Vector3::y(),
            500.0,
            500.0,
            256.0,
            256.0,
            512,
            512,
        );
        let p =
            predict_window(&cam, &Point3::new(10.0, 0.0, 0.0), 0.04, 0.0, &WindowParams::default()).unwrap();
        assert!((p.x - 256.0).abs() < 1e-9 && (p.y - 256.0).abs() < 1e-9);
        assert!((p.sigma_px - 2.0).abs() < 1e-9, "{}", p.sigma_px);
        assert_eq!(p.half_window, 6);
        assert!((p.range_m - 10.0).abs() < 1e-12);
        // 2 mrad of heading error is 1 px at f = 500: sigma = sqrt(2^2 + 1^2).
        let p = predict_window(&cam, &Point3::new(10.0, 0.0, 0.0), 0.04, 0.002, &WindowParams::default())
            .unwrap();
        assert!((p.sigma_px - 5f64.sqrt()).abs() < 1e-9);
        // Behind the camera, or outside the image: out of view.
        let back = predict_window(&cam, &Point3::new(-10.0, 0.0, 0.0), 0.04, 0.0, &WindowParams::default());
        assert_eq!(back, Err(TrackError::OutOfView));
        let aside = predict_window(&cam, &Point3::new(1.0, 5.0, 0.0), 0.04, 0.0, &WindowParams::default());
        assert_eq!(aside, Err(TrackError::OutOfView));
    }
}
