//! A dense, georeferenced 2D grid: the one raster type every map layer uses.
//!
//! Row 0 is the southern edge (minimum y), so that grid indices grow with world coordinates;
//! loaders of north-up images flip rows on load.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Placement and size of a grid in the world frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GridGeometry {
    /// Number of columns (along x).
    pub cols: usize,
    /// Number of rows (along y).
    pub rows: usize,
    /// Cell size (m).
    pub resolution: f64,
    /// World x of the western edge of column 0.
    pub origin_x: f64,
    /// World y of the southern edge of row 0.
    pub origin_y: f64,
}

impl GridGeometry {
    /// Width of the grid in metres.
    pub fn width_m(&self) -> f64 {
        self.cols as f64 * self.resolution
    }
    /// Height of the grid in metres.
    pub fn height_m(&self) -> f64 {
        self.rows as f64 * self.resolution
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }
    /// Whether the grid has no cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The (col, row) of the cell containing a world point, if inside.
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        let c = ((x - self.origin_x) / self.resolution).floor();
        let r = ((y - self.origin_y) / self.resolution).floor();
        if c >= 0.0 && r >= 0.0 && (c as usize) < self.cols && (r as usize) < self.rows {
            Some((c as usize, r as usize))
        } else {
            None
        }
    }
    /// World coordinates of a cell's centre.
    pub fn center(&self, col: usize, row: usize) -> (f64, f64) {
        (
            self.origin_x + (col as f64 + 0.5) * self.resolution,
            self.origin_y + (row as f64 + 0.5) * self.resolution,
        )
    }
    /// Linear index of (col, row).
    pub fn index(&self, col: usize, row: usize) -> usize {
        row * self.cols + col
    }
    /// Whether a world point lies inside the grid.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.cell_of(x, y).is_some()
    }
}

/// A dense grid of values with its world placement.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid2<T> {
    /// Placement and size.
    pub geometry: GridGeometry,
    /// Row-major values, `rows * cols` long, row 0 south.
    pub data: Vec<T>,
}

impl<T: Clone> Grid2<T> {
    /// A grid filled with one value.
    pub fn filled(geometry: GridGeometry, value: T) -> Self {
        Self { data: vec![value; geometry.len()], geometry }
    }
}

impl<T> Grid2<T> {
    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.geometry.cols
    }
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.geometry.rows
    }
    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.geometry.resolution
    }
    /// The value at (col, row); panics when out of range, like slice indexing.
    pub fn get(&self, col: usize, row: usize) -> &T {
        &self.data[row * self.geometry.cols + col]
    }
    /// Mutable value at (col, row).
    pub fn get_mut(&mut self, col: usize, row: usize) -> &mut T {
        &mut self.data[row * self.geometry.cols + col]
    }
    /// The value at (col, row) if inside.
    pub fn try_get(&self, col: isize, row: isize) -> Option<&T> {
        if col < 0 || row < 0 || col as usize >= self.geometry.cols || row as usize >= self.geometry.rows {
            None
        } else {
            Some(&self.data[row as usize * self.geometry.cols + col as usize])
        }
    }
    /// The value of the cell containing a world point, if inside.
    pub fn at_world(&self, x: f64, y: f64) -> Option<&T> {
        self.geometry.cell_of(x, y).map(|(c, r)| self.get(c, r))
    }
}

impl Grid2<bool> {
    /// Marks in `dst` (same geometry) every cell whose centre lies within `radius` of a set
    /// cell's centre, with half a cell squared of slack so that a radius of whole cells keeps
    /// its diagonal neighbours; clears the rest of `dst`.
    pub fn dilate_into(&self, radius: f64, dst: &mut Grid2<bool>) {
        let g = self.geometry;
        let reach = (radius / g.resolution).ceil() as isize;
        let r2 = (radius / g.resolution).powi(2);
        let offsets: Vec<(isize, isize)> = (-reach..=reach)
            .flat_map(|dr| (-reach..=reach).map(move |dc| (dr, dc)))
            .filter(|&(dr, dc)| ((dr * dr + dc * dc) as f64) <= r2 + 0.5)
            .collect();
        dst.data.iter_mut().for_each(|v| *v = false);
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*self.get(c, r) {
                    continue;
                }
                for &(dr, dc) in &offsets {
                    let (rr, cc) = (r as isize + dr, c as isize + dc);
                    if rr >= 0 && cc >= 0 && (rr as usize) < g.rows && (cc as usize) < g.cols {
                        *dst.get_mut(cc as usize, rr as usize) = true;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_marks_the_cells_within_the_radius_and_only_those() {
        let g = GridGeometry { cols: 11, rows: 11, resolution: 0.1, origin_x: 0.0, origin_y: 0.0 };
        let mut src = Grid2::filled(g, false);
        *src.get_mut(5, 5) = true;
        let mut dst = Grid2::filled(g, true);
        src.dilate_into(0.2, &mut dst);
        for r in 0..11 {
            for c in 0..11 {
                let d2 = (c as f64 - 5.0).powi(2) + (r as f64 - 5.0).powi(2);
                assert_eq!(*dst.get(c, r), d2 <= 4.5, "cell ({c}, {r})");
            }
        }
    }

    #[test]
    fn cell_of_and_center_round_trip() {
        let g = GridGeometry { cols: 10, rows: 5, resolution: 0.5, origin_x: -2.0, origin_y: 1.0 };
        for r in 0..5 {
            for c in 0..10 {
                let (x, y) = g.center(c, r);
                assert_eq!(g.cell_of(x, y), Some((c, r)));
            }
        }
        assert_eq!(g.cell_of(-2.01, 1.0), None);
        assert_eq!(g.cell_of(3.0, 1.0), None);
    }
}
