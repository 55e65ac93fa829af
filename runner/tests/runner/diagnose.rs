//! `tilth diagnose` end to end at the coarse preset: a candidate that is the free parameter
//! itself is reported as absorbed (not identifiable, never significant), the report has the
//! fields the issue names, the free parameters are fitted first with `--fit-first`, the verdict
//! is written and acted on by `tilth fit --from-diagnosis`, and `tilth next` ranks a menu.

use std::path::{Path, PathBuf};

use crate::tilth_in_root as tilth;

/// A fresh directory `name` with the study's model plus a candidate `more_rolling` that
/// raises the free parameter (soil-soil rolling friction) by `step`, and two repose rows:
/// (directory, model file, data file).
fn absorbed_case(name: &str, step: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut model = std::fs::read_to_string(root.join("models/li2022.toml")).unwrap();
    model += &format!(
        "\n[candidates.more_rolling]\nstrength = [\"soil-soil.rolling_friction\"]\nstep = {step}\n"
    );
    let model_path = dir.join("model.toml");
    std::fs::write(&model_path, model).unwrap();
    let data = dir.join("data.csv");
    std::fs::write(
        &data,
        "test,moisture_pct,observable,value,unit,uncertainty\nrepose,6,repose_angle_deg,35.53,deg,1.0\nrepose,12,repose_angle_deg,43.87,deg,1.0\n",
    )
    .unwrap();
    (dir, model_path, data)
}

/// `tilth diagnose` of `model` against `data` into `out` at the coarse preset, free: the
/// soil-soil rolling friction in 0..0.5, 2 replicates, with `extra` options.
fn run_diagnose(
    (model, data, out): (&Path, &Path, &Path),
    candidates: &str,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "diagnose",
        "--model",
        model.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--param",
        "soil-soil.rolling_friction=0:0.5",
        "--candidates",
        candidates,
        "--replicates",
        "2",
        "--coarse",
        "--cores",
        "2",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    // The model file's probes have their own test: the others weigh only what they name.
    if !extra.contains(&"PROBES") {
        args.push("--no-model-probes");
    }
    // The refit has its own test: the others check the linear diagnosis.
    if !extra.contains(&"REFIT") {
        args.push("--no-refit");
    }
    args.retain(|a| *a != "REFIT" && *a != "PROBES");
    tilth(&args)
}

/// The `diagnosis.json` in `out_dir` of a `diagnose` that must have succeeded.
fn diagnosis(out: &std::process::Output, out_dir: &Path) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(out_dir.join("diagnosis.json")).unwrap()).unwrap()
}

#[test]
fn a_candidate_the_free_parameters_reproduce_is_absorbed_not_discovered() {
    // A candidate that raises the free parameter by the same step as its finite difference
    // (5 % of the range 0..0.5 = 0.025, exact in binary).
    // The step kept at 5 % (--longest-param-step): lengthened, it would no longer be the
    // candidate's.
    let (dir, model_path, data) = absorbed_case("diagnose-absorbed", "0.025");
    let out = run_diagnose(
        (&model_path, &data, &dir.join("out")),
        "more_rolling,capillary",
        &["--longest-param-step", "0.05"],
    );
    let json = diagnosis(&out, &dir.join("out"));
    let cands = json["candidates"].as_array().unwrap();
    assert_eq!(cands.len(), 2);
    for c in cands {
        for field in [
            "name",
            "statistic",
            "p_value",
            "strength",
            "predicted_rmse_drop",
            "identifiable",
        ] {
            assert!(c.get(field).is_some(), "{field} missing in {c}");
        }
    }
    let more = cands.iter().find(|c| c["name"] == "more_rolling").unwrap();
    assert_eq!(more["identifiable"], false, "{more}");
    assert_eq!(more["unidentified"], "absorbed", "{more}");
    assert_eq!(more["significant"], false, "{more}");
    assert_eq!(more["p_value"].as_f64(), Some(1.0), "{more}");
    // Identical runs: nothing of its signature is left but rounding.
    assert!(more["distinct_fraction"].as_f64().unwrap() < 1e-9, "{more}");
    // Identifiable candidates rank before the others.
    let identifiable: Vec<bool> = cands.iter().map(|c| c["identifiable"] == true).collect();
    assert!(identifiable.windows(2).all(|w| w[0] || !w[1]), "{cands:?}");
    // The recalibration behind "would leave": the model's numbers, each shifted by the one
    // least-squares shift, checked against the range given.
    let recal = json["recalibration"].as_array().unwrap();
    assert_eq!(recal.len(), 1, "{recal:?}");
    let r = &recal[0];
    assert_eq!(r["parameter"], "soil-soil.rolling_friction");
    let nums = |k: &str| -> Vec<f64> {
        r[k].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    assert_eq!(nums("now"), vec![0.188, 0.15, 0.193, 0.338], "{r}");
    let shift = r["shift"].as_f64().unwrap();
    let after = nums("after");
    for (a, n) in after.iter().zip(nums("now")) {
        assert_eq!(*a, n + shift, "{r}");
    }
    assert_eq!(
        r["within_range"].as_bool().unwrap(),
        after.iter().all(|v| (0.0..=0.5).contains(v)),
        "{r}"
    );
    let md = std::fs::read_to_string(dir.join("out/diagnosis.md")).unwrap();
    assert!(
        md.contains("| soil-soil.rolling_friction | 0.1880, 0.1500, 0.1930, 0.3380 |"),
        "{md}"
    );
    assert!(md.contains("more_rolling is not identifiable"), "{md}");
    assert!(md.contains("It is not a discovery"), "{md}");
}

/// `--param-step` sets the free parameter's finite difference: with a step of 20 % of the
/// range 0..0.5 (0.1, exact in binary), a candidate that raises the parameter by 0.1 runs the
/// very models of that difference and is absorbed, as at the default step above.
#[test]
fn param_step_sets_the_free_parameters_finite_difference() {
    let (dir, model_path, data) = absorbed_case("diagnose-param-step", "0.1");
    let out_dir = dir.join("out");
    let run = |step: &str| {
        run_diagnose(
            (&model_path, &data, &out_dir),
            "more_rolling",
            &["--param-step", step],
        )
    };
    // Refused before anything is written.
    for bad in ["0", "0.6", "NaN"] {
        let out = run(bad);
        assert!(!out.status.success(), "--param-step {bad} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!(
                "--param-step {bad} is out of range: allowed (0, 0.5]"
            )),
            "{err}"
        );
        assert!(
            !out_dir.exists(),
            "--param-step {bad} wrote {}",
            out_dir.display()
        );
    }
    let out = run("0.2");
    let json = diagnosis(&out, &out_dir);
    let more = &json["candidates"][0];
    assert_eq!(more["name"], "more_rolling", "{json}");
    assert_eq!(more["unidentified"], "absorbed", "{more}");
    assert_eq!(more["significant"], false, "{more}");
    assert!(more["distinct_fraction"].as_f64().unwrap() < 1e-9, "{more}");
    assert_eq!(json["param_step"].as_f64(), Some(0.2), "{json}");
    // Twice 20 % is beyond the longest step (20 %): kept.
    assert_eq!(
        json["recalibration"][0]["step"].as_f64(),
        Some(0.2),
        "{json}"
    );
    let md = std::fs::read_to_string(out_dir.join("diagnosis.md")).unwrap();
    assert!(
        md.contains("soil-soil.rolling_friction (slopes from finite differences of 20 % of each range, lengthened up to 20 %"),
        "{md}"
    );
}

/// The model file's `[probes]` are weighed beside the candidates as held parameters: a
/// `--probe` of the same key replaces its step, a free parameter is not probed, and a probe
/// of a pair the model lacks, or with a zero step, is refused before anything is written.
#[test]
fn the_model_files_probes_are_weighed_unless_freed_or_replaced() {
    let (dir, model_path, data) = absorbed_case("diagnose-model-probes", "0.1");
    let out_dir = dir.join("out");
    let text = std::fs::read_to_string(&model_path).unwrap();
    let with_probe = |line: &str| text.replace("[probes]\n", &format!("[probes]\n{line}\n"));
    for (line, expected) in [
        (
            "\"soil-rock.friction\" = 0.1",
            "probes.\"soil-rock.friction\": `soil-rock` is not a pair of the model; its pairs are soil-soil, soil-steel",
        ),
        (
            "\"soil-steel.friction\" = 0.0",
            "probes.\"soil-steel.friction\" = 0 is out of range: allowed a non-zero number",
        ),
    ] {
        std::fs::write(&model_path, with_probe(line)).unwrap();
        let out = run_diagnose((&model_path, &data, &out_dir), "more_rolling", &["PROBES"]);
        assert!(!out.status.success(), "{line} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(&format!("{}: {expected}", model_path.display())),
            "{err}"
        );
        assert!(!out_dir.exists(), "{line}: wrote {}", out_dir.display());
    }
    std::fs::write(
        &model_path,
        with_probe("\"soil-soil.rolling_friction\" = 0.05"),
    )
    .unwrap();
    // Every step kept as given (--longest-param-step = --param-step), then lengthened.
    let out = run_diagnose(
        (&model_path, &data, &out_dir),
        "more_rolling",
        &[
            "PROBES",
            "--probe",
            "soil-soil.friction=0.2",
            "--longest-param-step",
            "0.05",
        ],
    );
    let json = diagnosis(&out, &out_dir);
    let probes = |json: &serde_json::Value| -> Vec<(String, f64, String)> {
        let all = json["probes"].as_array().unwrap().iter();
        all.map(|p| {
            (
                p["parameter"].as_str().unwrap().to_string(),
                p["step"].as_f64().unwrap(),
                p["variant"].as_str().unwrap().to_string(),
            )
        })
        .collect()
    };
    let expected = [
        ("soil-soil.friction", 0.2),
        ("soil-soil.restitution", 0.08),
        ("soil-soil.surface_energy", 0.1),
    ];
    let kept = probes(&json);
    assert_eq!(kept.len(), expected.len(), "{kept:?}");
    for ((key, step, variant), (want_key, want_step)) in kept.iter().zip(expected) {
        assert_eq!((key.as_str(), *step), (want_key, want_step), "{kept:?}");
        assert_eq!(*variant, format!("probe-{key}"));
        assert!(
            out_dir
                .join("models")
                .join(format!("{variant}.toml"))
                .is_file()
        );
    }
    let held: Vec<&str> = json["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["held_parameter"] == true)
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(held.len(), 3, "{json}");
    assert!(
        held.iter().all(|n| n.starts_with("held:soil-soil.")),
        "{held:?}"
    );
    // Lengthened as a free parameter's step is (by at most --longest-param-step over
    // --param-step, 4x): each probe's variant raises it by the step it reports. The
    // restitution is a plain number in the model (0.45), so its variant's value says so.
    let long_dir = dir.join("lengthened");
    let out = run_diagnose((&model_path, &data, &long_dir), "more_rolling", &["PROBES"]);
    let long = probes(&diagnosis(&out, &long_dir));
    // Without --probe, friction's step is the file's.
    for ((key, step, variant), given) in long.iter().zip([0.08, 0.08, 0.1]) {
        let factor = step / given;
        assert!(
            [1.0, 2.0, 4.0].iter().any(|f| (factor - f).abs() < 1e-9),
            "{key}: step {step} from {given}"
        );
        let model: toml::Table = toml::from_str(
            &std::fs::read_to_string(long_dir.join("models").join(format!("{variant}.toml")))
                .unwrap(),
        )
        .unwrap();
        if key == "soil-soil.restitution" {
            let raised = model["pairs"]["soil-soil"]["restitution"]
                .as_float()
                .unwrap();
            assert!(
                (raised - (0.45 + step)).abs() < 1e-12,
                "{variant}: {raised}"
            );
        }
    }
}

/// A free parameter whose slope over its first step is mostly the runs' noise is measured
/// again over twice the step, up to --longest-param-step: at the end each parameter's
/// noise share is at most a tenth, or its step could not double again; a lengthened step
/// has its own model file and runs, and `next` reads the diagnosis back.
#[test]
fn a_free_parameters_step_is_lengthened_while_noise_hides_its_effect() {
    let (dir, model_path, data) = absorbed_case("diagnose-lengthened", "0.1");
    let out_dir = dir.join("out");
    let out = run_diagnose(
        (&model_path, &data, &out_dir),
        "capillary,twisting",
        &["--param-step", "0.0125", "--longest-param-step", "0.4"],
    );
    let json = diagnosis(&out, &out_dir);
    let r = &json["recalibration"][0];
    let step = r["step"].as_f64().unwrap();
    let doublings = (step / 0.0125).log2();
    assert!(
        (doublings - doublings.round()).abs() < 1e-9 && (0.0..=5.0).contains(&doublings),
        "{r}"
    );
    let share = r["noise_share"].as_f64().unwrap();
    assert!(share <= 0.1 || 2.0 * step > 0.4, "{r}");
    let variant = r["variant"].as_str().unwrap();
    if step > 0.0125 {
        assert!(variant.ends_with(&format!("-step-{step}")), "{r}");
        // Its model raises the parameter by step x range (0.5) from the base's values.
        let base = std::fs::read_to_string(out_dir.join("models").join("base.toml")).unwrap();
        let raised =
            std::fs::read_to_string(out_dir.join(format!("models/{variant}.toml"))).unwrap();
        assert_ne!(base, raised);
        assert!(
            out_dir.join("runs").join(variant).is_dir(),
            "{variant}: no runs"
        );
    } else {
        assert_eq!(variant, "param-soil-soil.rolling_friction", "{r}");
    }
    // The column diagnosis.json holds is the one measured over that step: `next` (which
    // rebuilds the variants from the file) accepts it.
    let menu = dir.join("menu.csv");
    std::fs::write(&menu, "test,moisture_pct\nrepose,9\n").unwrap();
    let next = tilth(&[
        "next",
        "--diagnosis",
        out_dir.to_str().unwrap(),
        "--menu",
        menu.to_str().unwrap(),
        "--rivals",
        "capillary,twisting",
        "--out",
        dir.join("next").to_str().unwrap(),
        "--coarse",
        "--cores",
        "2",
        "--quiet",
    ]);
    assert!(
        next.status.success(),
        "{}",
        String::from_utf8_lossy(&next.stderr)
    );
}

/// With --fit-first the free parameters are fitted to the data first, and the candidates scored at
/// the fitted model; the verdict is written with the fields `fit` and `next` read, and
/// `fit --from-diagnosis` refuses any verdict but `effect`.
#[test]
fn the_free_parameters_are_fitted_first_and_the_verdict_is_written() {
    let (dir, model_path, data) = absorbed_case("diagnose-fit-first", "0.025");
    let out_dir = dir.join("out");
    let out = run_diagnose(
        (&model_path, &data, &out_dir),
        "capillary,twisting",
        &["--fit-first", "--fit-iterations", "1"],
    );
    let json = diagnosis(&out, &out_dir);
    let fit: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("fit/fit.json")).unwrap()).unwrap();
    let fitted = json["fitted_model"].as_str().expect("fitted_model");
    assert!(fitted.ends_with("fit/model.toml"), "{fitted}");
    // "now" is the fitted model: the start's numbers moved by the fit's offset.
    let offset = fit["estimate"][0].as_f64().unwrap();
    let now: Vec<f64> = json["recalibration"][0]["now"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (n, start) in now.iter().zip([0.188, 0.15, 0.193, 0.338]) {
        assert!(
            (n - (start + offset)).abs() < 1e-12,
            "{now:?} against offset {offset}"
        );
    }
    let v = &json["verdict"];
    let kind = v["verdict"].as_str().unwrap();
    assert!(
        ["effect", "ambiguous", "none_of_the_candidates", "no_effect"].contains(&kind),
        "{v}"
    );
    for field in ["effects", "ambiguous", "encompassing", "misfit"] {
        assert!(v.get(field).is_some(), "{field} missing in {v}");
    }
    assert_eq!(json["rows"].as_array().unwrap().len(), 2, "{json}");
    assert_eq!(
        json["columns"]["candidates"]["twisting"]["sensitivity"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    let md = std::fs::read_to_string(out_dir.join("diagnosis.md")).unwrap();
    assert!(md.contains("**Verdict: "), "{md}");
    assert!(md.contains("fitted to these data first"), "{md}");
    if kind != "effect" {
        let fit_out = tilth(&[
            "fit",
            "--model",
            model_path.to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
            "--from-diagnosis",
            out_dir.to_str().unwrap(),
            "--out",
            dir.join("fit").to_str().unwrap(),
            "--coarse",
            "--quiet",
        ]);
        assert!(!fit_out.status.success());
        let err = String::from_utf8_lossy(&fit_out.stderr);
        assert!(err.contains(&format!("the verdict is {kind}")), "{err}");
        assert!(!dir.join("fit/fit.json").exists());
    }
}

/// `tilth next` simulates a menu with the diagnosis's variants and ranks it: every option
/// has a separation per ordered pair of the rivals, best first, and the best is written as
/// a conditions file that `tilth synth` reads.
#[test]
fn next_ranks_a_menu_and_writes_the_best_as_conditions() {
    let (dir, model_path, data) = absorbed_case("diagnose-next", "0.025");
    let out_dir = dir.join("out");
    let out = run_diagnose((&model_path, &data, &out_dir), "capillary,twisting", &[]);
    let d = diagnosis(&out, &out_dir);
    let menu = dir.join("menu.csv");
    std::fs::write(&menu, "test,moisture_pct\nrepose,3\nrepose,9\n").unwrap();
    let next_dir = dir.join("next");
    let run = |rivals: &str| {
        tilth(&[
            "next",
            "--diagnosis",
            out_dir.to_str().unwrap(),
            "--menu",
            menu.to_str().unwrap(),
            "--rivals",
            rivals,
            "--out",
            next_dir.to_str().unwrap(),
            "--coarse",
            "--cores",
            "2",
            "--quiet",
        ])
    };
    let bad = run("capillary,nothing");
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("nothing is not a candidate"), "{err}");
    let ok = run("capillary,twisting");
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(next_dir.join("next.json")).unwrap()).unwrap();
    let options = json["options"].as_array().unwrap();
    assert_eq!(options.len(), 2, "{json}");
    // Ranked by the expected power, a probability itself. Box and Hill's weights without a
    // refit: P_k proportional to exp(T_k / 2), T_k the rival's score statistic (the linear
    // drop in chi^2 its fit would bring).
    let weights: Vec<f64> = (json["weights"].as_array().unwrap().iter())
        .map(|w| w.as_f64().unwrap())
        .collect();
    let statistic = |name: &str| {
        (d["candidates"].as_array().unwrap().iter())
            .find(|c| c["name"] == name)
            .unwrap()["statistic"]
            .as_f64()
            .unwrap()
    };
    let odds = ((statistic("capillary") - statistic("twisting")) / 2.0).exp();
    assert!(
        (weights[0] / weights[1] - odds).abs() < 1e-9 * odds.max(1.0),
        "{weights:?} against odds {odds}"
    );
    assert!(
        (weights.iter().sum::<f64>() - 1.0).abs() < 1e-9,
        "{weights:?}"
    );
    let expected: Vec<f64> = options
        .iter()
        .map(|o| o["expected_power"].as_f64().unwrap())
        .collect();
    assert!(expected[0] >= expected[1], "{expected:?}");
    assert!(
        expected.iter().all(|e| (0.0..=1.0).contains(e)),
        "{expected:?}"
    );
    let funnel = [
        "repose_angle_deg",
        "heap_cone_angle_deg",
        "tray_mass_g",
        "funnel_flow_rate_g_s",
        "funnel_residue_g",
    ];
    for o in options {
        // Both ways between the two rivals; the funnel test's readings, each once (a
        // reading that does not scatter, as the residue of a funnel that empties, has no
        // standard error without --noise and is left out).
        assert_eq!(o["pairs"].as_array().unwrap().len(), 2, "{o}");
        let obs: Vec<&str> = (o["observables"].as_array().unwrap().iter())
            .map(|v| v.as_str().unwrap())
            .collect();
        assert!(
            !obs.is_empty() && obs.iter().all(|x| funnel.contains(x)),
            "{o}"
        );
        let mut unique = obs.clone();
        unique.dedup();
        assert_eq!(unique.len(), obs.len(), "{o}");
    }
    let conditions = std::fs::read_to_string(next_dir.join("conditions.csv")).unwrap();
    let best = options[0]["conditions"]["moisture_pct"].as_f64().unwrap();
    assert!(
        conditions.starts_with("test,moisture_pct,observable\n"),
        "{conditions}"
    );
    let readings = options[0]["observables"].as_array().unwrap().len();
    assert_eq!(conditions.lines().count(), 1 + readings, "{conditions}");
    assert!(
        conditions.contains(&format!("repose,{best},heap_cone_angle_deg")),
        "{conditions}"
    );
}

/// The sum of the normal scores squared of a fit's rows, from its `z` and `z_dof` (null:
/// exact).
fn normal_scores_chi2(fit: &serde_json::Value) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
    let z = fit["z"].as_array().unwrap();
    let dof = fit["z_dof"].as_array().unwrap();
    assert_eq!(z.len(), dof.len(), "{fit}");
    z.iter()
        .zip(dof)
        .map(|(z, d)| {
            let z = z.as_f64().unwrap();
            let q = match d.as_f64() {
                None => z,
                Some(nu) => {
                    let tail = StudentsT::new(0.0, 1.0, nu).unwrap().sf(z.abs());
                    -Normal::standard().inverse_cdf(tail) * z.signum()
                }
            };
            q * q
        })
        .sum()
}

/// By default, the free parameter alone and every contender of the linear verdict with it
/// are fitted on simulations into DIR/refit/; each contender is judged needed (its chi^2 drop
/// from the free parameter's fit, Holm-corrected) and within the noise (P(chi^2_dof > sum of
/// the rows' normal scores squared), checked here in closed form for the even dof), and the
/// verdict follows the fits:
/// one both needed and within the noise is named with its fitted strength, several are
/// ambiguous, none is none_of_the_candidates or no_effect; the linear verdict is kept beside
/// it. The data: the study's model with its soil-soil surface energy 0.2 J/m^2 higher, and
/// a candidate that raises exactly that.
#[test]
fn refit_fits_each_contender_and_the_verdict_follows_the_fits() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("diagnose-refit");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut model = std::fs::read_to_string(root.join("models/li2022.toml")).unwrap();
    model +=
        "\n[candidates.more_cohesion]\nstrength = [\"soil-soil.surface_energy\"]\nstep = 0.15\n";
    let model_path = dir.join("model.toml");
    std::fs::write(&model_path, model).unwrap();
    let conditions = dir.join("conditions.csv");
    let mut rows = String::from("test,moisture_pct,observable\n");
    for m in [3, 6, 9, 12] {
        rows += &format!("repose,{m},heap_cone_angle_deg\nrepose,{m},tray_mass_g\n");
    }
    std::fs::write(&conditions, rows).unwrap();
    let data = dir.join("data.csv");
    let synth = tilth(&[
        "synth",
        "--truth",
        model_path.to_str().unwrap(),
        "--shift",
        "soil-soil.surface_energy=0.2",
        "--conditions",
        conditions.to_str().unwrap(),
        "--noise",
        "heap_cone_angle_deg=0.5,tray_mass_g=0.5",
        "--replicates",
        "2",
        "--seed",
        "1",
        "--out",
        data.to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    assert!(
        synth.status.success(),
        "{}",
        String::from_utf8_lossy(&synth.stderr)
    );
    let out_dir = dir.join("out");
    // The free parameter's step kept at 5 %: lengthened to 20 %, rolling friction takes out
    // the cohesion's misfit on these 8 rows (linearly, beyond its range), the linear verdict
    // is no_effect and nothing is refitted.
    let out = run_diagnose(
        (&model_path, &data, &out_dir),
        "more_cohesion,twisting",
        &[
            "REFIT",
            "--fit-iterations",
            "1",
            "--longest-param-step",
            "0.05",
        ],
    );
    let json = diagnosis(&out, &out_dir);
    assert!(json["linear_verdict"]["verdict"].is_string(), "{json}");
    let read = |dir: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(Path::new(dir).join("fit.json")).unwrap()).unwrap()
    };
    let free = &json["refit"]["free"];
    let free_chi2 = read(free["dir"].as_str().unwrap())["chi2"]
        .as_f64()
        .unwrap();
    assert_eq!(free["chi2"].as_f64(), Some(free_chi2));
    let fits = json["refit"]["contenders"]
        .as_array()
        .expect("refit: the linear verdict has contenders");
    assert!(!fits.is_empty());
    let (mut chosen, mut kept, mut gaps) = (vec![], vec![], vec![]);
    for f in fits {
        let name = f["name"].as_str().unwrap();
        let fit = read(f["dir"].as_str().unwrap());
        let (chi2, dof) = (fit["chi2"].as_f64().unwrap(), fit["dof"].as_f64().unwrap());
        assert_eq!(f["chi2"].as_f64(), Some(chi2), "{name}");
        assert_eq!(f["chi2_drop"].as_f64(), Some(free_chi2 - chi2), "{name}");
        // 8 rows, the free parameter and the contender: 6 degrees of freedom, and
        // P(chi^2_6 > x) = e^{-x/2} (1 + x/2 + (x/2)^2 / 2), x the sum of the rows' normal
        // scores squared: each z taken to the normal quantile of its tail under Student's t
        // with the row's degrees of freedom (the runs' and the data's scatter from 2 runs).
        assert_eq!(dof, 6.0, "{name}");
        let scores = normal_scores_chi2(&fit);
        assert!(
            (fit["chi2_scores"].as_f64().unwrap() - scores).abs() < 1e-9 * scores.max(1.0),
            "{name}: {fit}"
        );
        // Student's t has the heavier tails: no score beyond its z.
        assert!(scores <= chi2 * (1.0 + 1e-12), "{name}: {scores} > {chi2}");
        let h = scores / 2.0;
        let p = (-h).exp() * (1.0 + h + h * h / 2.0);
        assert!(
            (f["p_value"].as_f64().unwrap() - p).abs() < 1e-9,
            "{name}: {f}"
        );
        assert_eq!(f["within_noise"].as_bool(), Some(p >= 0.01), "{name}");
        // The rows' standardised residuals: chi^2 is their sum of squares.
        let z: Vec<f64> = f["z"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(z.len(), 8, "{name}");
        assert!((z.iter().map(|v| v * v).sum::<f64>() - chi2).abs() < 1e-9 * chi2.max(1.0));
        let needed = chi2 < free_chi2 && f["p_needed"].as_f64().unwrap() < 0.01;
        assert_eq!(f["needed"].as_bool(), Some(needed), "{name}");
        let excluded = f["p_worse"].as_f64().is_some_and(|p| p < 0.01);
        assert_eq!(f["excluded"].as_bool(), Some(excluded), "{name}");
        // What the fit could still gain, from its history: the last accepted step's
        // predicted gain, or, out of iterations on that step, the chi^2 it removed if more.
        let accepted: Vec<&serde_json::Value> = fit["history"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["accepted"] == true)
            .collect();
        let last = accepted.last().unwrap();
        let mut gain = last["predicted_gain"].as_f64().unwrap_or(0.0);
        let history = fit["history"].as_array().unwrap();
        let moving = history.last().unwrap()["accepted"] == true;
        if fit["stopped"] == "iterations" && moving && accepted.len() > 1 {
            let before = accepted[accepted.len() - 2]["chi2"].as_f64().unwrap();
            gain = gain.max(before - last["chi2"].as_f64().unwrap());
        }
        assert_eq!(f["unfinished_gain"].as_f64(), Some(gain.max(0.0)), "{name}");
        let moving = moving && fit["stopped"] == "iterations" && accepted.len() > 1;
        assert_eq!(f["still_moving"].as_bool(), Some(moving), "{name}");
        if needed {
            gaps.push((fit["chi2_scores"].as_f64().unwrap(), gain.max(0.0), f));
            chosen.push((chi2, name.to_string(), fit["estimate"][1].as_f64().unwrap()));
            kept.push(!excluded);
        }
    }
    // Each needed rival against the best needed one: P(gap) <= exp(-gap/2) if it were the
    // truth, the gap in normal scores less what its fit could still gain; Holm over them.
    if let Some(best) = (0..chosen.len()).min_by(|&a, &b| chosen[a].0.total_cmp(&chosen[b].0)) {
        let others: Vec<usize> = (0..gaps.len()).filter(|&k| k != best).collect();
        let raw: Vec<f64> = (others.iter())
            .map(|&k| {
                let g = gaps[k].0 - gaps[best].0 - gaps[k].1;
                if g > 0.0 { (-g / 2.0).exp() } else { 1.0 }
            })
            .collect();
        let mut order: Vec<usize> = (0..raw.len()).collect();
        order.sort_by(|&a, &b| raw[a].total_cmp(&raw[b]));
        let mut running = 0.0f64;
        for (rank, &i) in order.iter().enumerate() {
            running = running.max(((raw.len() - rank) as f64 * raw[i]).min(1.0));
            let got = gaps[others[i]].2["p_worse"].as_f64().unwrap();
            assert!((got - running).abs() < 1e-12, "{got} {running}");
        }
        assert!(gaps[best].2["p_worse"].is_null());
    }
    // The best needed contender, if within the noise, with every needed one not excluded.
    let mut order: Vec<usize> = (0..chosen.len()).collect();
    order.sort_by(|&a, &b| chosen[a].0.total_cmp(&chosen[b].0));
    let best_within = order.first().is_some_and(|&b| {
        let h = chosen[b].0 / 2.0;
        (-h).exp() * (1.0 + h + h * h / 2.0) >= 0.01
    });
    let chosen: Vec<(f64, String, f64)> = if best_within {
        order
            .iter()
            .filter(|&&k| kept[k])
            .map(|&k| chosen[k].clone())
            .collect()
    } else {
        vec![]
    };
    let v = &json["verdict"];
    let any_needed = fits.iter().any(|f| f["needed"] == true);
    match chosen.as_slice() {
        [] if !any_needed && free["within_noise"] == true => {
            assert_eq!(v["verdict"], "no_effect", "{v}")
        }
        [] => assert_eq!(v["verdict"], "none_of_the_candidates", "{v}"),
        [(_, name, strength)] => {
            assert_eq!(v["verdict"], "effect", "{v}");
            assert_eq!(v["effects"][0]["name"].as_str(), Some(name.as_str()));
            assert_eq!(v["effects"][0]["strength"].as_f64(), Some(*strength));
        }
        several => {
            assert_eq!(v["verdict"], "ambiguous", "{v}");
            let names: Vec<&str> = several.iter().map(|w| w.1.as_str()).collect();
            assert_eq!(v["ambiguous"], serde_json::json!(names));
        }
    }
    let md = std::fs::read_to_string(out_dir.join("diagnosis.md")).unwrap();
    assert!(md.contains("Refitted on simulations"), "{md}");
    // `next` on refitted rivals simulates each rival's fitted model, not its linear step;
    // `free`, the free parameter's own fit, is the rival "no effect".
    {
        let mut rivals: Vec<&str> = fits.iter().map(|f| f["name"].as_str().unwrap()).collect();
        rivals.push("free");
        let menu = dir.join("menu.csv");
        std::fs::write(&menu, "test,moisture_pct\nrepose,6\n").unwrap();
        let next_dir = dir.join("next");
        let o = tilth(&[
            "next",
            "--diagnosis",
            out_dir.to_str().unwrap(),
            "--menu",
            menu.to_str().unwrap(),
            "--out",
            next_dir.to_str().unwrap(),
            "--rivals",
            &rivals.join(","),
            "--coarse",
            "--cores",
            "2",
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let next: serde_json::Value =
            serde_json::from_slice(&std::fs::read(next_dir.join("next.json")).unwrap()).unwrap();
        assert_eq!(next["mode"], "fitted");
        let option = &next["options"][0];
        assert_eq!(
            option["pairs"].as_array().unwrap().len(),
            rivals.len() * (rivals.len() - 1)
        );
        for rival in &rivals {
            assert!(
                next_dir.join(format!("runs/fitted-{rival}")).is_dir(),
                "{rival}"
            );
        }
        assert!(
            std::fs::read_to_string(next_dir.join("conditions.csv"))
                .unwrap()
                .starts_with("test,")
        );
    }
}
