//! Response surfaces against an independent code (statsmodels: golden/make_golden.py) and
//! against the reference study's printed tables 7 and 9.

mod bad_tables;
mod li2022;
mod solve;

use std::path::PathBuf;
use tilth_tools::rsm::{Data, FitOptions, Order, Table};

/// The study's tables, as committed under sweeps/li2022/data.
pub fn study(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../sweeps/li2022/data")
        .join(file)
}

pub fn golden() -> serde_json::Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/rsm/golden/golden.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

pub fn strings(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Table 9's runs for one response, factors named x4, x6, x7.
pub fn bbd(response: &str) -> Data {
    let t = Table::read(study("table09_bbd_runs.csv")).unwrap();
    Data::from_table(
        &t,
        &strings(&["x4_coded", "x6_coded", "x7_coded"]),
        response,
        None,
    )
    .unwrap()
    .renamed(&strings(&["x4", "x6", "x7"]))
    .unwrap()
}

pub fn quadratic() -> FitOptions {
    FitOptions {
        order: Order::Quadratic,
        curvature: false,
        backward: None,
    }
}

/// |a - b| within `rel` of |b| (or `rel` absolutely near zero).
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1.0)
}
