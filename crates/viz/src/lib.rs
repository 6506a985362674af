//! Pictures of runs, drawn with plotters (text, axes, legends and colour bars) in the embedded
//! DejaVu Sans ([`font`]): the traverse picture ([`traverse`]), the per-run timeline
//! ([`timeline`]) and, through the re-exported [`plotters`], a campaign's charts; and the picture
//! of an instrument placement ([`placement`], on the small raster [`Canvas`]).

mod canvas;
pub mod font;
pub mod placement;
pub mod timeline;
pub mod traverse;

pub use canvas::{Canvas, Rgb};
pub use plotters;
pub use traverse::{TraverseScene, encode_png};

/// The traverse picture of a run (`traverse.png`): the same drawing for `rovernav run`, its
/// replay and a campaign's failure gallery.
pub fn run_traverse_png(
    report: &rovernav_executive::Report,
    world: &rovernav_executive::World,
    trace: &rovernav_executive::Trace,
) -> std::io::Result<Vec<u8>> {
    traverse::traverse_png(&TraverseScene {
        terrain: &world.terrain,
        rover: &world.rover,
        start: world.start.position(),
        goal: &world.goal,
        trace,
        report,
    })
}

/// The timeline of a run (`timeline.svg`, `timeline.png`): SVG text and PNG bytes.
pub fn run_timeline(
    report: &rovernav_executive::Report,
    world: &rovernav_executive::World,
    trace: &rovernav_executive::Trace,
) -> std::io::Result<(String, Vec<u8>)> {
    timeline::timeline(report, trace, world.goal.position, world.goal.tolerance)
}
