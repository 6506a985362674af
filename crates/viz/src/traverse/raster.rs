//! The terrain under a traverse picture, drawn by this crate (plotters blits it): elevation
//! colours from a Mars-like ramp, modulated by a hillshade (sun from the north-west, 45 deg up),
//! and the area the rover's range data covered tinted cyan.
//!
//! The colour range is fitted to the heights inside the drawn frame (2nd to 98th percentile),
//! so a route across a gentle part of a large DEM still shows its relief.

use super::frame::Frame;
use rovernav_core::Grid2;
use rovernav_terrain::Dem;

/// Elevation ramp stops, low to high: dark umber, rust, ochre, pale sand.
const RAMP: [[f64; 3]; 4] =
    [[70.0, 48.0, 42.0], [150.0, 88.0, 55.0], [205.0, 150.0, 95.0], [240.0, 222.0, 188.0]];

/// Tint of the sensed area and its weight.
pub const SENSED_TINT: [u8; 3] = [60, 200, 255];
const SENSED_ALPHA: f64 = 0.22;

/// Colour of no-data cells.
pub const NO_DATA: [u8; 3] = [25, 25, 35];

/// The elevation ramp at `t` in [0, 1] (clamped), as drawn on flat ground and in the colour bar.
pub fn ramp(t: f64) -> [u8; 3] {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let s = t * (RAMP.len() - 1) as f64;
    let i = (s.floor() as usize).min(RAMP.len() - 2);
    let f = s - i as f64;
    let mut out = [0u8; 3];
    for (k, o) in out.iter_mut().enumerate() {
        *o = (RAMP[i][k] + (RAMP[i + 1][k] - RAMP[i][k]) * f).round() as u8;
    }
    out
}

/// The heights the colour ramp spans: the 2nd and 98th percentiles of the finite heights inside
/// `frame` (sampled on at most about 250 000 cells); `(0, 1)` when there are none.
pub fn elevation_range(dem: &Dem, frame: &Frame) -> (f64, f64) {
    let g = *dem.geometry();
    let c0 = ((frame.x0 - g.origin_x) / g.resolution).floor().max(0.0) as usize;
    let r0 = ((frame.y0 - g.origin_y) / g.resolution).floor().max(0.0) as usize;
    let c1 = (((frame.x1 - g.origin_x) / g.resolution).ceil().max(0.0) as usize).min(g.cols);
    let r1 = (((frame.y1 - g.origin_y) / g.resolution).ceil().max(0.0) as usize).min(g.rows);
    let cells = (c1.saturating_sub(c0) * r1.saturating_sub(r0)).max(1);
    let stride = ((cells as f64 / 250_000.0).sqrt().ceil() as usize).max(1);
    let mut heights: Vec<f32> = Vec::new();
    for r in (r0..r1).step_by(stride) {
        for c in (c0..c1).step_by(stride) {
            let h = *dem.heights.get(c, r);
            if h.is_finite() {
                heights.push(h);
            }
        }
    }
    if heights.is_empty() {
        return (0.0, 1.0);
    }
    heights.sort_by(f32::total_cmp);
    let at = |q: f64| heights[((heights.len() - 1) as f64 * q).round() as usize] as f64;
    let (lo, hi) = (at(0.02), at(0.98));
    if hi - lo < 0.05 { (lo - 0.025, lo + 0.025) } else { (lo, hi) }
}

/// Shades `frame` into a `width` x `height` RGB raster (row 0 north): pixel `(px, py)` shows the
/// DEM cell under its centre.
pub fn shade(
    dem: &Dem,
    sensed: Option<&Grid2<bool>>,
    frame: &Frame,
    range: (f64, f64),
    width: usize,
    height: usize,
) -> Vec<u8> {
    let g = *dem.geometry();
    let (el, az) = (45f64.to_radians(), 135f64.to_radians());
    let sun = [az.cos() * el.cos(), az.sin() * el.cos(), el.sin()];
    let h = |c: isize, r: isize| -> f64 {
        let c = c.clamp(0, g.cols as isize - 1);
        let r = r.clamp(0, g.rows as isize - 1);
        *dem.heights.get(c as usize, r as usize) as f64
    };
    let span = (range.1 - range.0).max(1e-9);
    let mut out = vec![0u8; width * height * 3];
    for py in 0..height {
        let y = frame.y1 - (py as f64 + 0.5) / height as f64 * frame.height();
        for px in 0..width {
            let x = frame.x0 + (px as f64 + 0.5) / width as f64 * frame.width();
            let i = (py * width + px) * 3;
            let Some((c, r)) = g.cell_of(x, y) else {
                out[i..i + 3].copy_from_slice(&NO_DATA);
                continue;
            };
            let (c, r) = (c as isize, r as isize);
            let z = h(c, r);
            if !z.is_finite() {
                out[i..i + 3].copy_from_slice(&NO_DATA);
                continue;
            }
            let dzdx = (h(c + 1, r) - h(c - 1, r)) / (2.0 * g.resolution);
            let dzdy = (h(c, r + 1) - h(c, r - 1)) / (2.0 * g.resolution);
            // Flat ground keeps the ramp's colour (k = 1); slopes facing the sun lighten.
            let k = if dzdx.is_finite() && dzdy.is_finite() {
                let len = (dzdx * dzdx + dzdy * dzdy + 1.0).sqrt();
                let lit = ((-dzdx * sun[0] - dzdy * sun[1] + sun[2]) / len).clamp(0.0, 1.0);
                (1.0 + 0.9 * (lit - sun[2])).clamp(0.3, 1.35)
            } else {
                1.0
            };
            let base = ramp((z - range.0) / span);
            let mut rgb = base.map(|v| (v as f64 * k).min(255.0));
            if sensed.and_then(|s| s.at_world(x, y)).copied().unwrap_or(false) {
                for (v, t) in rgb.iter_mut().zip(SENSED_TINT) {
                    *v += (t as f64 - *v) * SENSED_ALPHA;
                }
            }
            out[i..i + 3].copy_from_slice(&rgb.map(|v| v.round() as u8));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::GridGeometry;

    fn ramp_dem() -> Dem {
        // Heights rise 0.1 m per column eastwards over 40 x 20 cells of 0.5 m.
        let geometry = GridGeometry { cols: 40, rows: 20, resolution: 0.5, origin_x: 0.0, origin_y: 0.0 };
        let mut grid = Grid2::filled(geometry, 0.0f32);
        for r in 0..20 {
            for c in 0..40 {
                *grid.get_mut(c, r) = 0.1 * c as f32;
            }
        }
        Dem::from_grid(grid)
    }

    #[test]
    fn ramp_runs_from_its_first_stop_to_its_last() {
        assert_eq!(ramp(0.0), [70, 48, 42]);
        assert_eq!(ramp(1.0), [240, 222, 188]);
        assert_eq!(ramp(-3.0), ramp(0.0));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
        // Brightness rises along the ramp.
        let sum = |t: f64| ramp(t).iter().map(|&v| v as u32).sum::<u32>();
        assert!((0..10).all(|k| sum(k as f64 / 10.0) < sum((k + 1) as f64 / 10.0)));
    }

    #[test]
    fn elevation_range_is_the_frames_percentiles() {
        let dem = ramp_dem();
        // Columns 10..20 hold heights 1.0..1.9: the 2nd and 98th percentiles of ten equal
        // columns are their first and last values.
        let frame = Frame { x0: 5.0, x1: 10.0, y0: 0.0, y1: 10.0 };
        let (lo, hi) = elevation_range(&dem, &frame);
        assert!((lo - 1.0).abs() < 1e-5 && (hi - 1.9).abs() < 1e-5, "{lo} {hi}");
    }

    #[test]
    fn sensed_cells_are_tinted_and_outside_is_no_data() {
        let dem = ramp_dem();
        let mut sensed = Grid2::filled(*dem.geometry(), false);
        *sensed.get_mut(30, 10) = true;
        // A frame twice the DEM's width: the east half lies outside it.
        let frame = Frame { x0: 0.0, x1: 40.0, y0: 0.0, y1: 10.0 };
        let img = shade(&dem, Some(&sensed), &frame, (0.0, 3.9), 80, 20);
        let px = |x: usize, y: usize| {
            [img[(y * 80 + x) * 3], img[(y * 80 + x) * 3 + 1], img[(y * 80 + x) * 3 + 2]]
        };
        assert_eq!(px(60, 5), NO_DATA);
        // Cell (30, 10) is x 15..15.5, y 5..5.5: pixel column 30, row 9 (y 5.0..5.5 from the top 10).
        let tinted = px(30, 9);
        let plain = px(30, 12);
        assert!(tinted[2] > plain[2] + 20, "{tinted:?} {plain:?}");
    }
}
