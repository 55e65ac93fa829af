//! Weighted least squares in a box, for calibrating shared parameters to several observables
//! at once on cheap surrogates (fitted response surfaces).
//!
//! Minimise S(theta) = sum_i r_i(theta)^2 over low <= theta <= high, with r_i the standardised
//! residuals (f_i(theta) - y_i) / sigma_i. The surrogates are quadratics, so S is smooth but
//! may have several minima in the box: a grid over the whole box finds the best basin, and a
//! compass search (step halving, Kolda, Lewis & Torczon 2003) polishes it without
//! derivatives, staying inside the box.

use nalgebra::{DMatrix, DVector};

/// Grid points per parameter for the global stage: finer for fewer parameters, at most
/// about 20,000 evaluations in all.
fn grid_points(k: usize) -> usize {
    match k {
        0 => 1,
        1 => 201,
        2 => 101,
        3 => 27,
        _ => ((20_000f64).powf(1.0 / k as f64).floor() as usize).max(3),
    }
}

/// The minimiser of `s` over the box `[low, high]`.
pub fn minimise_in_box(s: impl Fn(&[f64]) -> f64, low: &[f64], high: &[f64]) -> Vec<f64> {
    let k = low.len();
    let n = grid_points(k);
    let at = |idx: &[usize]| -> Vec<f64> {
        idx.iter()
            .enumerate()
            .map(|(j, &i)| low[j] + (high[j] - low[j]) * i as f64 / (n - 1).max(1) as f64)
            .collect()
    };
    let mut idx = vec![0usize; k];
    let mut best = at(&idx);
    let mut best_s = s(&best);
    'grid: loop {
        let mut j = 0;
        loop {
            if j == k {
                break 'grid;
            }
            idx[j] += 1;
            if idx[j] < n {
                break;
            }
            idx[j] = 0;
            j += 1;
        }
        let x = at(&idx);
        let v = s(&x);
        if v < best_s {
            best_s = v;
            best = x;
        }
    }
    // Compass search from the best grid point.
    let mut step: Vec<f64> = (0..k)
        .map(|j| (high[j] - low[j]) / (n - 1).max(1) as f64)
        .collect();
    let tiny: Vec<f64> = (0..k).map(|j| 1e-9 * (high[j] - low[j])).collect();
    while step.iter().zip(&tiny).any(|(a, b)| a > b) {
        let mut moved = false;
        for j in 0..k {
            for sign in [1.0, -1.0] {
                let mut x = best.clone();
                x[j] = (x[j] + sign * step[j]).clamp(low[j], high[j]);
                let v = s(&x);
                if v < best_s {
                    best_s = v;
                    best = x;
                    moved = true;
                }
            }
        }
        if !moved {
            step.iter_mut().for_each(|h| *h *= 0.5);
        }
    }
    best
}

/// One Gauss-Newton step for standardised residuals `r` with Jacobian `j` (rows: residuals,
/// columns: parameters): the least-squares solution of J d = -r, by SVD so that directions
/// the data do not fix get no step (minimum-norm solution).
pub fn gauss_newton_step(j: &[Vec<f64>], r: &[f64]) -> Vec<f64> {
    let m = r.len();
    let p = j.first().map_or(0, |row| row.len());
    if m == 0 || p == 0 {
        return vec![0.0; p];
    }
    let jm = DMatrix::from_fn(m, p, |a, b| j[a][b]);
    let rv = DVector::from_column_slice(r);
    let svd = jm.svd(true, true);
    let eps = 1e-10 * svd.singular_values.max();
    match svd.solve(&(-rv), eps) {
        Ok(d) => d.iter().copied().collect(),
        Err(_) => vec![0.0; p],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_weighted_least_squares_point_of_two_lines() {
        // f1 = theta (y1 = 1, sigma 1), f2 = theta (y2 = 3, sigma 2): the weighted mean
        // (1/1 * 1 + 1/4 * 3) / (1 + 1/4) = 1.4.
        let s = |t: &[f64]| (t[0] - 1.0).powi(2) + ((t[0] - 3.0) / 2.0).powi(2);
        let x = minimise_in_box(s, &[0.0], &[5.0]);
        assert!((x[0] - 1.4).abs() < 1e-7, "{x:?}");
    }

    #[test]
    fn stays_in_the_box_and_finds_the_global_basin() {
        // Two basins: a shallow one at (-0.8, 0) and the deepest at (0.7, 0.5); the unbounded
        // minimum in x is outside the box at y = 0.5.
        let s = |t: &[f64]| {
            let a = 1.0 - (-((t[0] + 0.8).powi(2) + t[1].powi(2)) / 0.05).exp();
            let b = 2.0 - 2.5 * (-((t[0] - 0.7).powi(2) + (t[1] - 0.5).powi(2)) / 0.05).exp();
            a.min(b)
        };
        let x = minimise_in_box(s, &[-1.0, -1.0], &[1.0, 1.0]);
        assert!(
            (x[0] - 0.7).abs() < 1e-6 && (x[1] - 0.5).abs() < 1e-6,
            "{x:?}"
        );
        let edge = minimise_in_box(|t: &[f64]| (t[0] - 2.0).powi(2), &[-1.0], &[1.0]);
        assert_eq!(edge, vec![1.0]);
    }

    #[test]
    fn gauss_newton_solves_a_linear_problem_in_one_step_and_skips_a_ridge() {
        // r = J theta - y at theta = 0: the step is the least-squares solution.
        let j = vec![vec![1.0, 0.0], vec![0.0, 2.0], vec![1.0, 1.0]];
        let y = [1.0, 2.0, 2.0];
        let r: Vec<f64> = y.iter().map(|v| -v).collect();
        let d = gauss_newton_step(&j, &r);
        // Normal equations: [[2, 1], [1, 5]] d = [3, 6] -> d = (1, 1).
        assert!(
            (d[0] - 1.0).abs() < 1e-12 && (d[1] - 1.0).abs() < 1e-12,
            "{d:?}"
        );
        // Both parameters enter only as their sum: the step is along (1, 1), none across.
        let ridge = gauss_newton_step(&[vec![1.0, 1.0], vec![2.0, 2.0]], &[-2.0, -4.0]);
        assert!((ridge[0] - ridge[1]).abs() < 1e-12);
        assert!((ridge[0] + ridge[1] - 2.0).abs() < 1e-12, "{ridge:?}");
    }
}
