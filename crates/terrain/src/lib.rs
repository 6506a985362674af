//! rovernav terrain layer.
