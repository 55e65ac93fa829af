//! The fitted equation as text, in coded units and in real units.
//!
//! Real-unit coefficients follow by substituting z_i = (x_i - c_i) / h_i into the coded
//! equation and collecting monomials (Myers, Montgomery & Anderson-Cook 2016, sec. 2.8): an
//! interaction b z_i z_j contributes b / (h_i h_j) to x_i x_j, -b c_j / (h_i h_j) to x_i,
//! -b c_i / (h_i h_j) to x_j and b c_i c_j / (h_i h_j) to the constant.

use super::Coding;
use super::anova::FitState;
use super::terms::Term;
use std::collections::BTreeMap;

/// A monomial: factor indices, sorted (empty: the constant).
type Monomial = Vec<usize>;

/// Coefficients in real units, by name, in Design-Expert's order (`intercept`, main effects,
/// interactions, squares). The curvature indicator has no real-unit form and is left out.
pub(crate) fn real_coefficients(
    s: &FitState,
    coding: &Coding,
    names: &[String],
) -> Vec<(String, f64)> {
    let mut poly: BTreeMap<Monomial, f64> = BTreeMap::new();
    let mut add = |m: Monomial, v: f64| *poly.entry(m).or_insert(0.0) += v;
    add(vec![], s.coef[0]);
    let (c, h) = (|i| coding.centre(i), |i| coding.half(i));
    for (t, &b) in s.terms.iter().zip(&s.coef[1..]) {
        match *t {
            Term::Linear(i) => {
                add(vec![i], b / h(i));
                add(vec![], -b * c(i) / h(i));
            }
            Term::Interaction(i, j) => {
                let k = b / (h(i) * h(j));
                add(vec![i, j], k);
                add(vec![i], -k * c(j));
                add(vec![j], -k * c(i));
                add(vec![], k * c(i) * c(j));
            }
            Term::Square(i) => {
                let k = b / (h(i) * h(i));
                add(vec![i, i], k);
                add(vec![i], -2.0 * k * c(i));
                add(vec![], k * c(i) * c(i));
            }
            Term::Curvature => {}
        }
    }
    let mut out = vec![("intercept".to_string(), poly.remove(&vec![]).unwrap_or(0.0))];
    let name = |m: &Monomial| match m.as_slice() {
        [i] => names[*i].clone(),
        [i, j] if i == j => format!("{}^2", names[*i]),
        [i, j] => format!("{}*{}", names[*i], names[*j]),
        _ => unreachable!("monomials have degree 1 or 2"),
    };
    // Present in the order of the coded terms.
    for t in &s.terms {
        let m = match *t {
            Term::Linear(i) => vec![i],
            Term::Interaction(i, j) => vec![i, j],
            Term::Square(i) => vec![i, i],
            Term::Curvature => continue,
        };
        if let Some(v) = poly.remove(&m) {
            out.push((name(&m), v));
        }
    }
    // Linear monomials produced by interactions or squares of factors without a main effect.
    for (m, v) in poly {
        out.push((name(&m), v));
    }
    out
}

/// `response = b0 + b1 x1 - b2 x1*x2 ...` in coded units.
pub(crate) fn coded(response: &str, s: &FitState, names: &[String]) -> String {
    let mut list = vec![("intercept".to_string(), s.coef[0])];
    list.extend(
        s.terms
            .iter()
            .zip(&s.coef[1..])
            .map(|(t, b)| (t.name(names), *b)),
    );
    format(response, &list)
}

/// Formats (term, coefficient) pairs as an equation.
pub fn format(response: &str, list: &[(String, f64)]) -> String {
    let mut out = format!("{response} =");
    for (k, (name, v)) in list.iter().enumerate() {
        let sign = if *v < 0.0 { "-" } else { "+" };
        // Six significant digits; an exponent only for extreme magnitudes.
        let a = v.abs();
        let mag = if a == 0.0 || (1e-4..1e7).contains(&a) {
            significant(a, 6)
        } else {
            format!("{a:.5e}")
        };
        out += &match (k, name.as_str()) {
            (0, "intercept") => format!(" {}{mag}", if *v < 0.0 { "-" } else { "" }),
            _ => format!(" {sign} {mag} {name}"),
        };
    }
    out
}

/// `v` with `digits` significant digits, in plain decimal notation (0 and non-finite values
/// as Rust prints them).
pub fn significant(v: f64, digits: u32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let d = (digits as i32 - 1 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.d$}")
}
