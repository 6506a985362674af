//! rovernav localization layer.
