//! rovernav viz layer.
