//! Tables that cannot be fitted are refused with a message that says why.

use super::*;
use tilth_tools::rsm::{RsmError, fit};

fn write(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rsm-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn quadratic_error(csv: &str, name: &str, factors: &[&str]) -> String {
    let p = write(name, csv);
    let t = Table::read(&p).unwrap();
    match Data::from_table(&t, &strings(factors), "y", None) {
        Err(e) => e.to_string(),
        Ok(d) => fit(&d, quadratic()).unwrap_err().to_string(),
    }
}

#[test]
fn too_few_runs() {
    // 2 factors, quadratic: 6 coefficients; 5 runs.
    let e = quadratic_error(
        "a,b,y\n-1,-1,1\n1,-1,2\n-1,1,3\n1,1,5\n0,0,2\n",
        "few.csv",
        &["a", "b"],
    );
    assert!(
        e.contains("few.csv") && e.contains("5 runs are too few") && e.contains("at least 7"),
        "{e}"
    );
}

#[test]
fn constant_column() {
    let e = quadratic_error("a,b,y\n1,0,1\n1,1,2\n1,-1,3\n", "constant.csv", &["a", "b"]);
    assert!(
        e.contains("constant.csv") && e.contains("factor column a is constant"),
        "{e}"
    );
}

#[test]
fn missing_response() {
    let e = quadratic_error("a,b,y\n-1,-1,1\n1,-1,\n", "missing.csv", &["a", "b"]);
    assert!(e.contains("missing.csv: line 3: y is missing"), "{e}");
}

#[test]
fn not_a_number() {
    let e = quadratic_error("a,b,y\n-1,-1,1\n1,x,2\n", "text.csv", &["a", "b"]);
    assert!(
        e.contains("text.csv: line 3: b = \"x\" is not a number"),
        "{e}"
    );
}

#[test]
fn unknown_column() {
    let e = quadratic_error("a,b,y\n-1,-1,1\n", "cols.csv", &["a", "c"]);
    assert!(
        e.contains("no column \"c\"") && e.contains("columns: a, b, y"),
        "{e}"
    );
}

/// A two-level design with centre points cannot tell the squares apart: x2^2 is aliased
/// with x1^2 (both are 1 at every corner, 0 at the centre).
#[test]
fn aliased_terms() {
    let t = Table::read(study("table06_pb_runs.csv")).unwrap();
    let factors: Vec<String> = (1..=3).map(|i| format!("x{i}")).collect();
    let d = Data::from_table(&t, &factors, "repose_angle_deg", None).unwrap();
    let e = fit(
        &d,
        FitOptions {
            order: Order::Quadratic,
            curvature: false,
            backward: None,
        },
    )
    .unwrap_err();
    assert!(matches!(e, RsmError::Aliased { .. }), "{e}");
    assert!(e.to_string().contains("term x2^2 is aliased"), "{e}");
}
