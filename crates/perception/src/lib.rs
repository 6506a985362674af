//! rovernav perception layer.
