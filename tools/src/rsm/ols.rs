//! Ordinary least squares through the singular value decomposition: coefficients, the
//! inverse normal matrix (for standard errors) and leverages (for PRESS), with a rank test.

use nalgebra::{DMatrix, DVector};

/// Singular values below this fraction of the largest count as zero (an aliased column).
const RANK_TOL: f64 = 1e-10;

/// A least-squares fit of y on the columns of X.
#[derive(Debug, Clone)]
pub struct Ols {
    pub coef: Vec<f64>,
    pub fitted: Vec<f64>,
    /// Residual sum of squares.
    pub sse: f64,
    /// (X'X)^-1.
    pub xtx_inv: DMatrix<f64>,
    /// Diagonal of the hat matrix X (X'X)^-1 X'.
    pub leverage: Vec<f64>,
}

/// Fits y = X b; `None` when X does not have full column rank.
pub fn ols(x: &DMatrix<f64>, y: &[f64]) -> Option<Ols> {
    let (n, p) = x.shape();
    if n < p {
        return None;
    }
    let svd = x.clone().svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let s = &svd.singular_values;
    let smax = s.max();
    if p == 0 || s.min() <= RANK_TOL * smax {
        return None;
    }
    let yv = DVector::from_column_slice(y);
    let uty = u.transpose() * &yv;
    let inv_s = s.map(|v| 1.0 / v);
    let coef = vt.transpose() * DVector::from_iterator(p, (0..p).map(|k| uty[k] * inv_s[k]));
    let fitted = x * &coef;
    let sse = (&yv - &fitted).norm_squared();
    let v = vt.transpose();
    let xtx_inv = &v * DMatrix::from_diagonal(&inv_s.map(|v| v * v)) * v.transpose();
    let leverage = (0..n).map(|r| u.row(r).norm_squared()).collect();
    Some(Ols {
        coef: coef.iter().copied().collect(),
        fitted: fitted.iter().copied().collect(),
        sse,
        xtx_inv,
        leverage,
    })
}

/// Whether X has full column rank.
pub fn full_rank(x: &DMatrix<f64>) -> bool {
    let (n, p) = x.shape();
    if p == 0 {
        return true;
    }
    if n < p {
        return false;
    }
    let s = x.clone().svd(false, false).singular_values;
    s.min() > RANK_TOL * s.max()
}
