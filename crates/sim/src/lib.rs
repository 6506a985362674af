//! rovernav sim layer.
