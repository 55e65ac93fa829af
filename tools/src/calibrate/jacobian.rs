//! Linearised uncertainty: with residuals r(theta) = (f(theta) - y) / sigma, the Jacobian J
//! at the optimum gives cov(theta) = (J' J)^-1 (Bates & Watts 1988, ch. 2). When J' J is
//! singular the data cannot fix every parameter: its null space is the direction along which
//! the parameters trade off without changing the fit (a ridge), and that is reported instead.

use nalgebra::DMatrix;
use serde::Serialize;

/// The result at one optimum.
#[derive(Debug, Clone, Serialize)]
pub struct Linearised {
    /// Rank of J (how many parameter combinations the data fix).
    pub rank: usize,
    /// Standard errors and 95 % intervals (normal) per parameter, when J has full rank.
    pub std_error: Option<Vec<f64>>,
    pub ci95: Option<Vec<(f64, f64)>>,
    /// Unit directions (in parameter units) that leave the residuals unchanged to first order.
    pub null_directions: Vec<Vec<f64>>,
    /// Each parameter's 95 % interval with all the others held at the optimum (always
    /// defined while the residuals depend on it).
    pub conditional_ci95: Vec<Option<(f64, f64)>>,
}

/// Linearised uncertainty of `theta` for the standardised residuals `r` (each residual divided
/// by its standard deviation). `step` is each parameter's finite-difference step.
pub fn linearised(r: impl Fn(&[f64]) -> Vec<f64>, theta: &[f64], step: &[f64]) -> Linearised {
    let p = theta.len();
    let m = r(theta).len();
    let mut j = DMatrix::<f64>::zeros(m, p);
    for k in 0..p {
        let (mut a, mut b) = (theta.to_vec(), theta.to_vec());
        a[k] += step[k];
        b[k] -= step[k];
        let (ra, rb) = (r(&a), r(&b));
        for i in 0..m {
            j[(i, k)] = (ra[i] - rb[i]) / (2.0 * step[k]);
        }
    }
    // Zero rows up to p make the decomposition return every right singular vector.
    let padded = DMatrix::from_fn(m.max(p), p, |i, k| if i < m { j[(i, k)] } else { 0.0 });
    let svd = padded.svd(false, true);
    let s = &svd.singular_values;
    let smax = s.iter().copied().fold(0.0, f64::max);
    let tol = 1e-8 * smax.max(1e-300);
    let rank = s.iter().filter(|v| **v > tol).count();
    let vt = svd.v_t.expect("requested");
    let null_directions = (0..p)
        .filter(|&k| k >= s.len() || s[k] <= tol)
        .map(|k| vt.row(k).iter().copied().collect())
        .collect();
    let z = 1.959963984540054;
    let conditional_ci95 = (0..p)
        .map(|k| {
            let g2: f64 = (0..m).map(|i| j[(i, k)].powi(2)).sum();
            (g2 > 0.0).then(|| {
                let se = 1.0 / g2.sqrt();
                (theta[k] - z * se, theta[k] + z * se)
            })
        })
        .collect();
    let (std_error, ci95) = if rank == p {
        match (j.transpose() * &j).try_inverse() {
            Some(cov) => {
                let se: Vec<f64> = (0..p).map(|k| cov[(k, k)].max(0.0).sqrt()).collect();
                let ci = se
                    .iter()
                    .zip(theta)
                    .map(|(e, t)| (t - z * e, t + z * e))
                    .collect();
                (Some(se), Some(ci))
            }
            None => (None, None),
        }
    } else {
        (None, None)
    };
    Linearised {
        rank,
        std_error,
        ci95,
        null_directions,
        conditional_ci95,
    }
}
