//! `tilth calibrate` end to end at the coarse preset, one moisture, one seed: the runs, the
//! ridge statement, the uncertainty and a calibrated model file that the lab accepts.

use std::path::{Path, PathBuf};

use crate::tilth_in_root as tilth;

/// `tilth calibrate` of the repose angle at 6 % moisture on the coarse funnel, on both cores,
/// with `options` (parameters, seeds, checks) into `dir`; its calibration.json.
fn calibrate_repose_at_6(dir: &Path, options: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "calibrate",
        "--model",
        "models/li2022.toml",
        "--data",
        "data/li2022/measurements.csv",
        "--test",
        "repose",
    ];
    args.extend_from_slice(options);
    args.extend_from_slice(&[
        "--coarse",
        "--where",
        "moisture_pct=6",
        "--cores",
        "2",
        "--quiet",
        "--out",
    ]);
    args.push(dir.to_str().unwrap());
    let out = tilth(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("calibration.json")).unwrap()).unwrap()
}

#[test]
fn calibrate_repose_at_one_moisture() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-repose");
    let _ = std::fs::remove_dir_all(&dir);
    let v = calibrate_repose_at_6(
        &dir,
        &[
            "--param",
            "soil-soil.rolling_friction=0.05:0.45",
            "--param",
            "soil-soil.surface_energy=0.05:1.0",
            "--seeds",
            "1",
            "--check-seeds",
            "2",
            "--refine",
            "0",
        ],
    );
    let c = &v["conditions"][0];
    assert_eq!(c["measured"], 35.53);
    // 3 x 3 factorial + 2 centre points, one seed each; then two runs at the chosen setting.
    assert_eq!(c["surface_runs"], 11);
    assert_eq!(c["iterations"].as_array().unwrap().len(), 1);
    let check = &c["iterations"][0];
    let values: Vec<f64> = check["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(values.len(), 2);
    // The error's standard error is the two runs' sd / sqrt(2) over the measurement.
    let sd = (values[0] - values[1]).abs() / 2f64.sqrt();
    let se = 100.0 * sd / 2f64.sqrt() / 35.53;
    assert!((c["error_se_pct"].as_f64().unwrap() - se).abs() < 1e-9 * se.max(1.0));
    let err = c["error_pct"].as_f64().unwrap();
    assert_eq!(
        c["within_beyond_scatter"].as_bool().unwrap(),
        err.abs() + 2.0 * se <= 2.0
    );
    let setting = c["calibrated"].as_array().unwrap();
    assert!((0.05..=0.45).contains(&setting[0].as_f64().unwrap()));
    assert!((0.05..=1.0).contains(&setting[1].as_f64().unwrap()));
    // One angle, two parameters: at most one combination is fixed.
    assert!(c["linearised"]["rank"].as_u64().unwrap() <= 1);
    assert_eq!(
        c["linearised"]["null_directions"][0]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    let q = &c["posterior"];
    for k in 0..2 {
        assert!(q["q025"][k].as_f64().unwrap() <= q["q975"][k].as_f64().unwrap());
    }
    // The posterior sample and the pictures.
    let samples = std::fs::read_to_string(dir.join("posterior-moisture_pct_6.csv")).unwrap();
    assert_eq!(
        samples.lines().next(),
        Some("rolling_friction,surface_energy")
    );
    assert_eq!(samples.lines().count(), 2001);
    assert!(dir.join("contour-moisture_pct_6.svg").exists());
    // The calibrated model keeps everything else and sets the two parameters; `tilth run`
    // of an experiment with it works as far as the plan (checked by running it coarse).
    let model = std::fs::read_to_string(dir.join("model.toml")).unwrap();
    assert_eq!(model.matches("calibrated by tilth calibrate").count(), 2);
    assert!(model.contains("[bond.pairs.soil-soil]"));
    let text = format!(
        "format_version = 1\nexperiment = \"repose\"\nmodel = {:?}\ncoarse = true\n[conditions]\nmoisture_pct = 6\n",
        dir.join("model.toml").display().to_string()
    );
    let exp = dir.join("check.toml");
    std::fs::write(&exp, text).unwrap();
    let run = tilth(&[
        "run",
        exp.to_str().unwrap(),
        "--out",
        dir.join("check").to_str().unwrap(),
        "--quiet",
        "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// A bond parameter (in the model's `[bond.pairs]`) calibrated against the UCS at one
/// condition: the runs set it in the specimen's scene and the calibrated model carries it in
/// `[bond.pairs.soil-soil]`, leaving `[pairs.soil-soil]` as it was.
#[test]
fn calibrate_a_bond_stiffness_against_the_ucs() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-ucs");
    let _ = std::fs::remove_dir_all(&dir);
    let out = tilth(&[
        "calibrate",
        "--model",
        "models/li2022.toml",
        "--data",
        "data/li2022/measurements.csv",
        "--test",
        "ucs",
        "--param",
        // The top of the range sets the test's cost: the bonded step falls as 1/sqrt(S), and
        // at 1e9 Pa/m the five surface runs and the check took 11 minutes of CI on 2 cores.
        "soil-soil.normal_stiffness_per_area=5e7:2e8",
        "--seeds",
        "1",
        "--refine",
        "0",
        "--coarse",
        "--where",
        "moisture_pct=6",
        "--where",
        "firmness_mpa=1.55",
        "--cores",
        "2",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("calibration.json")).unwrap())
            .unwrap();
    let c = &v["conditions"][0];
    assert_eq!(c["measured"], 259.13);
    // Three levels plus two centre points, one seed each.
    assert_eq!(c["surface_runs"], 5);
    // One free parameter: the curve plot shows the fit's runs and every direct check, each
    // check's runs as green points and labelled with their mean.
    let curve = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("curve-")
        })
        .expect("a curve-*.svg");
    let svg = std::fs::read_to_string(&curve).unwrap();
    let checks = c["iterations"].as_array().unwrap();
    for (k, it) in checks.iter().enumerate() {
        let label = format!("check {}: {:.4}", k + 1, it["mean"].as_f64().unwrap());
        assert!(svg.contains(&label), "{label} not in {}", curve.display());
    }
    let check_runs: usize = checks
        .iter()
        .map(|it| it["values"].as_array().unwrap().len())
        .sum();
    // plus one in the legend
    assert_eq!(
        svg.matches("fill=\"#2CA02C\"").count(),
        check_runs + 1,
        "{svg}"
    );
    assert!(svg.contains("runs (5)"), "the surface runs are drawn");
    // The starting value is the model's: table 3's stiffness at 6 %, 1.55 MPa.
    assert_eq!(c["start"][0], 1.07e8);
    let model: toml::Table = std::fs::read_to_string(dir.join("model.toml"))
        .unwrap()
        .parse()
        .unwrap();
    // Calibrated at one condition, the value applies there only: a first case at 6 %,
    // 1.55 MPa, then the model's own cases, unchanged, for every other condition.
    let bond = &model["bond"]["pairs"]["soil-soil"]["normal_stiffness_per_area"]["cases"];
    let cases = bond.as_array().unwrap();
    assert_eq!(
        cases[0]["when"].as_table().unwrap().clone(),
        "firmness_mpa = 1.55\nmoisture_pct = 6.0"
            .parse::<toml::Table>()
            .unwrap()
    );
    assert_eq!(cases[0]["value"].as_float(), c["calibrated"][0].as_f64());
    let original: toml::Table = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml"),
    )
    .unwrap()
    .parse()
    .unwrap();
    let before = &original["bond"]["pairs"]["soil-soil"]["normal_stiffness_per_area"]["cases"];
    assert_eq!(&cases[1..], before.as_array().unwrap().as_slice());
    assert!(
        model["pairs"]["soil-soil"]
            .get("normal_stiffness_per_area")
            .is_none()
    );
    // A key in neither table is refused by name.
    let bad = tilth(&[
        "calibrate",
        "--model",
        "models/li2022.toml",
        "--data",
        "data/li2022/measurements.csv",
        "--test",
        "ucs",
        "--param",
        "soil-soil.bond_strength=1:2",
        "--out",
        dir.join("bad").to_str().unwrap(),
    ]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("no pairs.soil-soil.bond_strength (nor bond.pairs.soil-soil.bond_strength)"),
        "{err}"
    );
}

/// Least-squares quadratic a + b x + c x^2 through `pts`, and its residual sd.
fn quadratic(pts: &[(f64, f64)]) -> ([f64; 3], f64) {
    let mut m = [[0.0f64; 4]; 3];
    for &(x, y) in pts {
        let row = [1.0, x, x * x];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += row[i] * row[j];
            }
            m[i][3] += row[i] * y;
        }
    }
    // Gauss-Jordan on the 3 x 3 normal equations.
    for c in 0..3 {
        let p = (c..3)
            .max_by(|a, b| m[*a][c].abs().total_cmp(&m[*b][c].abs()))
            .unwrap();
        m.swap(c, p);
        for r in 0..3 {
            if r != c {
                let f = m[r][c] / m[c][c];
                let pivot = m[c];
                for (x, p) in m[r].iter_mut().zip(pivot) {
                    *x -= f * p;
                }
            }
        }
    }
    let coef = [m[0][3] / m[0][0], m[1][3] / m[1][1], m[2][3] / m[2][2]];
    let f = |x: f64| coef[0] + coef[1] * x + coef[2] * x * x;
    let sse: f64 = pts.iter().map(|&(x, y)| (y - f(x)).powi(2)).sum();
    (coef, (sse / (pts.len() as f64 - 3.0)).sqrt())
}

/// `--joint`: one rolling friction for the four moistures, fitted to all four angles at once. The
/// calibrated value is checked against an independent weighted least-squares fit of the
/// same runs (quadratics refitted here, minimised on a fine grid).
#[test]
fn joint_calibration_shares_one_value_across_conditions() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-joint");
    let _ = std::fs::remove_dir_all(&dir);
    let out = tilth(&[
        "calibrate",
        "--joint",
        "--model",
        "models/li2022.toml",
        "--data",
        "data/li2022/measurements.csv",
        "--test",
        "repose",
        "--param",
        "soil-soil.rolling_friction=0.05:0.45",
        "--seeds",
        "1",
        "--refine",
        "0",
        "--coarse",
        "--cores",
        "2",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("calibration.json")).unwrap())
            .unwrap();
    assert_eq!(v["joint"], true);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    let theta = v["calibrated"][0].as_f64().unwrap();
    assert!((0.05..=0.45).contains(&theta));
    // The surface's runs, refitted here; sigma is their residual sd (no uncertainty given).
    let mut fits = vec![];
    for r in rows {
        let pts: Vec<(f64, f64)> = r["surface_points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| (p[0][0].as_f64().unwrap(), p[1].as_f64().unwrap()))
            .collect();
        assert_eq!(pts.len(), 5);
        let (coef, sd) = quadratic(&pts);
        assert!((r["sigma"].as_f64().unwrap() - sd).abs() <= 1e-6 * sd.max(1.0));
        fits.push((coef, sd, r["measured"].as_f64().unwrap()));
    }
    let s = |x: f64| -> f64 {
        fits.iter()
            .map(|(c, sd, y)| ((c[0] + c[1] * x + c[2] * x * x - y) / sd).powi(2))
            .sum()
    };
    let best = (0..=40_000)
        .map(|i| 0.05 + 0.4 * i as f64 / 40_000.0)
        .min_by(|a, b| s(*a).total_cmp(&s(*b)))
        .unwrap();
    assert!(
        s(theta) <= s(best) + 1e-9 * s(best).max(1e-12),
        "calibrated {theta} (S = {}) vs grid {best} (S = {})",
        s(theta),
        s(best)
    );
    // The calibrated model carries the one value as a number.
    let model: toml::Table = std::fs::read_to_string(dir.join("model.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        model["pairs"]["soil-soil"]["rolling_friction"].as_float(),
        Some((theta * 1e6).round() / 1e6)
    );
}

/// `--joint` over tests of which one cannot take a free parameter (a bond strength: the
/// funnel test has no bonds) is refused before any run, whatever the order of `--test`:
/// the shear box's surface, listed first, is not run first and thrown away.
#[test]
fn a_joint_parameter_one_test_cannot_take_is_refused_before_any_run() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-joint-refused");
    let _ = std::fs::remove_dir_all(&dir);
    let out = tilth(&[
        "calibrate",
        "--joint",
        "--model",
        "models/li2022.toml",
        "--data",
        "data/li2022/measurements.csv",
        "--test",
        "direct_shear,repose",
        "--param",
        "soil-soil.critical_normal_stress=6e3:20e3",
        "--where",
        "moisture_pct=3",
        "--seeds",
        "1",
        "--coarse",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--param soil-soil.critical_normal_stress: the repose test does not take it"),
        "{err}"
    );
    assert!(!dir.join("surface-direct_shear").exists(), "{err}");
}

/// `--check-se`: a check takes batches of `--check-seeds` seeds until its mean's standard
/// error is at most the given percent of the measurement, at most `--max-check-seeds`, and
/// stops early only when it already misses by more than the tolerance plus two standard
/// errors. Asked for an unreachable precision, the check at 6 % runs all three seeds (1001,
/// 1002, 1003) in three batches, unless the rule stops it, which is then checked from the
/// values.
#[test]
fn a_check_takes_seeds_until_its_mean_is_precise() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-check-se");
    let _ = std::fs::remove_dir_all(&dir);
    let v = calibrate_repose_at_6(
        &dir,
        &[
            "--param",
            "soil-soil.rolling_friction=0.05:0.45",
            "--seeds",
            "1",
            "--check-seeds",
            "1",
            "--check-se",
            "1e-6",
            "--max-check-seeds",
            "3",
            "--refine",
            "0",
        ],
    );
    assert_eq!(v["check_se_pct"], 1e-6);
    assert_eq!(v["max_check_seeds"], 3);
    let values: Vec<f64> = v["conditions"][0]["iterations"][0]["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let n = values.len();
    assert!(n >= 2, "{values:?}");
    if n == 2 {
        // Stopped early: the two runs must miss by more than 2 % plus two standard errors.
        let mean = 0.5 * (values[0] + values[1]);
        let se = 100.0 * (values[0] - values[1]).abs() / 2f64.sqrt() / 2f64.sqrt() / 35.53;
        let err = 100.0 * (mean - 35.53) / 35.53;
        assert!(err.abs() - 2.0 * se > 2.0, "{values:?}");
    } else {
        assert_eq!(n, 3);
    }
    // One batch per directory, each its own seed.
    let seed = |d: &str| -> u64 {
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(d).join("runs/001/summary.json")).unwrap(),
        )
        .unwrap();
        s["run"]["seed"].as_u64().unwrap()
    };
    assert_eq!(seed("check-0"), 1001);
    assert_eq!(seed("check-0-1"), 1002);
    assert_eq!(dir.join("check-0-2").exists(), n == 3);
    if n == 3 {
        assert_eq!(seed("check-0-2"), 1003);
    }
    let md = std::fs::read_to_string(dir.join("calibration.md")).unwrap();
    assert!(
        md.contains("until the mean's standard error is at most 0.000001 %"),
        "{md}"
    );
}

/// The precision options are checked before any run.
#[test]
fn check_precision_options_out_of_range_are_refused() {
    for (extra, want) in [
        (
            &["--check-se", "0"][..],
            "--check-se 0 is out of range: allowed > 0",
        ),
        (
            &["--max-check-seeds", "8"][..],
            "--max-check-seeds is the cap of --check-se",
        ),
        (
            &[
                "--check-se",
                "1",
                "--check-seeds",
                "4",
                "--max-check-seeds",
                "3",
            ][..],
            "--max-check-seeds 3 is out of range: allowed at least --check-seeds (4)",
        ),
    ] {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("calibrate-check-se-bad");
        let _ = std::fs::remove_dir_all(&dir);
        let mut args = vec![
            "calibrate",
            "--model",
            "models/li2022.toml",
            "--data",
            "data/li2022/measurements.csv",
            "--test",
            "repose",
            "--param",
            "soil-soil.rolling_friction=0.05:0.45",
            "--coarse",
            "--quiet",
            "--out",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = tilth(&args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want), "{extra:?}: {err}");
        assert!(!dir.exists(), "{extra:?}: wrote {}", dir.display());
    }
}
