//! `tilth fit`: bad parameters are refused before any run; the fitted model file is what was
//! simulated (compare of it, with the same seeds, gives the RMSE fit reported); the best
//! setting is never worse than the start; the standard errors count the Jacobian's noise.

use std::path::PathBuf;

use crate::tilth_in_root as tilth;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const DATA: &str = "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source
repose,6,,,heap_cone_angle_deg,41.0,deg,0.8,4,made up for the test
repose,6,,,funnel_flow_rate_g_s,480,g/s,15,4,made up for the test
repose,12,,,heap_cone_angle_deg,45.0,deg,0.8,4,made up for the test
repose,12,,,funnel_flow_rate_g_s,380,g/s,15,4,made up for the test
";

#[test]
fn bad_parameters_are_refused_before_any_run() {
    let dir = scratch("fit-refused");
    let data = dir.join("data.csv");
    std::fs::write(&data, DATA).unwrap();
    for (param, expect) in [
        ("soil-soil.rolling_friction=0.2:0.45", "outside [0.2, 0.45]"),
        ("candidate.clumps=0:1", "has no [candidates.clumps]"),
        ("candidate.twisting=0:1@2", "the start 2 is outside [0, 1]"),
        ("soil-soil.rolling_friction=0.4:0.1", "LOW < HIGH"),
        ("rolling_friction=0:1", "expected PAIR.KEY=LOW:HIGH"),
    ] {
        let out = dir.join("out");
        let o = tilth(&[
            "fit",
            "--model",
            "models/li2022.toml",
            "--data",
            data.to_str().unwrap(),
            "--param",
            param,
            "--out",
            out.to_str().unwrap(),
            "--coarse",
            "--quiet",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{param}: accepted");
        assert!(err.contains(expect), "{param}: `{expect}` not in {err}");
        assert!(!out.join("runs").exists(), "{param}: runs started");
    }
}

#[test]
fn the_fitted_model_is_what_was_simulated() {
    let dir = scratch("fit-consistent");
    let data = dir.join("data.csv");
    std::fs::write(&data, DATA).unwrap();
    let out = dir.join("fit");
    let o = tilth(&[
        "fit",
        "--model",
        "models/li2022.toml",
        "--data",
        data.to_str().unwrap(),
        "--param",
        "soil-soil.rolling_friction=0.05:0.45",
        "--param",
        "candidate.twisting=0:0.5@0.1",
        "--replicates",
        "2",
        "--iterations",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fit: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("fit.json")).unwrap()).unwrap();
    let history = fit["history"].as_array().unwrap();
    assert!(!history.is_empty());
    let chi2 = fit["chi2"].as_f64().unwrap();
    assert!(
        chi2 <= history[0]["chi2"].as_f64().unwrap(),
        "best worse than the start"
    );
    let model = std::fs::read_to_string(out.join("model.toml")).unwrap();
    assert!(
        model.contains("extra = [\"twisting\"]"),
        "the candidate is on: {model}"
    );
    assert!(model.contains("# Fitted by `tilth fit`"));
    // compare of the fitted model with the same seeds (1..2) reproduces the fit's RMSE.
    let cmp = dir.join("compare");
    let o = tilth(&[
        "compare",
        "--model",
        out.join("model.toml").to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        cmp.to_str().unwrap(),
        "--replicates",
        "2",
        "--coarse",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cmp.join("compare.json")).unwrap()).unwrap();
    for (k, v) in fit["rmse"].as_object().unwrap() {
        let again = c["observables"][k]["rmse"].as_f64().unwrap();
        let v = v.as_f64().unwrap();
        assert!(
            (again - v).abs() <= 1e-9 * v.abs().max(1.0),
            "{k}: fit {v}, compare {again}"
        );
    }
}

/// Readings whose uncertainty dwarfs any model's miss: the start is at the noise (the step
/// from it is predicted to gain less chi^2 than chi^2_1's 95 % quantile, 3.84), so the fit
/// runs the start and its Jacobian and stops there.
#[test]
fn a_fit_stops_where_the_residuals_reach_the_noise() {
    let dir = scratch("fit-at-noise");
    let data = dir.join("data.csv");
    std::fs::write(
        &data,
        DATA.replace(",0.8,4,", ",30,4,")
            .replace(",15,4,", ",600,4,"),
    )
    .unwrap();
    let out = dir.join("fit");
    let o = tilth(&[
        "fit",
        "--model",
        "models/li2022.toml",
        "--data",
        data.to_str().unwrap(),
        "--param",
        "soil-soil.rolling_friction=0.05:0.45",
        "--replicates",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fit: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("fit.json")).unwrap()).unwrap();
    let chi2 = fit["chi2"].as_f64().unwrap();
    let dof = fit["dof"].as_f64().unwrap();
    assert!(
        chi2 <= dof,
        "the data were meant to be at the noise: chi^2 {chi2}, dof {dof}"
    );
    assert_eq!(fit["stopped"], "at_noise");
    assert_eq!(fit["history"].as_array().unwrap().len(), 1);
    let gain = fit["history"][0]["predicted_gain"].as_f64().unwrap();
    assert!((0.0..3.841).contains(&gain), "predicted gain {gain}");
    assert!(out.join("runs/iter-0/param-0").exists(), "no Jacobian");
    assert!(
        !out.join("runs/iter-1").exists(),
        "stepped on from the noise"
    );
    // The Jacobian's noise only adds uncertainty: the corrected standard error is at least
    // the uncorrected one, or not determined at all (noise as large as the signal).
    let naive = fit["standard_error_uncorrected"][0].as_f64().unwrap();
    match fit["standard_error"][0].as_f64() {
        Some(se) => assert!(se >= naive, "corrected {se} under the uncorrected {naive}"),
        None => assert!(fit["standard_error"][0].is_null()),
    }
    let noise = fit["jacobian_noise"][0][0].as_f64().unwrap();
    assert!(noise >= 0.0, "the Jacobian's noise variance {noise}");
    let md = std::fs::read_to_string(out.join("fit.md")).unwrap();
    assert!(md.contains("Stopped at the noise"), "{md}");
}
