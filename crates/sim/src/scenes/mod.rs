//! Labelled scenes for the onboard-science detectors (paper 003 section 5): skies with and
//! without clouds ([`clouds`]) and fixed-camera sequences with and without dust devils
//! ([`dust_devils`]), and the lander watching the rover turn ([`lander`]), rendered by
//! [`crate::render`] with their truth.
//!
//! Clouds and dust devils are the renderer's transparent volumes. The truth of every pixel comes
//! from the geometry, not from the detector's view of the image: the volumes' optical depth along
//! the pixel's centre ray (clipped at the surface the renderer's range says the ray met) gives
//! the transmission `T`, and with the volumes' single-scattering source `S` the radiance behind
//! them is `L_b = (L - S (1 - T)) / T` from the rendered noise-free radiance `L`. The event's
//! relative contrast in that pixel is `L / L_b - 1` (exact when all volumes of a scene share
//! their albedo, as the generators ensure).

pub mod clouds;
pub mod descent;
pub mod dust_devils;
pub mod lander;

use nalgebra::Point2;
use rovernav_core::{Pose3, RoverConfig};
use rovernav_terrain::Terrain;
use rovernav_terrain::procedural::{MarsYardParams, generate};
use rovernav_vision::{Cahv, CameraModel};

use crate::raycast::HeightField;
use crate::render::{RenderSettings, Rig, Scene, Sensor, Volume};

/// A small Mars yard to stand on, with its ray-casting structure.
pub struct Site {
    /// The terrain.
    pub terrain: Terrain,
    /// Its height field.
    pub field: HeightField,
    /// Mean height of the DEM (the level of the far ground, m).
    pub ground_z: f64,
}

impl Site {
    /// A 24 m yard at 10 cm for `seed`.
    pub fn new(seed: u64) -> Self {
        let params =
            MarsYardParams { width_m: 24.0, height_m: 24.0, resolution: 0.1, seed, ..Default::default() };
        let terrain = generate(&params);
        let field = HeightField::new(&terrain.dem);
        let h = &terrain.dem.heights.data;
        let finite: Vec<f64> = h.iter().filter(|v| v.is_finite()).map(|&v| v as f64).collect();
        let ground_z = if finite.is_empty() { 0.0 } else { finite.iter().sum::<f64>() / finite.len() as f64 };
        Self { terrain, field, ground_z }
    }

    /// The rover's pose at the yard's centre with the given roll and pitch (rad) and heading.
    pub fn pose(&self, roll: f64, pitch: f64, yaw: f64) -> Pose3 {
        let g = self.terrain.dem.geometry();
        let (x, y) = (g.origin_x + 0.5 * g.width_m(), g.origin_y + 0.5 * g.height_m());
        let z = self.terrain.dem.height(x, y).unwrap_or(self.ground_z);
        Pose3 { x, y, z, roll, pitch, yaw }
    }

    /// The left Navcam of a rover at `pose`, head at `pan`/`tilt` (rad), `size` pixels square.
    pub fn navcam(&self, pose: &Pose3, pan: f64, tilt: f64, size: usize) -> Cahv {
        let rig = Rig::new(&RoverConfig::default()).with_size(size);
        let cam = rig.camera("navcam_left", pan, tilt).expect("navcam_left is a rig camera");
        cam.in_world(pose, pose)
    }
}

/// The noisier detector of the science sets: MER Navcam images downlinked after 12-to-8-bit
/// companding and lossy compression carry more noise than the raw 12-bit default; 15 e-/DN and
/// 2 DN read noise give about 0.6 % at mid-scale, and `jpeg_quality` adds block compression
/// (the flight images were ICER-compressed; the renderer's DCT quantiser stands in for it).
pub fn science_settings(jpeg_quality: Option<u8>) -> RenderSettings {
    RenderSettings {
        supersample: 1,
        shadows: true,
        sensor: Sensor {
            gain_e_per_dn: 15.0,
            read_noise_dn: 2.0,
            dead_pixels: 4,
            jpeg_quality,
            ..Sensor::default()
        },
    }
}

/// Relative contrast `L / L_b - 1` of the scene's volumes in each pixel (row-major; 0 where no
/// volume is crossed), from the rendered noise-free `radiance` and `range`.
pub fn volume_contrast(scene: &Scene, camera: &dyn CameraModel, radiance: &[f32], range: &[f32]) -> Vec<f32> {
    let (w, h) = (camera.width(), camera.height());
    let lit = &scene.lighting;
    let mut out = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let ray = camera.unproject(&Point2::new(x as f64, y as f64));
            let o = [ray.origin.x, ray.origin.y, ray.origin.z];
            let d = ray.direction.into_inner();
            let d = [d.x, d.y, d.z];
            let mut tau = 0.0;
            let mut source = 0.0;
            for v in &scene.volumes {
                if let Some((a, b)) = v.chord(o, d, scene.time) {
                    let b = b.min(range[i] as f64);
                    if b > a {
                        tau += v.density * (b - a);
                        source = volume_source(v, lit);
                    }
                }
            }
            if tau > 0.0 {
                let t = (-tau).exp();
                let l = radiance[i] as f64;
                let behind = (l - source * (1.0 - t)) / t;
                out[i] = if behind > 1e-9 { (l / behind - 1.0) as f32 } else { 0.0 };
            }
        }
    }
    out
}

/// The single-scattering source of a volume under the scene's light (as the renderer's
/// compositing computes it).
fn volume_source(v: &Volume, lit: &crate::render::Lighting) -> f64 {
    v.albedo * (lit.direct * lit.sun[2].max(0.0).sqrt() + lit.diffuse)
}

/// The bounding box `[x, y, width, height]` of the pixels where `|contrast| >= min`, and their
/// count and peak `|contrast|`.
pub fn event_extent(contrast: &[f32], width: usize, min: f32) -> (Option<[u32; 4]>, usize, f32) {
    let (mut x0, mut y0, mut x1, mut y1, mut n, mut peak) = (usize::MAX, usize::MAX, 0, 0, 0, 0f32);
    for (i, c) in contrast.iter().enumerate() {
        peak = peak.max(c.abs());
        if c.abs() >= min {
            let (x, y) = (i % width, i / width);
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
            n += 1;
        }
    }
    let bbox = (n > 0).then(|| [x0 as u32, y0 as u32, (x1 - x0 + 1) as u32, (y1 - y0 + 1) as u32]);
    (bbox, n, peak)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Label;

    #[test]
    fn cloud_truth_lies_in_the_sky_and_clear_cases_have_none() {
        let site = Site::new(3);
        let clear = clouds::cloud_image(&site, 0, 64, 1, None);
        assert_eq!(clear.truth.class, clouds::CloudClass::Clear);
        assert!(!clear.truth.cloud && clear.truth.peak_contrast == 0.0);
        // Distinct cases (indices 14..19 of every 20): the cloud pixels are sky pixels.
        let mut seen = 0;
        for index in 14..20 {
            let case = clouds::cloud_image(&site, index, 64, 1, None);
            let Some([x, y, w, h]) = case.truth.bbox else { continue };
            seen += 1;
            assert!(x + w <= 64 && y + h <= 64);
            // Clouds are seen against the sky: most of their box is sky to the renderer.
            let labels = &case.rendered.labels;
            let sky = (y..y + h).flat_map(|r| (x..x + w).map(move |c| (r * 64 + c) as usize));
            let (n, in_sky) = sky.fold((0, 0), |(n, s), i| (n + 1, s + (labels[i] == Label::Sky) as usize));
            assert!(case.truth.peak_contrast >= clouds::VISIBLE_CONTRAST);
            assert!(2 * in_sky > n, "cloud box {:?}: {in_sky} of {n} pixels are sky", case.truth.bbox);
        }
        assert!(seen >= 3, "{seen} distinct clouds visible");
    }

    #[test]
    fn dust_devil_truth_follows_the_column_and_empty_sequences_have_none() {
        let site = Site::new(4);
        let empty = dust_devils::dust_devil_sequence(&site, 0, 6, 64, 2, None);
        assert!(empty.truth.iter().all(|t| !t.present && t.peak_contrast == 0.0));
        let seq = dust_devils::dust_devil_sequence(&site, 1, 8, 96, 2, None);
        let present: Vec<_> = seq.truth.iter().filter(|t| t.present).collect();
        assert!(!present.is_empty());
        // The scene is static but for the dust devils: wherever two frames' noise-free
        // radiances differ by more than twice the visibility contrast, one of their truth boxes
        // covers the pixel.
        let n = 96;
        for k in 0..seq.frames.len() {
            for j in 0..k {
                let (a, b) = (&seq.frames[k].radiance, &seq.frames[j].radiance);
                for i in 0..n * n {
                    let d = (a[i] - b[i]).abs() / a[i].min(b[i]).max(1e-6);
                    if d > 2.0 * dust_devils::VISIBLE_CONTRAST {
                        let (x, y) = ((i % n) as u32, (i / n) as u32);
                        let inside = [&seq.truth[k], &seq.truth[j]].iter().any(|t| {
                            t.bbox.is_some_and(|[bx, by, bw, bh]| {
                                x >= bx && x < bx + bw && y >= by && y < by + bh
                            })
                        });
                        assert!(
                            inside,
                            "frames {k}/{j}: pixel ({x}, {y}) changed by {d:.3} outside the truth boxes"
                        );
                    }
                }
            }
        }
    }
}
