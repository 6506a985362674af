//! An RGB raster with alpha-blended primitives and PNG output.

use std::io::Write;

/// An 8-bit RGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

/// An RGB image.
#[derive(Clone, Debug)]
pub struct Canvas {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// Row-major RGB bytes, row 0 at the top.
    pub pixels: Vec<u8>,
}

/// 3x5 glyphs for the few characters labels need, one row per 3-bit number.
fn glyph(ch: char) -> Option<[u8; 5]> {
    Some(match ch {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        'm' => [0, 0, 7, 7, 5],
        '-' => [0, 0, 7, 0, 0],
        _ => return None,
    })
}

impl Canvas {
    /// A black canvas.
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, pixels: vec![0; width * height * 3] }
    }

    /// The colour at a pixel.
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        let i = (y * self.width + x) * 3;
        Rgb(self.pixels[i], self.pixels[i + 1], self.pixels[i + 2])
    }

    /// Sets a pixel.
    pub fn set(&mut self, x: usize, y: usize, c: Rgb) {
        let i = (y * self.width + x) * 3;
        self.pixels[i..i + 3].copy_from_slice(&[c.0, c.1, c.2]);
    }

    /// Blends a colour into a pixel (ignores pixels outside).
    pub fn blend(&mut self, x: isize, y: isize, c: Rgb, alpha: f64) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let i = (y as usize * self.width + x as usize) * 3;
        let a = alpha.clamp(0.0, 1.0);
        for (k, v) in [c.0, c.1, c.2].into_iter().enumerate() {
            let old = self.pixels[i + k] as f64;
            self.pixels[i + k] = (old + (v as f64 - old) * a).round() as u8;
        }
    }

    /// Fills an axis-aligned rectangle.
    pub fn fill_rect(&mut self, x: f64, y: f64, w: f64, h: f64, c: Rgb, alpha: f64) {
        let (x0, y0) = (x.floor() as isize, y.floor() as isize);
        let (x1, y1) = ((x + w).ceil() as isize, (y + h).ceil() as isize);
        for py in y0.max(0)..y1.min(self.height as isize) {
            for px in x0.max(0)..x1.min(self.width as isize) {
                self.blend(px, py, c, alpha);
            }
        }
    }

    /// Fills a disc.
    pub fn fill_circle(&mut self, cx: f64, cy: f64, r: f64, c: Rgb, alpha: f64) {
        let (x0, x1) = ((cx - r).floor() as isize, (cx + r).ceil() as isize);
        let (y0, y1) = ((cy - r).floor() as isize, (cy + r).ceil() as isize);
        for py in y0.max(0)..=y1.min(self.height as isize - 1) {
            for px in x0.max(0)..=x1.min(self.width as isize - 1) {
                let d = ((px as f64 + 0.5 - cx).powi(2) + (py as f64 + 0.5 - cy).powi(2)).sqrt();
                let cover = (r + 0.5 - d).clamp(0.0, 1.0);
                if cover > 0.0 {
                    self.blend(px, py, c, alpha * cover);
                }
            }
        }
    }

    /// Draws a circle outline.
    pub fn stroke_circle(&mut self, cx: f64, cy: f64, r: f64, c: Rgb, width: f64) {
        let steps = ((r * 6.3) as usize).max(12);
        let pts: Vec<(f64, f64)> = (0..steps)
            .map(|i| {
                let a = i as f64 / steps as f64 * std::f64::consts::TAU;
                (cx + r * a.cos(), cy + r * a.sin())
            })
            .collect();
        self.polyline(&pts, true, c, width);
    }

    /// Draws a thick line segment.
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), c: Rgb, width: f64) {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy);
        if !len.is_finite() {
            return;
        }
        let half = (width / 2.0).max(0.5);
        let minx = (a.0.min(b.0) - half - 1.0).floor().max(0.0) as isize;
        let maxx = (a.0.max(b.0) + half + 1.0).ceil().min(self.width as f64 - 1.0) as isize;
        let miny = (a.1.min(b.1) - half - 1.0).floor().max(0.0) as isize;
        let maxy = (a.1.max(b.1) + half + 1.0).ceil().min(self.height as f64 - 1.0) as isize;
        for py in miny..=maxy {
            for px in minx..=maxx {
                let (qx, qy) = (px as f64 + 0.5, py as f64 + 0.5);
                let t = if len > 0.0 {
                    (((qx - a.0) * dx + (qy - a.1) * dy) / (len * len)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = (qx - a.0 - t * dx).hypot(qy - a.1 - t * dy);
                let cover = (half + 0.5 - d).clamp(0.0, 1.0);
                if cover > 0.0 {
                    let i = (py as usize * self.width + px as usize) * 3;
                    for (k, target) in [c.0, c.1, c.2].into_iter().enumerate() {
                        let old = self.pixels[i + k] as f64;
                        self.pixels[i + k] = (old + (target as f64 - old) * cover).round() as u8;
                    }
                }
            }
        }
    }

    /// Draws a polyline, optionally closed.
    pub fn polyline(&mut self, pts: &[(f64, f64)], closed: bool, c: Rgb, width: f64) {
        for w in pts.windows(2) {
            self.line(w[0], w[1], c, width);
        }
        if closed && pts.len() > 2 {
            self.line(pts[pts.len() - 1], pts[0], c, width);
        }
    }

    /// Fills a simple polygon (even-odd rule).
    pub fn fill_polygon(&mut self, pts: &[(f64, f64)], c: Rgb, alpha: f64) {
        if pts.len() < 3 {
            return;
        }
        let miny = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
        let maxy =
            pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max).ceil().min(self.height as f64 - 1.0);
        if maxy < 0.0 {
            return;
        }
        for py in miny..=maxy as usize {
            let y = py as f64 + 0.5;
            let mut xs = Vec::new();
            for i in 0..pts.len() {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                if (a.1 <= y) != (b.1 <= y) {
                    xs.push(a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0));
                }
            }
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks(2) {
                if let [x0, x1] = pair {
                    for px in (x0.round().max(0.0) as isize)..(x1.round().min(self.width as f64) as isize) {
                        self.blend(px, py as isize, c, alpha);
                    }
                }
            }
        }
    }

    /// Draws an X marker.
    pub fn cross(&mut self, x: f64, y: f64, size: f64, c: Rgb, width: f64) {
        self.line((x - size, y - size), (x + size, y + size), c, width);
        self.line((x - size, y + size), (x + size, y - size), c, width);
    }

    /// Writes text with the built-in 3x5 font (digits, '.', '-', 'm'), `scale` px per dot.
    pub fn text(&mut self, x: f64, y: f64, s: &str, c: Rgb, scale: usize) {
        let mut cx = x;
        for ch in s.chars() {
            if let Some(rows) = glyph(ch) {
                for (ry, bits) in rows.iter().enumerate() {
                    for rx in 0..3 {
                        if bits & (4 >> rx) != 0 {
                            let s = scale as f64;
                            self.fill_rect(cx + rx as f64 * s, y + ry as f64 * s, s, s, c, 1.0);
                        }
                    }
                }
            }
            cx += 4.0 * scale as f64;
        }
    }

    /// Encodes the canvas as an RGB PNG.
    pub fn write_png(&self, out: impl Write) -> std::io::Result<()> {
        let mut encoder = png::Encoder::new(out, self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(&self.pixels).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trip_keeps_pixels() {
        let mut c = Canvas::new(7, 5);
        c.set(3, 2, Rgb(10, 200, 30));
        c.fill_rect(0.0, 0.0, 2.0, 1.0, Rgb(255, 0, 0), 1.0);
        let mut bytes = Vec::new();
        c.write_png(&mut bytes).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (7, 5));
        assert_eq!(&buf[..info.buffer_size()], &c.pixels[..]);
    }

    #[test]
    fn filled_polygon_covers_its_interior_only() {
        let mut c = Canvas::new(20, 20);
        c.fill_polygon(&[(5.0, 5.0), (15.0, 5.0), (15.0, 15.0), (5.0, 15.0)], Rgb(255, 255, 255), 1.0);
        assert_eq!(c.get(10, 10), Rgb(255, 255, 255));
        assert_eq!(c.get(2, 2), Rgb(0, 0, 0));
        assert_eq!(c.get(17, 10), Rgb(0, 0, 0));
    }

    #[test]
    fn thick_line_passes_through_its_midpoint() {
        let mut c = Canvas::new(30, 30);
        c.line((2.0, 2.0), (28.0, 28.0), Rgb(0, 255, 0), 3.0);
        assert_eq!(c.get(15, 15), Rgb(0, 255, 0));
        assert_eq!(c.get(25, 5), Rgb(0, 0, 0));
    }
}
