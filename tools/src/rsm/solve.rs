//! Solving a fitted surface for a target: every setting, within the factors' ranges, whose
//! predicted response equals the target.
//!
//! With one free factor the answer is a few points; with two it is a curve (a ridge of
//! equally good settings), with three a surface. Returning one arbitrary point of a ridge,
//! as a desirability optimiser does, hides that the target cannot separate the factors; here
//! the whole set is traced and its extent reported.
//!
//! Tracing: for each free factor in turn as the "solved" one, the others run over a grid in
//! coded units and the quadratic in the solved factor, a z^2 + b z + c = target, is solved
//! exactly (the model is at most quadratic in each factor). Taking every factor in turn as
//! the solved one catches the steep stretches of a curve that one grid direction misses.

use super::{Anova, RsmError};
use serde::Serialize;

/// Grid points per free factor (the solved one excluded): two free factors give a curve of
/// up to 2 x 201 points, three a surface of up to 3 x 41^2.
fn grid_size(free: usize) -> usize {
    match free {
        0 | 1 => 1,
        2 => 201,
        3 => 41,
        4 => 15,
        _ => 7,
    }
}

/// One solution: settings in real units (every factor, fixed ones included).
#[derive(Debug, Clone, Serialize)]
pub struct Setting {
    pub values: Vec<f64>,
    pub predicted: f64,
}

/// All the settings that hit one target.
#[derive(Debug, Clone, Serialize)]
pub struct Solution {
    pub label: String,
    pub target: f64,
    /// Names of the factors that were free.
    pub free: Vec<String>,
    /// Dimension of the solution set (free factors - 1) when it is not empty.
    pub dimension: usize,
    pub settings: Vec<Setting>,
    /// Each factor's (min, max) over the settings, real units.
    pub extent: Vec<(String, f64, f64)>,
    /// Whether the target pins the free factors down to (about) one point.
    pub identifiable: bool,
    /// When nothing reaches the target: the closest setting on a grid and its prediction.
    pub closest: Option<Setting>,
    /// The finding in words.
    pub statement: String,
}

/// Solves `anova`'s surface for `target`, with `fixed` factors held at real values and the
/// others free within their coded range [-1, 1] (the design's region; the surface is not
/// trusted outside it).
pub fn solve(
    anova: &Anova,
    label: &str,
    target: f64,
    fixed: &[(usize, f64)],
) -> Result<Solution, RsmError> {
    let k = anova.factors.len();
    let fixed_z = fixed_coded(anova, fixed);
    let free: Vec<usize> = (0..k).filter(|i| fixed_z[*i].is_none()).collect();
    if free.is_empty() {
        return Err(RsmError::Request(
            "every factor is fixed: nothing to solve for".into(),
        ));
    }
    let points = trace(anova, &fixed_z, &free, target);
    let settings: Vec<Setting> = points
        .iter()
        .map(|z| Setting {
            values: anova.coding.real(z),
            predicted: anova.predict_coded(z),
        })
        .collect();
    let free_names: Vec<String> = free.iter().map(|&i| anova.factors[i].clone()).collect();
    let extent = extent(anova, &settings);
    let moving = moving(anova, &free, &extent, settings.len());
    let identifiable = !settings.is_empty() && moving.len() < 2;
    let (closest, statement) = if settings.is_empty() {
        let c = closest_setting(anova, &fixed_z, &free, target);
        let s = format!(
            "no setting within the design's ranges predicts {target} for {}; the closest, {}, predicts {:.4}",
            anova.response,
            describe(&anova.factors, &c.values),
            c.predicted
        );
        (Some(c), s)
    } else if identifiable {
        (
            None,
            format!(
                "{} setting(s) predict {target}: the target pins the free factors ({}) down",
                settings.len(),
                free_names.join(", ")
            ),
        )
    } else {
        let ridge = ridge_statement(anova, free.len(), &moving, settings.len(), target);
        (None, ridge)
    };
    Ok(Solution {
        label: label.to_string(),
        target,
        free: free_names,
        dimension: if settings.is_empty() {
            0
        } else {
            free.len() - 1
        },
        settings,
        extent,
        identifiable,
        closest,
        statement,
    })
}

/// Each factor's fixed value in coded units, z = (x - centre) / half-range; `None` if free.
fn fixed_coded(anova: &Anova, fixed: &[(usize, f64)]) -> Vec<Option<f64>> {
    (0..anova.factors.len())
        .map(|i| {
            fixed
                .iter()
                .find(|f| f.0 == i)
                .map(|f| (f.1 - anova.coding.centre(i)) / anova.coding.half(i))
        })
        .collect()
}

/// Every coded setting within [-1, 1] that hits `target`: each free factor in turn solved
/// exactly along grid lines of the others, sorted along the free factors and with
/// duplicates (within 1e-9) removed.
fn trace(anova: &Anova, fixed_z: &[Option<f64>], free: &[usize], target: f64) -> Vec<Vec<f64>> {
    let n = grid_size(free.len());
    let mut points: Vec<Vec<f64>> = Vec::new();
    for &solved in free {
        let others: Vec<usize> = free.iter().copied().filter(|i| *i != solved).collect();
        let total = n.pow(others.len() as u32);
        for flat in 0..total {
            let mut z: Vec<f64> = fixed_z.iter().map(|v| v.unwrap_or(0.0)).collect();
            let mut rest = flat;
            for &o in &others {
                let g = rest % n;
                rest /= n;
                z[o] = if n == 1 {
                    0.0
                } else {
                    -1.0 + 2.0 * g as f64 / (n - 1) as f64
                };
            }
            for root in roots_along(anova, &z, solved, target) {
                let mut p = z.clone();
                p[solved] = root;
                points.push(p);
            }
        }
    }
    // One list along the first free factor (then the others).
    points.sort_by(|a, b| {
        free.iter()
            .map(|&i| a[i].total_cmp(&b[i]))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    points.dedup_by(|a, b| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9));
    points
}

/// Each factor's (name, min, max) over `settings`, real units.
fn extent(anova: &Anova, settings: &[Setting]) -> Vec<(String, f64, f64)> {
    (0..anova.factors.len())
        .map(|i| {
            let (lo, hi) = settings
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                    (a.min(s.values[i]), b.max(s.values[i]))
                });
            (anova.factors[i].clone(), lo, hi)
        })
        .collect()
}

/// The free factors that move along the solutions, as (name, min, max, share of the range):
/// those spanning over a tenth of their range, when there is more than one setting.
fn moving(
    anova: &Anova,
    free: &[usize],
    extent: &[(String, f64, f64)],
    settings: usize,
) -> Vec<(String, f64, f64, f64)> {
    free.iter()
        .map(|&i| {
            let e = &extent[i];
            let frac = (e.2 - e.1) / (anova.coding.high[i] - anova.coding.low[i]);
            (e.0.clone(), e.1, e.2, frac)
        })
        .filter(|s| settings > 1 && s.3 > 0.1)
        .collect()
}

/// The finding when the target cannot separate the `moving` factors: the ridge (two free
/// factors) or surface of `settings` points, and how far each factor moves along it.
fn ridge_statement(
    anova: &Anova,
    free: usize,
    moving: &[(String, f64, f64, f64)],
    settings: usize,
    target: f64,
) -> String {
    let along: Vec<String> = moving
        .iter()
        .map(|(name, lo, hi, _)| {
            format!("{name} from {} to {}", significant4(*lo), significant4(*hi))
        })
        .collect();
    let names: Vec<&str> = moving.iter().map(|m| m.0.as_str()).collect();
    format!(
        "one target cannot separate {}: every setting on this {} of {} points predicts {} = {target} ({} along it). Fix all but one of them, or add an observable that depends on them differently (a shear or compression test, a second repose test).",
        names.join(" and "),
        if free == 2 {
            "ridge (a curve)"
        } else {
            "surface"
        },
        settings,
        anova.response,
        along.join(", ")
    )
}

/// Roots in [-1, 1] of predicted(z with z[i] = t) = target: the surface is at most
/// quadratic in t, so three evaluations give its coefficients exactly.
fn roots_along(anova: &Anova, z: &[f64], i: usize, target: f64) -> Vec<f64> {
    let at = |t: f64| {
        let mut p = z.to_vec();
        p[i] = t;
        anova.predict_coded(&p) - target
    };
    let (f0, f1, fm) = (at(0.0), at(1.0), at(-1.0));
    let a = 0.5 * (f1 + fm) - f0;
    let b = 0.5 * (f1 - fm);
    let c = f0;
    let scale = f0.abs().max(f1.abs()).max(fm.abs()).max(1e-300);
    let mut out = Vec::new();
    if a.abs() <= 1e-12 * scale {
        if b.abs() > 1e-12 * scale {
            out.push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let s = disc.sqrt();
            // The numerically stable pair of roots.
            let q = -0.5 * (b + b.signum() * s);
            out.push(q / a);
            if q != 0.0 {
                out.push(c / q);
            }
        }
    }
    out.retain(|t| (-1.0 - 1e-12..=1.0 + 1e-12).contains(t));
    out.iter().map(|t| t.clamp(-1.0, 1.0)).collect()
}

fn closest_setting(anova: &Anova, fixed_z: &[Option<f64>], free: &[usize], target: f64) -> Setting {
    let n: usize = match free.len() {
        1 => 401,
        2 => 101,
        3 => 31,
        _ => 9,
    };
    let total = n.pow(free.len() as u32);
    let mut best: Option<(f64, Vec<f64>)> = None;
    for flat in 0..total {
        let mut z: Vec<f64> = fixed_z.iter().map(|v| v.unwrap_or(0.0)).collect();
        let mut rest = flat;
        for &o in free {
            z[o] = -1.0 + 2.0 * (rest % n) as f64 / (n - 1) as f64;
            rest /= n;
        }
        let miss = (anova.predict_coded(&z) - target).abs();
        if best.as_ref().is_none_or(|b| miss < b.0) {
            best = Some((miss, z));
        }
    }
    let z = best.map(|b| b.1).unwrap_or_default();
    Setting {
        values: anova.coding.real(&z),
        predicted: anova.predict_coded(&z),
    }
}

fn describe(names: &[String], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} = {}", significant4(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

fn significant4(v: f64) -> String {
    super::equation::significant(v, 4)
}
