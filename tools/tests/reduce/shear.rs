//! Direct shear runs with made-up curves whose peaks are known.

use crate::fixture::{Fixture, write_file};
use tilth_tools::reduce::plot::{mohr_coulomb_svg, shear_svg};
use tilth_tools::reduce::*;

pub const AREA: f64 = 3.0e-3;

/// Shear force of the made-up curve: F(s) = F_p x e^(1 - x), x = s / s_p, whose maximum is
/// F_p at s = s_p exactly.
pub fn force(s: f64, peak: f64, at: f64) -> f64 {
    let x = s / at;
    peak * x * (1.0 - x).exp()
}

/// Samples of a direct shear file: every 0.01 mm from 0 to 5 mm (so a peak at a multiple of
/// 0.01 mm is sampled exactly).
pub const SAMPLES: usize = 501;

/// A direct shear file with the first `samples` of [`SAMPLES`], a chunk closed after every
/// `per_chunk` samples; returns the fixture (not finished: a test may take the bytes a
/// crash would leave) and the file's length after each closed chunk.
pub fn shear_fixture(
    pressure: f64,
    peak: f64,
    at: f64,
    per_chunk: usize,
    samples: usize,
) -> (Fixture, Vec<usize>) {
    let p = pressure.to_string();
    let mut f = Fixture::new(
        &[
            ("run_id", "3"),
            ("seed", "1"),
            ("factor.bond_stiffness", "1e9"),
        ],
        &[
            ("type", "direct_shear"),
            ("diameter_m", "0.0618"),
            ("area_m2", "0.003"),
            ("normal_pressure_pa", p.as_str()),
        ],
    );
    let mut ends = Vec::new();
    for k in 0..samples {
        let s = k as f64 * 1e-5;
        let t = 0.5 + k as f64 * 2e-3;
        f.scalars(
            t,
            &[
                ("shear_displacement", s),
                ("shear_force", force(s, peak, at)),
                ("normal_force", pressure * AREA),
                ("inertial_number", 1e-4),
            ],
        );
        if (k + 1) % per_chunk == 0 {
            f.flush();
            ends.push(f.killed_now().len());
        }
    }
    (f, ends)
}

#[test]
fn peak_shear_force_from_a_file() {
    let path = write_file(
        "shear-50kPa.mcap",
        &shear_fixture(50e3, 130.0, 1.5e-3, 126, SAMPLES).0.finish(),
    );
    let opts = ReadOptions {
        cloud: CloudChoice::None,
    };
    let run = read_run(&path, &opts).unwrap();
    let r = shear(&run, &ShearOptions::default()).unwrap();
    let a = &r.analysis;
    assert!(r.source.complete);
    assert!(
        (a.peak_shear_force_n - 130.0).abs() < 1e-9,
        "{}",
        a.peak_shear_force_n
    );
    assert!((a.displacement_at_peak_m - 1.5e-3).abs() < 1e-12);
    assert!((a.peak_shear_stress_pa - 130.0 / AREA).abs() < 1e-6);
    assert_eq!(a.curve.len(), 501);
    assert!((a.mean_normal_stress_pa.unwrap() - 50e3).abs() < 1e-6);
    assert_eq!(a.max_inertial_number, Some(1e-4));
    // Readings at 0.8, 1.6, ... mm: the largest is at 1.6 mm, just past the peak.
    let read = force(1.6e-3, 130.0, 1.5e-3);
    assert!((a.peak_at_readings_n.unwrap() - read).abs() < 1e-9);

    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["peak_shear_force_n"], 130.0);
    assert_eq!(json["complete"], true);
    let svg = shear_svg(&r).unwrap();
    assert!(svg.contains("peak 130.00 N"));
    std::fs::write(path.with_extension("svg"), svg).unwrap();
}

/// Three pressures whose peaks lie exactly on tau = c + sigma tan(phi), c = 10 kPa,
/// phi = 30 deg: the fit through the three files gives c and phi back.
#[test]
fn mohr_coulomb_through_three_files() {
    let (c, phi) = (10e3, 30f64.to_radians());
    let results: Vec<ShearResult> = [50e3, 100e3, 200e3]
        .iter()
        .enumerate()
        .map(|(k, &sigma)| {
            let peak = (c + sigma * phi.tan()) * AREA;
            let at = [1.2e-3, 1.8e-3, 2.6e-3][k];
            let path = write_file(
                &format!("shear-{}kPa.mcap", sigma / 1e3),
                &shear_fixture(sigma, peak, at, 251, SAMPLES).0.finish(),
            );
            let run = read_run(
                &path,
                &ReadOptions {
                    cloud: CloudChoice::None,
                },
            )
            .unwrap();
            shear(&run, &ShearOptions::default()).unwrap()
        })
        .collect();
    let fit = mohr_coulomb(&results).unwrap();
    eprintln!(
        "Mohr-Coulomb: c = {} Pa, phi = {} deg, R^2 = {}",
        fit.cohesion_pa, fit.friction_angle_deg, fit.r_squared
    );
    assert!((fit.cohesion_pa - 10e3).abs() < 1e-6, "{}", fit.cohesion_pa);
    assert!((fit.friction_angle_deg - 30.0).abs() < 1e-9);
    assert!((fit.r_squared - 1.0).abs() < 1e-12);
    assert!(fit.complete);
    assert_eq!(fit.points.len(), 3);
    let svg = mohr_coulomb_svg(&fit).unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("reduce-tests");
    std::fs::write(dir.join("mohr-coulomb.svg"), svg).unwrap();
}

/// A ucs file is not a shear file.
#[test]
fn wrong_experiment_is_refused() {
    let f = Fixture::new(&[("run_id", "1")], &[("type", "ucs")]);
    let path = write_file("not-shear.mcap", &f.finish());
    let run = read_run(&path, &ReadOptions::default()).unwrap();
    let e = shear(&run, &ShearOptions::default()).unwrap_err();
    assert!(matches!(e, ReduceError::WrongExperiment { .. }), "{e}");
    assert!(e.to_string().contains("\"ucs\""), "{e}");
}
