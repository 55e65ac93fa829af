//! SVG pictures of a response surface: contour plot with a target line, the response against
//! one free factor with its targets, Pareto chart of the
//! standardized effects, main effects, predicted against actual.
//!
//! Drawn as the reducers' pictures are (plotters' SVG backend, text left to the viewer).

mod contour;
mod curve;
mod main_effects;
mod pareto;
mod predicted_vs_actual;

pub use contour::{contour_marked_svg, contour_svg};
pub use curve::{CheckRuns, response_curve_checked_svg, response_curve_svg};
pub use main_effects::main_effects_svg;
pub use pareto::pareto_svg;
pub use predicted_vs_actual::predicted_vs_actual_svg;

use super::{Anova, RsmError};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::RGBColor;

const FONT: &str = "sans-serif";
const BLUE: RGBColor = RGBColor(31, 119, 180);
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(127, 127, 127);
/// Tableau's ten colours.
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A chart in data coordinates on an SVG page, as every picture here draws.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Maps any drawing error to [`RsmError::Plot`] for the picture `what`.
fn err<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> RsmError {
    move |e| RsmError::Plot {
        what: what.to_string(),
        problem: e.to_string(),
    }
}

/// The legend, upper left on an opaque box.
fn legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>, what: &'static str) -> Result<(), RsmError> {
    legend_at(chart, what, SeriesLabelPosition::UpperLeft)
}

/// The legend at `position` on an opaque box.
fn legend_at<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    what: &'static str,
    position: SeriesLabelPosition,
) -> Result<(), RsmError> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 12))
        .background_style(WHITE)
        .border_style(BLACK)
        .draw()
        .map_err(err(what))
}

/// The factors not held at a value by `fixed`, in order: the axes of a picture.
fn free_factors(a: &Anova, fixed: &[(usize, f64)]) -> Vec<usize> {
    (0..a.factors.len())
        .filter(|i| !fixed.iter().any(|f| f.0 == *i))
        .collect()
}

/// "name = value" of each fixed factor, for a title or a legend entry.
fn fixed_text(a: &Anova, fixed: &[(usize, f64)]) -> Vec<String> {
    fixed
        .iter()
        .map(|(k, v)| format!("{} = {v}", a.factors[*k]))
        .collect()
}

/// The corner of the plot area `[x0, x1] x [y0, y1]` holding the fewest of `points`, for the
/// legend (a box of about 45 % of the width and 30 % of the height), so that it does not
/// cover the data or a target's label. Ties go in the order upper left, upper right, lower
/// left, lower right.
fn quietest_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    let corners = [
        (SeriesLabelPosition::UpperLeft, true, true),
        (SeriesLabelPosition::UpperRight, false, true),
        (SeriesLabelPosition::LowerLeft, true, false),
        (SeriesLabelPosition::LowerRight, false, false),
    ];
    let count = |left: bool, upper: bool| {
        points
            .iter()
            .filter(|(px, py)| {
                let in_x = if left {
                    *px <= x.0 + 0.45 * w
                } else {
                    *px >= x.1 - 0.45 * w
                };
                let in_y = if upper {
                    *py >= y.1 - 0.3 * h
                } else {
                    *py <= y.0 + 0.3 * h
                };
                in_x && in_y
            })
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperLeft);
    for (pos, left, upper) in corners {
        let n = count(left, upper);
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::quietest_corner;
    use plotters::prelude::SeriesLabelPosition as P;

    /// A rising curve with its target's label along the top left (the repose curve at 12 %,
    /// where the label sat under the legend): the legend leaves the upper left for the lower
    /// right, the one corner without points.
    #[test]
    fn the_legend_goes_to_the_corner_with_fewest_points() {
        let mut pts: Vec<(f64, f64)> = (0..=10)
            .map(|k| (k as f64 / 10.0, 40.0 + k as f64 / 2.0))
            .collect();
        pts.extend((0..=8).map(|k| (k as f64 / 20.0, 44.8)));
        let at = quietest_corner(&pts, (0.0, 1.0), (40.0, 45.0));
        assert!(matches!(at, P::LowerRight), "{at:?}");
        // Nothing anywhere: the usual upper left.
        assert!(matches!(
            quietest_corner(&[], (0.0, 1.0), (0.0, 1.0)),
            P::UpperLeft
        ));
        // Only the upper left taken: the upper right.
        let at = quietest_corner(&[(0.1, 0.9)], (0.0, 1.0), (0.0, 1.0));
        assert!(matches!(at, P::UpperRight), "{at:?}");
    }
}
