//! Model terms in coded units: main effects, two-factor interactions, squares, and the
//! curvature indicator of a screening design with centre points.

use serde::Serialize;

/// How many terms: the model orders of Design-Expert and R's `rsm` (`FO`, `FO + TWI`, `SO`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Order {
    /// Main effects only.
    Linear,
    /// Main effects and two-factor interactions.
    #[serde(rename = "2fi")]
    TwoFi,
    /// Main effects, interactions and squares.
    Quadratic,
}

impl Order {
    pub fn parse(s: &str) -> Option<Order> {
        match s {
            "linear" => Some(Order::Linear),
            "2fi" => Some(Order::TwoFi),
            "quadratic" => Some(Order::Quadratic),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Order::Linear => "linear",
            Order::TwoFi => "2fi",
            Order::Quadratic => "quadratic",
        }
    }
}

/// One column of the model matrix (the intercept is implicit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Term {
    /// x_i
    Linear(usize),
    /// x_i x_j, i < j
    Interaction(usize, usize),
    /// x_i^2
    Square(usize),
    /// 1 at centre points, 0 elsewhere: its coefficient is the centre's departure from the
    /// plane through the corners (Design-Expert's "Curvature" row).
    Curvature,
}

impl Term {
    /// Every term of `order` for `k` factors, in Design-Expert's order (A, B, ..., AB, AC, ...,
    /// A^2, ...).
    pub fn all(order: Order, k: usize) -> Vec<Term> {
        let mut out: Vec<Term> = (0..k).map(Term::Linear).collect();
        if order != Order::Linear {
            for i in 0..k {
                for j in i + 1..k {
                    out.push(Term::Interaction(i, j));
                }
            }
        }
        if order == Order::Quadratic {
            out.extend((0..k).map(Term::Square));
        }
        out
    }

    /// The term's value at a run with coded settings `z`.
    pub fn value(self, z: &[f64]) -> f64 {
        match self {
            Term::Linear(i) => z[i],
            Term::Interaction(i, j) => z[i] * z[j],
            Term::Square(i) => z[i] * z[i],
            Term::Curvature => f64::from(is_centre(z)),
        }
    }

    /// Name from the factor names: `x4`, `x4*x6`, `x4^2`, `curvature`.
    pub fn name(self, factors: &[String]) -> String {
        match self {
            Term::Linear(i) => factors[i].clone(),
            Term::Interaction(i, j) => format!("{}*{}", factors[i], factors[j]),
            Term::Square(i) => format!("{}^2", factors[i]),
            Term::Curvature => "curvature".into(),
        }
    }

    /// The factors the term contains (a main effect stays while a higher term needs it).
    pub fn factors(self) -> Vec<usize> {
        match self {
            Term::Linear(i) | Term::Square(i) => vec![i],
            Term::Interaction(i, j) => vec![i, j],
            Term::Curvature => vec![],
        }
    }
}

/// A run whose coded settings are all zero.
pub fn is_centre(z: &[f64]) -> bool {
    z.iter().all(|v| v.abs() < 1e-9)
}

/// A term name in a canonical form, so that `x4*x6`, `x4_x6`, `x4:x6`, `AB`-style sources and
/// `x4^2`, `x4_sq`, `I(x4^2)` match when comparing with a reported table.
pub fn canonical(name: &str) -> String {
    let n = name.trim().to_ascii_lowercase();
    let n = n
        .trim_start_matches("i(")
        .trim_end_matches(')')
        .replace(['^', '²'], "_sq")
        .replace("_sq2", "_sq");
    let n = n.replace(['*', ':'], "_");
    match n.as_str() {
        "error" | "residuals" => "residual".into(),
        "lack of fit" => "lack_of_fit".into(),
        "r2" | "r_sq" | "r_squared" | "r-squared" => "r_squared".into(),
        _ => n,
    }
}
