//! Typed errors of the perception layer.

use rovernav_mapping::MappingError;
use thiserror::Error;

/// Why terrain assessment could not be set up or run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PerceptionError {
    /// A configuration value is out of range.
    #[error("invalid terrain configuration `{field}`: {reason}")]
    InvalidConfig {
        /// The parameter's name.
        field: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The map layer refused its parameters.
    #[error(transparent)]
    Mapping(#[from] MappingError),
    /// Two inputs that must be co-registered are not.
    #[error("`{what}` does not match the geometry of the sensed maps")]
    GeometryMismatch {
        /// The mismatching input.
        what: &'static str,
    },
}
