//! Loaders of elevation models and images from files: GeoTIFF, PDS3 IMG (attached or detached
//! label) and NumPy `.npy`.
//!
//! This is the one module of the crate that touches the file system. Every error names the file
//! and, where there is one, the field or tag at fault; corrupt input gives an error, never a
//! panic.

use std::path::{Path, PathBuf};

use thiserror::Error;

pub mod geotiff;
pub mod npy;
pub mod pds3;

pub use geotiff::{load_geotiff, parse_geotiff};
pub use npy::{load_npy, parse_npy, save_npy, to_npy_bytes};
pub use pds3::{CahvorModel, GlobalDem, Pds3Block, Pds3Image, Pds3Label, Pds3Value, SampleType};

/// Why a file could not be loaded. The first field of every variant is the file.
#[derive(Debug, Error)]
pub enum LoadError {
    /// The file could not be opened or read.
    #[error("{}: {source}", .file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The TIFF decoder rejected the file.
    #[error("{}: TIFF: {source}", .file.display())]
    Tiff {
        /// The file.
        file: PathBuf,
        /// The decoder's error.
        source: tiff::TiffError,
    },
    /// A required GeoTIFF tag is absent.
    #[error("{}: GeoTIFF tag {name} ({code}) missing", .file.display())]
    MissingTag {
        /// The file.
        file: PathBuf,
        /// Tag name.
        name: &'static str,
        /// Tag number.
        code: u16,
    },
    /// A required label keyword or header field is absent.
    #[error("{}: field {field} missing", .file.display())]
    MissingField {
        /// The file.
        file: PathBuf,
        /// The field.
        field: String,
    },
    /// A field is present but its value is unusable.
    #[error("{}: field {field}: {reason}", .file.display())]
    InvalidField {
        /// The file.
        file: PathBuf,
        /// The field.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A syntax error in a text label or header.
    #[error("{}:{line}: {message}", .file.display())]
    Syntax {
        /// The file.
        file: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file ends before the data its header describes.
    #[error("{}: truncated: {what} needs {needed} bytes from offset {offset}, file has {actual}", .file.display())]
    Truncated {
        /// The file.
        file: PathBuf,
        /// The part that does not fit.
        what: String,
        /// Bytes needed.
        needed: u64,
        /// Offset the part starts at.
        offset: u64,
        /// File length.
        actual: u64,
    },
    /// A valid file using a feature this loader does not handle.
    #[error("{}: unsupported: {what}", .file.display())]
    Unsupported {
        /// The file.
        file: PathBuf,
        /// The feature.
        what: String,
    },
}

impl LoadError {
    /// The file the error is about.
    pub fn file(&self) -> &Path {
        match self {
            LoadError::Io { file, .. }
            | LoadError::Tiff { file, .. }
            | LoadError::MissingTag { file, .. }
            | LoadError::MissingField { file, .. }
            | LoadError::InvalidField { file, .. }
            | LoadError::Syntax { file, .. }
            | LoadError::Truncated { file, .. }
            | LoadError::Unsupported { file, .. } => file,
        }
    }

    pub(crate) fn io(file: &Path, source: std::io::Error) -> Self {
        LoadError::Io { file: file.to_path_buf(), source }
    }

    pub(crate) fn invalid(file: &Path, field: impl Into<String>, reason: impl Into<String>) -> Self {
        LoadError::InvalidField { file: file.to_path_buf(), field: field.into(), reason: reason.into() }
    }

    pub(crate) fn missing(file: &Path, field: impl Into<String>) -> Self {
        LoadError::MissingField { file: file.to_path_buf(), field: field.into() }
    }

    pub(crate) fn unsupported(file: &Path, what: impl Into<String>) -> Self {
        LoadError::Unsupported { file: file.to_path_buf(), what: what.into() }
    }
}

/// Reads a whole file, naming it in the error.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    std::fs::read(path).map_err(|e| LoadError::io(path, e))
}
