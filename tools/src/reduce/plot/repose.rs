//! The heap's silhouettes with the lines fitted to their halves.
//!
//! Both axes are in millimetres at the same scale, so the drawn slopes are the measured
//! angles as a person would see them on the photograph.

use super::{
    BLUE, Chart, DARK_BLUE, DARK_ORANGE, GREY, ORANGE, TITLE_HEIGHT, legend, mesh, plot_error,
    title_block,
};
use crate::reduce::error::ReduceError;
use crate::reduce::repose::{HalfFit, ReposeAnalysis, ReposeResult, ViewFit};
use crate::reduce::silhouette::{SilhouetteMethod, View};
use plotters::prelude::*;
use plotters::style::RGBColor;
use std::ops::Range;

const WHAT: &str = "the repose silhouette";
/// Line colours of photographs taken all around the heap.
const AROUND: [RGBColor; 6] = [
    RGBColor(16, 60, 120),
    RGBColor(170, 70, 0),
    RGBColor(44, 130, 44),
    RGBColor(150, 30, 30),
    RGBColor(110, 70, 160),
    RGBColor(120, 80, 60),
];
/// Width of the plotting area, px; its height follows from the data at equal scale.
const PLOT_WIDTH: u32 = 760;
const MARGIN: u32 = 15;
const X_LABELS: u32 = 45;
const Y_LABELS: u32 = 55;

/// Millimetres per metre: the picture is drawn in mm.
const MM: f64 = 1e3;

/// The silhouette of each view (points), the tray top, the height band fitted (dashed) and
/// the line fitted to each half over that band, with the angles and R^2 in the legend.
pub fn repose_svg(result: &ReposeResult) -> Result<String, ReduceError> {
    let a = &result.analysis;
    let frame = Frame::of(a);
    let title = format!(
        "Angle of repose {:.2}° (mean of {} halves; cone fit {:.2}°)",
        a.repose_angle_deg,
        2 * a.views.len(),
        a.cone.angle_deg
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, frame.size).into_drawing_area();
        let area = title_block(&root, &title, &result.source, WHAT)?;
        let mut chart = ChartBuilder::on(&area)
            .margin(MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(frame.x.clone(), frame.y.clone())
            .map_err(plot_error(WHAT))?;
        mesh(
            &mut chart,
            "horizontal distance from the tray axis (mm)",
            "height above the tray top (mm)",
            WHAT,
        )?;
        draw_tray_and_band(&mut chart, a)?;
        let x = (frame.x.start, frame.x.end);
        for (k, w) in a.views.iter().enumerate() {
            if frame.around {
                draw_view_around(&mut chart, a, k, w, x)?;
            } else {
                draw_view_pair(&mut chart, a, w, x)?;
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, WHAT)?;
        root.present().map_err(plot_error(WHAT))?;
    }
    Ok(svg)
}

/// The picture's ranges (mm) and size (px). x spans the tray with 2 mm to spare; y runs from
/// 3 mm below the tray top to 8 % above the heap, plus room for the legend (about 18 px an
/// entry) so that it hides no point. Both axes at the same scale, PLOT_WIDTH px across x.
struct Frame {
    x: Range<f64>,
    y: Range<f64>,
    size: (u32, u32),
    /// Whether the views are photographs all around the heap (one legend entry each) rather
    /// than the x-z and y-z pair (three each).
    around: bool,
}

impl Frame {
    fn of(a: &ReposeAnalysis) -> Frame {
        let r = a.tray.radius_m * MM;
        let x = (-r - 2.0)..(r + 2.0);
        let around = a.views.iter().any(|w| matches!(w.view, View::Azimuth(_)));
        let entries = 2 + if around {
            1 + a.views.len()
        } else {
            3 * a.views.len()
        };
        let px_per_mm = PLOT_WIDTH as f64 / (x.end - x.start);
        let y = -3.0..(a.heap_height_m * MM * 1.08 + (18 * entries + 24) as f64 / px_per_mm);
        let plot_height = ((y.end - y.start) * px_per_mm).round() as u32;
        let size = (
            PLOT_WIDTH + Y_LABELS + 2 * MARGIN,
            plot_height + X_LABELS + 2 * MARGIN + TITLE_HEIGHT,
        );
        Frame { x, y, size, around }
    }
}

/// How the silhouette's points were taken, for the legend.
fn method_text(method: SilhouetteMethod) -> &'static str {
    match method {
        SilhouetteMethod::Envelope => "outline at bin centres",
        SilhouetteMethod::HighestTop => "highest top per bin",
    }
}

/// The tray top (thick black) and the two heights of the band fitted (dashed grey), with
/// their legend entries.
fn draw_tray_and_band<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &ReposeAnalysis,
) -> Result<(), ReduceError> {
    let r = a.tray.radius_m * MM;
    chart
        .draw_series(LineSeries::new(
            [(-r, 0.0), (r, 0.0)],
            BLACK.stroke_width(3),
        ))
        .map_err(plot_error(WHAT))?
        .label(format!("tray top, radius {r:.1} mm"))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(3)));
    for (k, h) in [a.band_m.0, a.band_m.1].into_iter().enumerate() {
        let series = chart
            .draw_series(DashedLineSeries::new(
                [(-r, h * MM), (r, h * MM)],
                6,
                4,
                GREY.stroke_width(1),
            ))
            .map_err(plot_error(WHAT))?;
        if k == 0 {
            series
                .label(format!(
                    "band fitted: {:.0}-{:.0} % of the heap height ({:.1} mm)",
                    100.0 * a.band_fraction.0,
                    100.0 * a.band_fraction.1,
                    a.heap_height_m * MM
                ))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], GREY));
        }
    }
    Ok(())
}

/// Photograph `k` of those taken all around: faint points in its own colour and a thin line
/// per half, one legend entry for the photograph (the first also names the silhouettes).
fn draw_view_around<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &ReposeAnalysis,
    k: usize,
    w: &ViewFit,
    x: (f64, f64),
) -> Result<(), ReduceError> {
    let colour = AROUND[k % AROUND.len()];
    let series = chart
        .draw_series(
            w.silhouette_m
                .iter()
                .map(|&(u, h)| Circle::new((u * MM, h * MM), 1, colour.mix(0.5).filled())),
        )
        .map_err(plot_error(WHAT))?;
    if k == 0 {
        series
            .label(format!(
                "silhouettes ({})",
                method_text(a.silhouette_method)
            ))
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, GREY.filled()));
    }
    for (side, half) in [(0, w.left), (1, w.right)] {
        let series = chart
            .draw_series(LineSeries::new(
                band_line(&half, a.band_m, MM, x),
                colour.stroke_width(1),
            ))
            .map_err(plot_error(WHAT))?;
        if side == 0 {
            series
                .label(format!(
                    "{}: {:.2}° / {:.2}°",
                    w.view.axis(),
                    w.left.angle_deg,
                    w.right.angle_deg
                ))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
    }
    Ok(())
}

/// The x-z (blue) or y-z (orange) photograph: its points, and each half's line in the darker
/// shade, each with its legend entry (angle, R^2 and points for a half).
fn draw_view_pair<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &ReposeAnalysis,
    w: &ViewFit,
    x: (f64, f64),
) -> Result<(), ReduceError> {
    let (points, line): (RGBColor, RGBColor) = match w.view {
        View::Yz => (ORANGE, DARK_ORANGE),
        _ => (BLUE, DARK_BLUE),
    };
    let name = match w.view {
        View::Yz => "y-z",
        _ => "x-z",
    };
    chart
        .draw_series(
            w.silhouette_m
                .iter()
                .map(|&(u, h)| Circle::new((u * MM, h * MM), 2, points.filled())),
        )
        .map_err(plot_error(WHAT))?
        .label(format!(
            "{name} silhouette ({})",
            method_text(a.silhouette_method)
        ))
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, points.filled()));
    for (side, half) in [("left", w.left), ("right", w.right)] {
        chart
            .draw_series(LineSeries::new(
                band_line(&half, a.band_m, MM, x),
                line.stroke_width(2),
            ))
            .map_err(plot_error(WHAT))?
            .label(format!(
                "{name} {side}: {:.2}° (R² {:.3}, {} points)",
                half.angle_deg, half.r_squared, half.points
            ))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], line.stroke_width(2)));
    }
    Ok(())
}

/// The fitted line h = a + b u between the band's heights, in mm, cut where it leaves the
/// frame's horizontal range `u_mm`. (The plotting crate pins a point outside the frame to its
/// edge instead of cutting the segment, which would bend the drawn line and show a slope
/// other than the measured one.)
fn band_line(half: &HalfFit, band_m: (f64, f64), mm: f64, u_mm: (f64, f64)) -> [(f64, f64); 2] {
    let (a, b) = (half.intercept_m * mm, half.slope);
    let u = |h: f64| (h - a) / b;
    let clip = |p: (f64, f64)| {
        let uc = p.0.clamp(u_mm.0, u_mm.1);
        if uc == p.0 { p } else { (uc, a + b * uc) }
    };
    [band_m.0, band_m.1].map(|h| clip((u(h * mm), h * mm)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn half(angle_deg: f64, intercept_m: f64) -> HalfFit {
        HalfFit {
            angle_deg,
            slope: -angle_deg.to_radians().tan(),
            intercept_m,
            r_squared: 1.0,
            points: 10,
        }
    }

    #[test]
    fn a_line_inside_the_frame_runs_between_the_band_heights() {
        // h = 20 - u (mm): at h = 5 and 15, u = 15 and 5.
        let l = band_line(&half(45.0, 0.020), (0.005, 0.015), 1e3, (-33.0, 33.0));
        assert!((l[0].0 - 15.0).abs() < 1e-9 && (l[0].1 - 5.0).abs() < 1e-9);
        assert!((l[1].0 - 5.0).abs() < 1e-9 && (l[1].1 - 15.0).abs() < 1e-9);
    }

    #[test]
    fn a_line_leaving_the_frame_is_cut_at_its_edge_with_its_slope_kept() {
        // A 20 degree right half from 25 mm at the axis reaches the band's foot (2 mm) at
        // u = 63 mm, beyond the frame's 33 mm: the drawn end is at u = 33 on the same line.
        let h = half(20.0, 0.025);
        let l = band_line(&h, (0.002, 0.020), 1e3, (-33.0, 33.0));
        assert!((l[0].0 - 33.0).abs() < 1e-9);
        let drawn_slope = (l[1].1 - l[0].1) / (l[1].0 - l[0].0);
        assert!(
            (drawn_slope - h.slope).abs() < 1e-12,
            "drawn {drawn_slope}, fitted {}",
            h.slope
        );
        assert!((l[0].1 - (25.0 + h.slope * 33.0)).abs() < 1e-9);
    }
}
