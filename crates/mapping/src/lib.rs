//! rovernav mapping layer.
