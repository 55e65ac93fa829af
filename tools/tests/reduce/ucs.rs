//! Unconfined compression runs with curves computed by hand.

use crate::fixture::{Fixture, write_file};
use tilth_tools::reduce::plot::ucs_svg;
use tilth_tools::reduce::*;

fn ucs_file(name: &str, curve: &[(f64, f64)]) -> std::path::PathBuf {
    let mut f = Fixture::new(
        &[("run_id", "5"), ("seed", "9")],
        &[
            ("type", "ucs"),
            ("diameter_m", "0.0618"),
            ("height_m", "0.04"),
        ],
    );
    for (k, &(eps, force)) in curve.iter().enumerate() {
        f.scalars(
            0.2 * k as f64,
            &[
                ("axial_strain", eps),
                ("axial_force", force),
                ("inertial_number", 2e-5),
            ],
        );
    }
    write_file(name, &f.finish())
}

fn read(path: &std::path::Path) -> UcsResult {
    let run = read_run(
        path,
        &ReadOptions {
            cloud: CloudChoice::None,
        },
    )
    .unwrap();
    ucs(&run, &UcsOptions::default()).unwrap()
}

/// sigma = F (1 - eps) / A_0 with A_0 = pi 0.0618^2 / 4 = 2.999624e-3 m^2: the stress peaks
/// at eps = 0.10 (F = 200 N: 180 N / A_0 = 60.0075 kPa) although the force still rises to
/// 203 N at 0.12 (178.64 N / A_0 = 59.5542 kPa).
#[test]
fn strength_at_the_stress_peak() {
    let curve = [
        (0.0, 0.0),
        (0.02, 60.0),
        (0.05, 150.0),
        (0.10, 200.0),
        (0.12, 203.0),
        (0.14, 180.0),
        (0.16, 150.0),
    ];
    let path = ucs_file("ucs-peak.mcap", &curve);
    let r = read(&path);
    let a = &r.analysis;
    assert!(r.source.complete);
    assert_eq!(a.failure, Failure::Peak);
    assert!((a.ucs_kpa - 60.0075).abs() < 1e-4, "{}", a.ucs_kpa);
    assert!((a.strain_at_failure - 0.10).abs() < 1e-12);
    assert_eq!(a.force_at_failure_n, 200.0);
    assert_eq!(a.peak_force_n, 203.0);
    assert!((a.corrected_area_at_failure_m2 - 2.999_624e-3 / 0.9).abs() < 1e-8);
    assert_eq!(a.curve.len(), 7);
    assert!((a.curve[4].1 - 59.5542).abs() < 1e-4);
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["ucs_kpa"], a.ucs_kpa);
    assert_eq!(json["failure"], "peak");
    let svg = ucs_svg(&r).unwrap();
    assert!(svg.contains("failure (peak): 60.01 kPa"));
    std::fs::write(path.with_extension("svg"), svg).unwrap();
}

/// F = 1000 N * eps keeps sigma rising past 15 %: failure is sigma at 15 %,
/// 150 N * 0.85 / A_0 = 42.5053 kPa.
#[test]
fn strength_at_fifteen_percent_when_still_rising() {
    let curve: Vec<(f64, f64)> = (0..=20)
        .map(|k| (k as f64 * 0.01, k as f64 * 10.0))
        .collect();
    let path = ucs_file("ucs-rising.mcap", &curve);
    let r = read(&path);
    assert_eq!(r.analysis.failure, Failure::StrainLimit);
    assert!(
        (r.analysis.ucs_kpa - 42.5053).abs() < 1e-4,
        "{}",
        r.analysis.ucs_kpa
    );
    std::fs::write(path.with_extension("svg"), ucs_svg(&r).unwrap()).unwrap();
}
