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
            &["`funnel` is not a test", "repose, direct_shear, ucs, tilt"],
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

/// The number of grains in `grams` of 4 mm grains of the model's soil (1380 kg/m^3).
fn grains_in(grams: f64) -> f64 {
    grams * 1e-3 / (1380.0 * std::f64::consts::PI / 6.0 * 0.004f64.powi(3))
}

/// A setting column (`repose.mass_g`) sets its own row's runs over `--set`, and a row that
/// leaves it empty keeps `--set`'s value: two plans, each run with its own amount of soil.
#[test]
fn a_setting_column_sets_its_rows_runs_over_set() {
    let (dir, data) = setup("setting-column");
    std::fs::write(
        &data,
        "test,moisture_pct,repose.mass_g,observable,value,unit,uncertainty\n\
         repose,6,10,tray_mass_g,9.0,g,0.5\n\
         repose,6,,tray_mass_g,14.0,g,0.5\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = compare(&data, &out, &["repose.mass_g=15"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let particles = |sub: &str| {
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(sub).join("runs/001/summary.json")).unwrap(),
        )
        .unwrap();
        s["experiment"]["particles"].as_f64().unwrap()
    };
    for (sub, grams) in [("repose+repose_mass_g", 10.0), ("repose", 15.0)] {
        let (n, expected) = (particles(sub), grains_in(grams));
        assert!(
            (n - expected).abs() <= 0.5 + 1e-9,
            "{sub}: {n} particles, {grams} g is {expected:.1}"
        );
    }
    let csv = std::fs::read_to_string(out.join("compare.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = head
        .iter()
        .position(|h| *h == "repose.mass_g")
        .expect("column");
    let cells: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    assert_eq!(cells, ["10", ""], "{csv}");
}

/// Bad setting columns are refused before any run, naming the file, the row or column and
/// what is allowed; a conditions file for `synth` is held to the same columns.
#[test]
fn a_bad_setting_column_is_refused_before_any_run() {
    let (dir, data) = setup("setting-refused");
    let tail = "observable,value,unit\n";
    let cases: [(&str, &str, &[&str]); 6] = [
        (
            "test,moisture_pct,firmness_mpa,normal_pressure_pa,direct_shear.normal_pressure,",
            "direct_shear,6,1.55,100000,50000,peak_shear_force_n,200,N",
            &[
                "column `direct_shear.normal_pressure`",
                "`normal_pressure_pa`",
            ],
        ),
        (
            "test,moisture_pct,repose.tray_diamter,",
            "repose,6,0.1,tray_mass_g,9,g",
            &[
                "column `repose.tray_diamter`",
                "unknown field",
                "tray_diameter",
            ],
        ),
        (
            "test,moisture_pct,funnel.mass_g,",
            "repose,6,10,tray_mass_g,9,g",
            &["unknown column `funnel.mass_g`", "settings TEST.KEY"],
        ),
        (
            "test,moisture_pct,firmness_mpa,repose.mass_g,",
            "ucs,6,1.55,10,ucs_kpa,200,kPa",
            &[
                "row 2, column repose.mass_g",
                "a ucs row cannot set a repose test's key",
            ],
        ),
        (
            "test,moisture_pct,repose.mass_g,",
            "repose,6,lots,tray_mass_g,9,g",
            &[
                "row 2, column repose.mass_g",
                "`lots` is not a finite number",
            ],
        ),
        (
            "test,moisture_pct,repose.mass_g,",
            "repose,6,-5,tray_mass_g,9,g",
            &["repose.mass_g = -5", "out of range", "(0, inf) g"],
        ),
    ];
    for (k, (head, row, words)) in cases.iter().enumerate() {
        std::fs::write(&data, format!("{head}{tail}{row}\n")).unwrap();
        let out = dir.join(format!("out-{k}"));
        let o = compare(&data, &out, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "case {k} was taken");
        for w in *words {
            assert!(err.contains(w), "case {k}: `{w}` not in: {err}");
        }
        assert!(err.contains("data.csv"), "case {k}: file not named: {err}");
        let runs = std::fs::read_dir(&out).into_iter().flatten().count();
        assert_eq!(
            runs,
            0,
            "case {k}: something was written to {}",
            out.display()
        );
    }
    let conditions = dir.join("conditions.csv");
    std::fs::write(
        &conditions,
        "test,moisture_pct,repose.drop_heigth\nrepose,6,0.1\n",
    )
    .unwrap();
    let o = tilth(&[
        "synth",
        "--truth",
        "models/li2022.toml",
        "--conditions",
        conditions.to_str().unwrap(),
        "--noise",
        "tray_mass_g=0.5",
        "--out",
        dir.join("synth.csv").to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "synth took a misspelt setting");
    for w in [
        "conditions.csv",
        "repose.drop_heigth",
        "unknown field",
        "drop_height",
    ] {
        assert!(err.contains(w), "synth: `{w}` not in: {err}");
    }
}
