//! The elevation model and its queries.

use rovernav_core::{Grid2, GridGeometry};

/// Maps the local frame of a DEM (metres from its south-west corner) to projected coordinates.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GeoReference {
    /// Coordinate reference system, as text (e.g. "Mars2000 equidistant cylindrical").
    pub crs: String,
    /// Projected easting of local (0, 0) (m).
    pub easting: f64,
    /// Projected northing of local (0, 0) (m).
    pub northing: f64,
}

impl Default for GeoReference {
    fn default() -> Self {
        Self { crs: "local".into(), easting: 0.0, northing: 0.0 }
    }
}

/// A digital elevation model: heights on a regular grid, NaN where there is no data.
#[derive(Clone, Debug, PartialEq)]
pub struct Dem {
    /// Heights (m); the grid's origin is local (0, 0) unless the DEM was cut from a larger one.
    pub heights: Grid2<f32>,
    /// The nodata value of the source file, if it had one (already replaced by NaN).
    pub nodata: Option<f32>,
    /// Georeference of the local frame.
    pub geo: GeoReference,
}

/// A rock: a body sitting on the terrain (paper 000's Mars-yard obstacles).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Rock {
    /// Centre east (local m).
    pub x: f64,
    /// Centre north (local m).
    pub y: f64,
    /// Diameter (m).
    pub diameter: f64,
    /// Height above the surrounding ground (m).
    pub height: f64,
}

/// A terrain: the elevation model (rocks included in its heights) and the rock bodies on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Terrain {
    /// Heights, with rocks already added.
    pub dem: Dem,
    /// The rocks, for ground truth and drawing.
    pub rocks: Vec<Rock>,
}

impl Dem {
    /// A DEM from a height grid with a local georeference.
    pub fn from_grid(heights: Grid2<f32>) -> Self {
        Self { heights, nodata: None, geo: GeoReference::default() }
    }

    /// A flat DEM of the given size.
    pub fn flat(cols: usize, rows: usize, resolution: f64, z: f32) -> Self {
        let geometry = GridGeometry { cols, rows, resolution, origin_x: 0.0, origin_y: 0.0 };
        Self::from_grid(Grid2::filled(geometry, z))
    }

    /// Grid placement.
    pub fn geometry(&self) -> &GridGeometry {
        &self.heights.geometry
    }

    /// Height at a world point by bilinear interpolation between cell centres; `None` outside
    /// the grid or where any of the four cells has no data.
    pub fn height(&self, x: f64, y: f64) -> Option<f64> {
        let g = &self.heights.geometry;
        let fx = (x - g.origin_x) / g.resolution - 0.5;
        let fy = (y - g.origin_y) / g.resolution - 0.5;
        if !(fx >= -0.5 && fy >= -0.5 && fx <= g.cols as f64 - 0.5 && fy <= g.rows as f64 - 0.5) {
            return None;
        }
        let fx = fx.clamp(0.0, (g.cols - 1) as f64);
        let fy = fy.clamp(0.0, (g.rows - 1) as f64);
        let c0 = (fx.floor() as usize).min(g.cols.saturating_sub(2));
        let r0 = (fy.floor() as usize).min(g.rows.saturating_sub(2));
        let c1 = (c0 + 1).min(g.cols - 1);
        let r1 = (r0 + 1).min(g.rows - 1);
        let tx = fx - c0 as f64;
        let ty = fy - r0 as f64;
        let h00 = *self.heights.get(c0, r0) as f64;
        let h10 = *self.heights.get(c1, r0) as f64;
        let h01 = *self.heights.get(c0, r1) as f64;
        let h11 = *self.heights.get(c1, r1) as f64;
        let h = (h00 * (1.0 - tx) + h10 * tx) * (1.0 - ty) + (h01 * (1.0 - tx) + h11 * tx) * ty;
        h.is_finite().then_some(h)
    }

    /// Projected (easting, northing) of a local point.
    pub fn to_projected(&self, x: f64, y: f64) -> (f64, f64) {
        (self.geo.easting + x, self.geo.northing + y)
    }

    /// Local point of projected (easting, northing).
    pub fn to_local(&self, easting: f64, northing: f64) -> (f64, f64) {
        (easting - self.geo.easting, northing - self.geo.northing)
    }
}
