//! From one design to the next: the path of steepest ascent (or descent) from a first-order
//! fit, and the next design's ranges around the best point of a path that was run.
//!
//! References: Box & Wilson (1951); Montgomery, *Design and Analysis of Experiments*
//! (8th ed., 2013), sec. 11.2.

use super::terms::Term;
use super::{Anova, RsmError, Table};
use crate::design::steepest_ascent;
use serde::Serialize;

/// Points along the path, coded and real.
#[derive(Debug, Clone, Serialize)]
pub struct SteepestPath {
    /// Factors on the path and their coded direction (the fitted first-order coefficients,
    /// negated for descent).
    pub factors: Vec<String>,
    pub direction: Vec<f64>,
    /// Coded step of the leading factor (the one with the largest |coefficient|).
    pub step: f64,
    pub coded: Vec<Vec<f64>>,
    pub real: Vec<Vec<f64>>,
    /// Predicted response at each point (an extrapolation beyond the design's region).
    pub predicted: Vec<f64>,
}

/// The path from the design's centre along the first-order coefficients of `on` (indices
/// into the fit's factors), `steps` points with the leading factor moving `step` coded units
/// per point; the other factors stay at their centres.
pub fn steepest_path(
    a: &Anova,
    on: &[usize],
    step: f64,
    steps: usize,
    descent: bool,
) -> Result<SteepestPath, RsmError> {
    let coef = |i: usize| {
        a.fit
            .terms
            .iter()
            .zip(&a.fit.coef[1..])
            .find(|(t, _)| **t == Term::Linear(i))
            .map(|(_, b)| *b)
    };
    let mut direction = Vec::new();
    for &i in on {
        let b = coef(i).ok_or_else(|| {
            RsmError::Request(format!(
                "{} has no first-order term in the fit (removed or not a factor)",
                a.factors[i]
            ))
        })?;
        direction.push(if descent { -b } else { b });
    }
    let origin = vec![0.0; on.len()];
    let along = steepest_ascent(&direction, &origin, step, steps)
        .map_err(|e| RsmError::Request(e.to_string()))?;
    let k = a.factors.len();
    let coded: Vec<Vec<f64>> = along
        .iter()
        .map(|p| {
            let mut z = vec![0.0; k];
            for (v, &i) in p.iter().zip(on) {
                z[i] = *v;
            }
            z
        })
        .collect();
    Ok(SteepestPath {
        factors: on.iter().map(|&i| a.factors[i].clone()).collect(),
        direction,
        step,
        real: coded.iter().map(|z| a.coding.real(z)).collect(),
        predicted: coded.iter().map(|z| a.predict_coded(z)).collect(),
        coded,
    })
}

/// The best run of a path and the ranges for the next design around it.
#[derive(Debug, Clone, Serialize)]
pub struct NextRegion {
    /// Row (0-based, in table order) of the best run and its line in the file.
    pub best_row: usize,
    pub best_line: usize,
    /// Sum of squared relative misses over the targets, per row (or -response when
    /// maximising).
    pub scores: Vec<f64>,
    pub factors: Vec<String>,
    /// The best run's settings, and the next design's low and high levels.
    pub centre: Vec<f64>,
    pub low: Vec<f64>,
    pub high: Vec<f64>,
    pub statement: String,
}

/// The row of `table` (a path, in path order) whose `response` is best, scored by the sum
/// over `targets` of the squared relative miss ((y - t) / t)^2 (or the largest response
/// without targets), and the next design's ranges: the settings `neighbours` rows before and
/// after it (clamped to the path's ends).
pub fn next_region(
    table: &Table,
    factors: &[String],
    response: &str,
    targets: &[f64],
    neighbours: usize,
) -> Result<NextRegion, RsmError> {
    let y = table.numbers(response)?;
    let x: Vec<Vec<f64>> = factors
        .iter()
        .map(|f| table.numbers(f))
        .collect::<Result<_, _>>()?;
    if y.len() < 2 {
        return Err(RsmError::Request(format!(
            "{}: a path needs at least 2 runs, it has {}",
            table.source,
            y.len()
        )));
    }
    let scores: Vec<f64> = y
        .iter()
        .map(|v| {
            if targets.is_empty() {
                -v
            } else {
                targets.iter().map(|t| ((v - t) / t).powi(2)).sum()
            }
        })
        .collect();
    let best = (0..y.len())
        .min_by(|a, b| scores[*a].total_cmp(&scores[*b]))
        .unwrap_or(0);
    let lo_row = best.saturating_sub(neighbours);
    let hi_row = (best + neighbours).min(y.len() - 1);
    let pick = |row: usize| x.iter().map(|c| c[row]).collect::<Vec<f64>>();
    let (a, b) = (pick(lo_row), pick(hi_row));
    let low: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p.min(*q)).collect();
    let high: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p.max(*q)).collect();
    let centre = pick(best);
    let at_end = best == 0 || best == y.len() - 1;
    let statement = format!(
        "run {} (line {}) is best ({} = {}); the next design spans rows {}..{}: {}{}",
        best + 1,
        table.lines[best],
        response,
        y[best],
        lo_row + 1,
        hi_row + 1,
        factors
            .iter()
            .zip(low.iter().zip(&high))
            .map(|(f, (l, h))| format!("{f} {l}..{h}"))
            .collect::<Vec<_>>()
            .join(", "),
        if at_end {
            "; the best run is at the path's end, so the optimum may lie beyond it: extend the path first"
        } else {
            ""
        }
    );
    Ok(NextRegion {
        best_row: best,
        best_line: table.lines[best],
        scores,
        factors: factors.to_vec(),
        centre,
        low,
        high,
        statement,
    })
}
