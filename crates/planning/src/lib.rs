//! rovernav planning layer.
