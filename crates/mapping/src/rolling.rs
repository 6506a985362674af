//! Robot-centred rolling grid on a torus: the MRPTA T-grid store (paper 004 section 3.3).
//!
//! The window covers `cols x rows` cells of a world-fixed lattice (cell `(ix, iy)` spans
//! `[ix*res, (ix+1)*res) x [iy*res, (iy+1)*res)`), axis-aligned with the world frame. Lattice
//! cell `(ix, iy)` is stored at slot `(ix mod cols, iy mod rows)`, so when the window moves the
//! cells that stay keep their slots: a move only changes the window origin and resets the slots
//! of the cells that fell off (they are reused by the cells that enter). Nothing is copied,
//! which is what lets the navigation loop recentre the grid every step (the grid_map design).
//!
//! [`CopyingGrid`] is the obvious copy-on-move implementation, kept as the reference the tests
//! compare against and the baseline the benchmarks measure.

use crate::MappingError;
use rovernav_core::{Grid2, GridGeometry, Point2};

/// Checks the window size and resolution shared by both grid kinds.
fn check_shape(cols: usize, rows: usize, resolution: f64) -> Result<(), MappingError> {
    if cols == 0 || rows == 0 {
        return Err(MappingError::InvalidParameter {
            field: "cols/rows",
            reason: format!("the window must have at least one cell, got {cols}x{rows}"),
        });
    }
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(MappingError::InvalidParameter {
            field: "resolution",
            reason: format!("must be a positive finite length, got {resolution}"),
        });
    }
    Ok(())
}

/// Lattice index of a world coordinate; saturates for coordinates far outside any real map.
fn lattice(v: f64, resolution: f64) -> i64 {
    (v / resolution).floor() as i64
}

/// A fixed-size window of cells centred on the rover, stored on a torus.
#[derive(Clone, Debug)]
pub struct RollingGrid<T> {
    cols: usize,
    rows: usize,
    resolution: f64,
    /// Lattice index of the window's south-west cell.
    origin_ix: i64,
    origin_iy: i64,
    fill: T,
    slots: Vec<T>,
}

impl<T: Clone> RollingGrid<T> {
    /// A window of `cols x rows` cells of `resolution` metres centred on `centre`, every cell
    /// set to `fill` (the value a cell takes when it enters the window).
    pub fn new(
        cols: usize,
        rows: usize,
        resolution: f64,
        fill: T,
        centre: Point2,
    ) -> Result<Self, MappingError> {
        check_shape(cols, rows, resolution)?;
        let (origin_ix, origin_iy) = window_origin(cols, rows, resolution, centre);
        Ok(Self {
            cols,
            rows,
            resolution,
            origin_ix,
            origin_iy,
            slots: vec![fill.clone(); cols * rows],
            fill,
        })
    }

    /// Moves the window so that `centre` lies in its central cell, clearing the cells that leave.
    pub fn recenter(&mut self, centre: Point2) {
        let (ix, iy) = window_origin(self.cols, self.rows, self.resolution, centre);
        self.shift_to(ix, iy);
    }

    /// Moves the window origin to lattice cell `(origin_ix, origin_iy)`.
    pub fn shift_to(&mut self, origin_ix: i64, origin_iy: i64) {
        let dx = origin_ix.saturating_sub(self.origin_ix);
        let dy = origin_iy.saturating_sub(self.origin_iy);
        if dx.unsigned_abs() >= self.cols as u64 || dy.unsigned_abs() >= self.rows as u64 {
            self.slots.fill(self.fill.clone());
        } else {
            // Lattice columns that leave the window: their slots are the ones entering columns use.
            let leaving_cols = if dx > 0 {
                self.origin_ix..self.origin_ix + dx
            } else {
                self.origin_ix + self.cols as i64 + dx..self.origin_ix + self.cols as i64
            };
            for ix in leaving_cols {
                let slot_col = ix.rem_euclid(self.cols as i64) as usize;
                for slot_row in 0..self.rows {
                    self.slots[slot_row * self.cols + slot_col] = self.fill.clone();
                }
            }
            let leaving_rows = if dy > 0 {
                self.origin_iy..self.origin_iy + dy
            } else {
                self.origin_iy + self.rows as i64 + dy..self.origin_iy + self.rows as i64
            };
            for iy in leaving_rows {
                let slot_row = iy.rem_euclid(self.rows as i64) as usize;
                self.slots[slot_row * self.cols..(slot_row + 1) * self.cols].fill(self.fill.clone());
            }
        }
        self.origin_ix = origin_ix;
        self.origin_iy = origin_iy;
    }

    /// Resets every cell to the fill value.
    pub fn clear(&mut self) {
        self.slots.fill(self.fill.clone());
    }

    /// A dense copy of the window in row-major order (row 0 south), for export.
    pub fn to_grid2(&self) -> Grid2<T> {
        Grid2 { geometry: self.geometry(), data: self.iter_window().cloned().collect() }
    }
}

/// Lattice origin of a window whose central cell contains `centre`.
fn window_origin(cols: usize, rows: usize, resolution: f64, centre: Point2) -> (i64, i64) {
    (lattice(centre.x, resolution) - (cols / 2) as i64, lattice(centre.y, resolution) - (rows / 2) as i64)
}

impl<T> RollingGrid<T> {
    /// Number of columns of the window.
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// Number of rows of the window.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.resolution
    }
    /// Lattice index `(ix, iy)` of the window's south-west cell.
    pub fn origin_lattice(&self) -> (i64, i64) {
        (self.origin_ix, self.origin_iy)
    }
    /// World placement of the window as it stands now.
    pub fn geometry(&self) -> GridGeometry {
        GridGeometry {
            cols: self.cols,
            rows: self.rows,
            resolution: self.resolution,
            origin_x: self.origin_ix as f64 * self.resolution,
            origin_y: self.origin_iy as f64 * self.resolution,
        }
    }
    /// World coordinates of the centre of window cell `(col, row)`.
    pub fn center(&self, col: usize, row: usize) -> Point2 {
        Point2::new(
            (self.origin_ix + col as i64) as f64 * self.resolution + 0.5 * self.resolution,
            (self.origin_iy + row as i64) as f64 * self.resolution + 0.5 * self.resolution,
        )
    }
    /// Storage slot of window cell `(col, row)`; both must be inside the window.
    #[inline]
    fn slot(&self, col: usize, row: usize) -> usize {
        let sc = (self.origin_ix + col as i64).rem_euclid(self.cols as i64) as usize;
        let sr = (self.origin_iy + row as i64).rem_euclid(self.rows as i64) as usize;
        sr * self.cols + sc
    }
    /// Window cell `(col, row)` containing a world point, if inside the window.
    #[inline]
    pub fn cell_of(&self, x: f64, y: f64) -> Option<(usize, usize)> {
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let col = lattice(x, self.resolution) - self.origin_ix;
        let row = lattice(y, self.resolution) - self.origin_iy;
        if col >= 0 && row >= 0 && (col as usize) < self.cols && (row as usize) < self.rows {
            Some((col as usize, row as usize))
        } else {
            None
        }
    }
    /// The value of window cell `(col, row)`; panics outside the window, like slice indexing.
    pub fn get(&self, col: usize, row: usize) -> &T {
        assert!(col < self.cols && row < self.rows, "cell ({col}, {row}) outside the window");
        &self.slots[self.slot(col, row)]
    }
    /// Mutable value of window cell `(col, row)`; panics outside the window.
    pub fn get_mut(&mut self, col: usize, row: usize) -> &mut T {
        assert!(col < self.cols && row < self.rows, "cell ({col}, {row}) outside the window");
        let s = self.slot(col, row);
        &mut self.slots[s]
    }
    /// The value of the cell containing a world point, if inside the window.
    #[inline]
    pub fn at_world(&self, x: f64, y: f64) -> Option<&T> {
        self.cell_of(x, y).map(|(c, r)| &self.slots[self.slot(c, r)])
    }
    /// Mutable value of the cell containing a world point, if inside the window.
    #[inline]
    pub fn at_world_mut(&mut self, x: f64, y: f64) -> Option<&mut T> {
        let (c, r) = self.cell_of(x, y)?;
        let s = self.slot(c, r);
        Some(&mut self.slots[s])
    }
    /// Storage slot and world cell centre of the cell containing a world point, if inside the
    /// window: the hot path for binning many points (no integer division).
    #[inline]
    pub fn locate(&self, x: f64, y: f64) -> Option<(usize, Point2)> {
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let ix = lattice(x, self.resolution);
        let iy = lattice(y, self.resolution);
        let col = ix - self.origin_ix;
        let row = iy - self.origin_iy;
        if col < 0 || row < 0 || col as usize >= self.cols || row as usize >= self.rows {
            return None;
        }
        // Slot = (origin + offset) mod size, with origin mod size < size and offset < size.
        let mut sc = self.origin_ix.rem_euclid(self.cols as i64) as usize + col as usize;
        if sc >= self.cols {
            sc -= self.cols;
        }
        let mut sr = self.origin_iy.rem_euclid(self.rows as i64) as usize + row as usize;
        if sr >= self.rows {
            sr -= self.rows;
        }
        let center = Point2::new((ix as f64 + 0.5) * self.resolution, (iy as f64 + 0.5) * self.resolution);
        Some((sr * self.cols + sc, center))
    }

    /// Mutable value of a storage slot returned by [`RollingGrid::locate`].
    #[inline]
    pub fn slot_mut(&mut self, slot: usize) -> &mut T {
        &mut self.slots[slot]
    }

    /// Window row `row` as two contiguous storage runs (west part first).
    pub fn row_runs(&self, row: usize) -> (&[T], &[T]) {
        let sr = (self.origin_iy + row as i64).rem_euclid(self.rows as i64) as usize;
        let sc = self.origin_ix.rem_euclid(self.cols as i64) as usize;
        let storage_row = &self.slots[sr * self.cols..(sr + 1) * self.cols];
        (&storage_row[sc..], &storage_row[..sc])
    }
    /// All window cells in row-major order, row 0 south, column 0 west.
    pub fn iter_window(&self) -> impl Iterator<Item = &T> + '_ {
        (0..self.rows).flat_map(move |r| {
            let (a, b) = self.row_runs(r);
            a.iter().chain(b.iter())
        })
    }
}

/// The copy-on-move reference grid: same window semantics as [`RollingGrid`], but a move
/// allocates a new buffer and copies the overlapping cells. For tests and benchmarks.
#[derive(Clone, Debug)]
pub struct CopyingGrid<T> {
    grid: Grid2<T>,
    origin_ix: i64,
    origin_iy: i64,
    fill: T,
}

impl<T: Clone> CopyingGrid<T> {
    /// A window of `cols x rows` cells centred on `centre`, filled with `fill`.
    pub fn new(
        cols: usize,
        rows: usize,
        resolution: f64,
        fill: T,
        centre: Point2,
    ) -> Result<Self, MappingError> {
        check_shape(cols, rows, resolution)?;
        let (origin_ix, origin_iy) = window_origin(cols, rows, resolution, centre);
        let geometry = GridGeometry {
            cols,
            rows,
            resolution,
            origin_x: origin_ix as f64 * resolution,
            origin_y: origin_iy as f64 * resolution,
        };
        Ok(Self { grid: Grid2::filled(geometry, fill.clone()), origin_ix, origin_iy, fill })
    }

    /// Moves the window so that `centre` lies in its central cell, copying the overlap.
    pub fn recenter(&mut self, centre: Point2) {
        let g = self.grid.geometry;
        let (ix, iy) = window_origin(g.cols, g.rows, g.resolution, centre);
        self.shift_to(ix, iy);
    }

    /// Moves the window origin to lattice cell `(origin_ix, origin_iy)`, copying the overlap.
    pub fn shift_to(&mut self, origin_ix: i64, origin_iy: i64) {
        let g = self.grid.geometry;
        let mut data = vec![self.fill.clone(); g.len()];
        for row in 0..g.rows {
            let old_row = origin_iy + row as i64 - self.origin_iy;
            if old_row < 0 || old_row >= g.rows as i64 {
                continue;
            }
            for col in 0..g.cols {
                let old_col = origin_ix + col as i64 - self.origin_ix;
                if old_col >= 0 && old_col < g.cols as i64 {
                    data[row * g.cols + col] =
                        self.grid.data[old_row as usize * g.cols + old_col as usize].clone();
                }
            }
        }
        self.grid.data = data;
        self.origin_ix = origin_ix;
        self.origin_iy = origin_iy;
        self.grid.geometry.origin_x = origin_ix as f64 * g.resolution;
        self.grid.geometry.origin_y = origin_iy as f64 * g.resolution;
    }

    /// The window as a dense grid.
    pub fn grid(&self) -> &Grid2<T> {
        &self.grid
    }

    /// Mutable value of the cell containing a world point, if inside the window.
    pub fn at_world_mut(&mut self, x: f64, y: f64) -> Option<&mut T> {
        let g = self.grid.geometry;
        let col = lattice(x, g.resolution) - self.origin_ix;
        let row = lattice(y, g.resolution) - self.origin_iy;
        if col >= 0 && row >= 0 && (col as usize) < g.cols && (row as usize) < g.rows {
            Some(self.grid.get_mut(col as usize, row as usize))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn centre_lies_in_the_central_cell() {
        let g = RollingGrid::new(121, 121, 0.15, 0u8, Point2::new(10.02, -3.4)).unwrap();
        assert_eq!(g.cell_of(10.02, -3.4), Some((60, 60)));
        let geo = g.geometry();
        assert!(geo.contains(10.02, -3.4));
        assert_eq!(geo.cell_of(10.02, -3.4), Some((60, 60)));
    }

    #[test]
    fn cells_that_stay_keep_their_values_and_new_cells_are_clear() {
        let mut g = RollingGrid::new(5, 5, 1.0, 0i32, Point2::new(0.5, 0.5)).unwrap();
        // Window spans lattice -2..3 on both axes.
        *g.at_world_mut(2.5, 0.5).unwrap() = 7;
        *g.at_world_mut(-1.5, 0.5).unwrap() = 9;
        g.recenter(Point2::new(2.5, 0.5)); // window now spans 0..5 in x
        assert_eq!(g.at_world(2.5, 0.5), Some(&7));
        assert_eq!(g.at_world(-1.5, 0.5), None);
        // The slot that held 9 is now lattice x = 3 (3 mod 5 == -2 mod 5): it must read clear.
        assert_eq!(g.at_world(3.5, 0.5), Some(&0));
    }

    #[test]
    fn bad_shapes_are_rejected() {
        assert!(RollingGrid::new(0, 3, 0.1, 0u8, Point2::default()).is_err());
        assert!(RollingGrid::new(3, 3, f64::NAN, 0u8, Point2::default()).is_err());
        assert!(CopyingGrid::new(3, 3, -1.0, 0u8, Point2::default()).is_err());
    }

    #[derive(Clone, Debug)]
    enum Op {
        Move(f64, f64),
        Write(f64, f64, i32),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            (-4.0..4.0f64, -4.0..4.0f64).prop_map(|(x, y)| Op::Move(x, y)),
            (-4.0..4.0f64, -4.0..4.0f64, 1..1000i32).prop_map(|(x, y, v)| Op::Write(x, y, v)),
        ]
    }

    proptest! {
        /// After any sequence of moves and writes the torus reads exactly like a grid rebuilt
        /// by copying on every move.
        #[test]
        fn torus_matches_copying_grid(
            cols in 1usize..9, rows in 1usize..9, ops in prop::collection::vec(op(), 0..60)
        ) {
            let res = 0.35;
            let mut torus = RollingGrid::new(cols, rows, res, 0i32, Point2::default()).unwrap();
            let mut copy = CopyingGrid::new(cols, rows, res, 0i32, Point2::default()).unwrap();
            for op in ops {
                match op {
                    Op::Move(x, y) => {
                        torus.recenter(Point2::new(x, y));
                        copy.recenter(Point2::new(x, y));
                    }
                    Op::Write(x, y, v) => {
                        let located = torus.locate(x, y);
                        prop_assert_eq!(located.map(|(_, p)| torus.cell_of(p.x, p.y)), located.map(|_| torus.cell_of(x, y)));
                        let a = torus.at_world_mut(x, y).map(|c| { *c = v; });
                        if let Some((slot, _)) = located {
                            prop_assert_eq!(*torus.slot_mut(slot), v);
                        }
                        let b = copy.at_world_mut(x, y).map(|c| { *c = v; });
                        prop_assert_eq!(a.is_some(), b.is_some());
                    }
                }
                prop_assert_eq!(torus.geometry(), copy.grid().geometry);
                let dense = torus.to_grid2();
                prop_assert_eq!(&dense.data, &copy.grid().data);
                for r in 0..rows {
                    for c in 0..cols {
                        prop_assert_eq!(torus.get(c, r), copy.grid().get(c, r));
                    }
                }
            }
        }
    }
}
