//! rovernav navigation layer.
