//! Typed errors of the mapping layer.

use thiserror::Error;

/// Why a map could not be built or updated.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MappingError {
    /// A size, resolution or other parameter is out of range.
    #[error("invalid parameter `{field}`: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A layer's data length does not match its geometry.
    #[error("layer `{layer}` holds {got} cells but its geometry has {expected}")]
    LayerSize {
        /// The layer's name.
        layer: &'static str,
        /// Cells the geometry implies.
        expected: usize,
        /// Cells present.
        got: usize,
    },
    /// A layer is placed differently from the others of the same map.
    #[error("layer `{layer}` has a different geometry from the `elevation` layer")]
    GeometryMismatch {
        /// The layer's name.
        layer: &'static str,
    },
}
