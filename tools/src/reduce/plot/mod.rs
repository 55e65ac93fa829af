//! SVG pictures of the reductions, one per result kind, each returned as the SVG text.
//!
//! Drawn with `plotters`' SVG backend without its font features: text goes into the SVG as
//! `<text>` elements and the viewer renders it, so no font files or fontconfig are needed
//! where the pictures are made (the layout of labels uses plotters' fixed estimate of text
//! width instead of real glyph metrics, which is close enough for axis labels and legends).
//! A picture of an incomplete file says so in its title.

mod mohr_coulomb;
mod repose;
mod shear;
mod tilt;
mod ucs;

pub use mohr_coulomb::mohr_coulomb_svg;
pub use repose::repose_svg;
pub use shear::shear_svg;
pub use tilt::tilt_svg;
pub use ucs::ucs_svg;

use super::error::ReduceError;
use super::read::RunSource;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::RGBColor;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The font family every text uses; the SVG viewer picks the actual face.
const FONT: &str = "sans-serif";
/// Height of the two-line title block above a chart, px.
const TITLE_HEIGHT: u32 = 52;

/// Blue and orange of the usual 10-colour palette (Tableau), and their darker shades for
/// lines drawn over points of the same colour.
const BLUE: RGBColor = RGBColor(31, 119, 180);
const DARK_BLUE: RGBColor = RGBColor(16, 60, 120);
const ORANGE: RGBColor = RGBColor(255, 127, 14);
const DARK_ORANGE: RGBColor = RGBColor(170, 70, 0);
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(127, 127, 127);
/// Grid lines, as solid light greys rather than black with opacity, which some SVG
/// renderers ignore.
const GRID_FINE: RGBColor = RGBColor(238, 238, 238);
const GRID_BOLD: RGBColor = RGBColor(205, 205, 205);

/// A chart in data coordinates on an SVG page, as every picture here draws.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Maps any drawing error to [`ReduceError::Plot`] for the picture `what`.
fn plot_error<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> ReduceError {
    move |e| ReduceError::Plot {
        what: what.to_string(),
        problem: e.to_string(),
    }
}

/// Draws `title` and, below it, the file the numbers came from (red, and saying so, when the
/// file is incomplete) at the top of `area`, and returns the area left for the chart.
fn title_block<'a>(
    area: &DrawingArea<SVGBackend<'a>, Shift>,
    title: &str,
    source: &RunSource,
    what: &'static str,
) -> Result<DrawingArea<SVGBackend<'a>, Shift>, ReduceError> {
    let subtitle = if source.complete {
        source.file.clone()
    } else {
        format!(
            "{} (INCOMPLETE FILE: numbers from the part that was read)",
            source.file
        )
    };
    titled(area, title, &subtitle, source.complete, what)
}

/// Draws `title` and `subtitle` (red unless `complete`) at the top of `area`, and returns
/// the area left for the chart.
fn titled<'a>(
    area: &DrawingArea<SVGBackend<'a>, Shift>,
    title: &str,
    subtitle: &str,
    complete: bool,
    what: &'static str,
) -> Result<DrawingArea<SVGBackend<'a>, Shift>, ReduceError> {
    area.fill(&WHITE).map_err(plot_error(what))?;
    let (top, rest) = area.split_vertically(TITLE_HEIGHT);
    let width = top.dim_in_pixel().0 as i32;
    // Anchored at the baseline: the SVG then needs no `dy` shift, which some renderers
    // ignore.
    let centred = |size: u32| {
        TextStyle::from((FONT, size).into_font()).pos(Pos::new(HPos::Center, VPos::Bottom))
    };
    top.draw_text(title, &centred(20), (width / 2, 24))
        .map_err(plot_error(what))?;
    let style = centred(13).color(if complete { &BLACK } else { &RED });
    top.draw_text(subtitle, &style, (width / 2, 44))
        .map_err(plot_error(what))?;
    Ok(rest)
}

/// Draws the grid, axes and labels of `chart` in the common style.
fn mesh<'a, 'b>(
    chart: &mut Chart<'a, 'b>,
    x_desc: &str,
    y_desc: &str,
    what: &'static str,
) -> Result<(), ReduceError> {
    chart
        .configure_mesh()
        .light_line_style(GRID_FINE)
        .bold_line_style(GRID_BOLD)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((FONT, 13))
        .draw()
        .map_err(plot_error(what))
}

/// Draws the legend of `chart` at `position` on an opaque white box.
fn legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    position: SeriesLabelPosition,
    what: &'static str,
) -> Result<(), ReduceError> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 12))
        .background_style(WHITE)
        .border_style(BLACK)
        .draw()
        .map_err(plot_error(what))
}

/// `lo..hi` widened by `pad` of its span on each side, never empty.
fn padded(lo: f64, hi: f64, pad: f64) -> std::ops::Range<f64> {
    let span = if hi > lo { hi - lo } else { 1.0 };
    (lo - pad * span)..(hi + pad * span)
}
