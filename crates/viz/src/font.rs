//! The one font of every chart: DejaVu Sans, embedded (`fonts/DejaVuSans.ttf`) so that text looks
//! the same on every machine and no system font is looked up (plotters' `ab_glyph` backend).
//!
//! DejaVu Sans is free software: Bitstream Vera licence with DejaVu's changes in the public domain
//! (`crates/viz/fonts/LICENSE-DejaVu.txt`); it may be redistributed and embedded.

use plotters::style::{FontFamily, FontStyle, register_font};
use std::sync::Once;

/// The family name charts ask for.
pub const FAMILY: &str = "sans-serif";

static DEJAVU_SANS: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// Registers the embedded font with plotters (once per process; later calls do nothing).
pub fn ensure() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded file is a valid TrueType font; a failure here would only leave text out.
        let _ = register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS);
        let _ = register_font(FAMILY, FontStyle::Bold, DEJAVU_SANS);
    });
}

/// The chart font family.
pub fn family() -> FontFamily<'static> {
    ensure();
    FontFamily::Name(FAMILY)
}
