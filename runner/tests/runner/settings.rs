//! `--set TEST.KEY=VALUE` on the commands that run the lab tests: the key reaches every run
//! of that test (a user's own instrument or amount of soil), and a bad one is refused, with
//! the key and what is allowed, before any run.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::tilth_in_root as tilth;

const DATA: &str = "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source
repose,6,,,tray_mass_g,20.0,g,0.5,4,made up for the test
";

fn setup(name: &str) -> (PathBuf, PathBuf) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("data.csv");
    std::fs::write(&data, DATA).unwrap();
    (dir, data)
}

/// `tilth compare` of the data at the coarse preset into `out`, with `--set` for each of `sets`.
fn compare(data: &Path, out: &Path, sets: &[&str]) -> Output {
    let mut args = vec![
        "compare",
        "--model",
        "models/li2022.toml",
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--coarse",
        "--quiet",
    ];
    for s in sets {
        args.extend(["--set", s]);
    }
    tilth(&args)
}

#[test]
fn a_set_key_reaches_every_run_of_its_test() {
    let (dir, data) = setup("set-reaches-runs");
    let out = dir.join("out");
    let o = compare(&data, &out, &["repose.mass_g=20", "ucs.height=0.05"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("--set ucs.height: no ucs rows here, so it is not used"),
        "{err}"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("repose/runs/001/summary.json")).unwrap(),
    )
    .unwrap();
    // 20 g of 4 mm grains of the model's soil (1380 kg/m^3), not the coarse preset's 40 g.
    let grain = 1380.0 * std::f64::consts::PI / 6.0 * 0.004f64.powi(3);
    let expected = 0.020 / grain;
    let particles = summary["experiment"]["particles"].as_f64().unwrap();
    assert!(
        (particles - expected).abs() <= 0.5 + 1e-9,
        "{particles} particles, 20 g is {expected:.1}"
    );
    // The runs' experiment says so, and compare.json records what was set.
    let text = std::fs::read_to_string(out.join("repose/sweep.toml")).unwrap();
    assert!(text.contains("mass_g = 20"), "{text}");
    assert!(
        !text.contains("height"),
        "a ucs key in the repose runs: {text}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    assert_eq!(
        report["set"],
        serde_json::json!(["repose.mass_g=20", "ucs.height=0.05"])
    );
}

#[test]
fn a_bad_set_is_refused_before_any_run() {
    let (dir, data) = setup("set-refused");
    let cases: [(&str, &[&str]); 7] = [
        (
            "repose.tray_diamter=0.1",
            &["tray_diamter", "unknown field", "tray_diameter"],
        ),
        (
            "repose.mass_g=-5",
            &["repose.mass_g = -5", "out of range", "(0, inf) g"],
        ),
        (
            "funnel.mass_g=300",
            &["`funnel` is not a test", "repose, direct_shear, ucs"],
        ),
        ("repose.mass_g", &["--set repose.mass_g", "TEST.KEY=VALUE"]),
        ("repose.mass_g=lots", &["`lots` is not a value"]),
        // A test with no rows here: its key is still checked, not skipped unseen.
        (
            "ucs.heigth=0.05",
            &["--set ucs.heigth=0.05", "unknown field `heigth`", "height"],
        ),
        ("ucs.height=\"tall\"", &["--set ucs.height", "invalid type"]),
    ];
    for (k, (set, words)) in cases.iter().enumerate() {
        let out = dir.join(format!("out-{k}"));
        let o = compare(&data, &out, &[set]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "--set {set} was taken");
        for w in *words {
            assert!(err.contains(w), "--set {set}: `{w}` not in: {err}");
        }
        assert!(
            !out.join("repose/runs").exists()
                || std::fs::read_dir(out.join("repose/runs"))
                    .unwrap()
                    .next()
                    .is_none(),
            "--set {set}: a run started"
        );
    }
}
