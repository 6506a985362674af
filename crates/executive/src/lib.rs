//! rovernav executive layer.
