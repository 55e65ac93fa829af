//! Measurement files: bad ones are refused before any run, naming row and column; `tilth
//! synth` writes files in the same format that `compare` reads back.

use std::path::{Path, PathBuf};

use crate::tilth_in_root as tilth;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `tilth synth --truth models/li2022.toml ARGS --coarse --quiet`.
fn synth_li2022(args: &[&str]) -> std::process::Output {
    let mut all = vec!["synth", "--truth", "models/li2022.toml"];
    all.extend(args);
    all.extend(["--coarse", "--quiet"]);
    tilth(&all)
}

const HEAD: &str = "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source";

/// `compare` on a data file with one bad row: fails, names the file, row and column and
/// what is allowed, and leaves no run behind.
fn refused(case: &str, csv: &str, expect: &[&str]) {
    let dir = scratch(&format!("measurements-{case}"));
    let data = dir.join("data.csv");
    std::fs::write(&data, csv).unwrap();
    let out_dir = dir.join("out");
    let out = tilth(&[
        "compare",
        "--model",
        "models/li2022.toml",
        "--data",
        data.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{case}: accepted");
    for e in expect {
        assert!(err.contains(e), "{case}: `{e}` not in: {err}");
    }
    assert!(err.contains("data.csv"), "{case}: file not named: {err}");
    assert!(!out_dir.exists(), "{case}: runs started before the check");
}

#[test]
fn a_missing_column_is_named() {
    refused(
        "missing-column",
        "test,moisture_pct,observable,unit\nrepose,6,repose_angle_deg,deg\n",
        &["missing column value"],
    );
}

#[test]
fn an_unknown_test_is_named_with_its_row() {
    refused(
        "unknown-test",
        &format!(
            "{HEAD}\nrepose,6,,,repose_angle_deg,35.5,deg,,,\nheap,6,,,repose_angle_deg,35.5,deg,,,\n"
        ),
        &[
            "row 3, column test",
            "`heap` is unknown",
            "allowed: repose, direct_shear, ucs, tilt",
        ],
    );
}

#[test]
fn an_unknown_observable_is_named_with_its_row() {
    refused(
        "unknown-observable",
        &format!("{HEAD}\nucs,6,1.55,,peak_shear_force_n,259,kPa,,,\n"),
        &["row 2, column observable", "measures `ucs_kpa`"],
    );
}

#[test]
fn a_condition_outside_the_model_is_named_with_the_range() {
    refused(
        "outside-range",
        &format!(
            "{HEAD}\nrepose,6,,,repose_angle_deg,35.5,deg,,,\nrepose,15,,,repose_angle_deg,40,deg,,,\n"
        ),
        &[
            "row 3, column moisture_pct",
            "outside the model's range [3, 12]",
        ],
    );
}

#[test]
fn a_non_positive_uncertainty_is_refused() {
    for (case, u) in [("zero-uncertainty", "0"), ("negative-uncertainty", "-1.5")] {
        refused(
            case,
            &format!("{HEAD}\nrepose,6,,,repose_angle_deg,35.5,deg,{u},,\n"),
            &["row 2, column uncertainty", "allowed > 0"],
        );
    }
}

#[test]
fn a_bad_uncertainty_dof_is_refused() {
    let head = HEAD.replace("uncertainty,", "uncertainty,uncertainty_dof,");
    for (case, u, dof) in [
        ("zero-dof", "0.5", "0"),
        ("negative-dof", "0.5", "-3"),
        ("dof-without-uncertainty", "", "3"),
    ] {
        refused(
            case,
            &format!("{head}\nrepose,6,,,repose_angle_deg,35.5,deg,{u},{dof},,\n"),
            &[
                "row 2, column uncertainty_dof",
                "allowed > 0 beside an uncertainty",
            ],
        );
    }
}

#[test]
fn a_needed_condition_left_empty_is_named() {
    refused(
        "empty-condition",
        &format!("{HEAD}\nucs,6,,,ucs_kpa,259,kPa,,,\n"),
        &["row 2, column firmness_mpa", "empty"],
    );
}

#[test]
fn a_value_that_is_not_a_number_is_named() {
    refused(
        "not-a-number",
        &format!("{HEAD}\nrepose,6,,,repose_angle_deg,35.5deg,deg,,,\n"),
        &["row 2, column value", "not a finite number"],
    );
}

/// Noise 0: the file holds exactly what the truth's runs reduced to, and compare reads it
/// back (a model compared with its own noiseless output at the same seed has no residual).
/// With noise, the same seed gives the same file and `uncertainty` is the noise's SD.
#[test]
fn synth_writes_what_the_truth_simulates_and_compare_reads_it() {
    let dir = scratch("synth");
    let cond = dir.join("conditions.csv");
    std::fs::write(&cond, "test,moisture_pct\nrepose,6\nrepose,12\n").unwrap();
    let synth = |out: &Path, noise: &str| {
        let o = synth_li2022(&[
            "--conditions",
            cond.to_str().unwrap(),
            "--noise",
            noise,
            "--seed",
            "0",
            "--out",
            out.to_str().unwrap(),
            "--work",
            dir.join("runs").to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(out).unwrap()
    };
    let exact = synth(&dir.join("exact.csv"), "repose_angle_deg=0");
    let noisy = synth(&dir.join("noisy.csv"), "repose_angle_deg=2%");
    let again = synth(&dir.join("again.csv"), "repose_angle_deg=2%");
    assert_eq!(noisy, again, "same seed, different file");
    let values = |text: &str, col: usize| -> Vec<String> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').nth(col).unwrap().to_string())
            .collect()
    };
    let (ex, no) = (values(&exact, 5), values(&noisy, 5));
    assert_eq!(values(&exact, 7), vec!["", ""], "no noise, no uncertainty");
    for (e, n) in ex.iter().zip(&no) {
        let (e, n): (f64, f64) = (e.parse().unwrap(), n.parse().unwrap());
        assert_ne!(e, n, "noise not added");
        assert!(
            (n - e).abs() < 5.0 * 0.02 * e,
            "noise far beyond 5 SD: {e} -> {n}"
        );
    }
    for (e, u) in ex.iter().zip(values(&noisy, 7)) {
        let (e, u): (f64, f64) = (e.parse().unwrap(), u.parse().unwrap());
        assert!(
            (u - 0.02 * e).abs() <= 1e-12 * e,
            "uncertainty {u} is not 2 % of {e}"
        );
    }

    // The truth's runs used seed 1 (seed 0's block); compare's first replicate uses seed 1
    // too, so the model compared with its own exact output has zero residual.
    let o = tilth(&[
        "compare",
        "--model",
        "models/li2022.toml",
        "--data",
        dir.join("exact.csv").to_str().unwrap(),
        "--out",
        dir.join("compare").to_str().unwrap(),
        "--coarse",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("compare/compare.json")).unwrap()).unwrap();
    for row in json["rows"].as_array().unwrap() {
        assert_eq!(row["residual"].as_f64(), Some(0.0), "{row}");
    }
    // The summary in words and the plots it refers to.
    let words = json["summary"].as_str().unwrap();
    assert!(words.contains("RMSE 0.000 deg"), "{words}");
    assert!(words.contains("No overall bias"), "{words}");
    for plot in json["plots"].as_array().unwrap() {
        let svg =
            std::fs::read_to_string(dir.join("compare").join(plot.as_str().unwrap())).unwrap();
        assert!(svg.starts_with("<svg"), "{plot}");
    }
    assert_eq!(json["plots"].as_array().unwrap().len(), 2);
}

/// `tilth report`: two compare runs of a project become one offline page, the errors in a
/// table (a fall marked as better), their plots side by side, nothing fetched.
#[test]
fn report_puts_a_projects_compare_runs_side_by_side() {
    let dir = scratch("report");
    let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" height=\"10\"><circle cx=\"5\" cy=\"5\" r=\"MARK\"/></svg>";
    for (name, created, rmse, mark) in [("v1", 1.0, 8.1, "4"), ("v2", 2.0, 2.5, "3")] {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(
            d.join("residual-repose-moisture_pct.svg"),
            svg.replace("MARK", mark),
        )
        .unwrap();
        // A plot that only the first run still has, and one that neither has.
        if name == "v1" {
            std::fs::write(d.join("sim.svg"), svg.replace("MARK", "7")).unwrap();
        }
        let json = serde_json::json!({
            "created": created,
            "model": format!("models/{name}.toml"),
            "data": "d.csv",
            "replicates": 2,
            "rows": [],
            "observables": {"repose_angle_deg": {"rmse": rmse, "mean_relative_error": rmse / 35.0, "n": 4}},
            "verdicts": [{"observable": "repose_angle_deg", "unit": "deg"}],
            "summary": format!("- **repose** (repose_angle_deg): RMSE {rmse} deg.\n"),
            "plots": ["residual-repose-moisture_pct.svg", "sim.svg", "gone.svg"],
        });
        std::fs::write(d.join("compare.json"), json.to_string()).unwrap();
    }
    let o = tilth(&["report", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let v1 = html.find("models/v1.toml").unwrap();
    let v2 = html.find("models/v2.toml").unwrap();
    assert!(v1 < v2, "oldest first");
    assert!(
        html.contains("<td class=\"better\">2.5000<br><small>7.1 %</small></td>"),
        "the fall is marked, with the mean relative error under the RMSE"
    );
    // One row per observable with its unit, one column per run.
    assert!(
        html.contains("<td class=\"l\">repose_angle_deg (deg)</td><td>8.1000<br><small>23.1 %</small></td><td class=\"better\">"),
        "a row per observable"
    );
    assert!(
        html.contains("<th>1. v1</th><th>2. v2</th>"),
        "a column per run"
    );
    assert!(
        html.contains("r=\"4\"") && html.contains("r=\"3\""),
        "both runs' plots inlined"
    );
    assert!(
        html.contains("r=\"7\"") && html.contains("(file not found)<br>2. v2"),
        "a plot one run lost keeps its place in the row"
    );
    assert!(
        !html.contains("<h3>gone.svg</h3>")
            && html.contains("found beside none of them: gone.svg."),
        "a plot no run has is named, not drawn as an empty heading"
    );
    assert!(
        !html.contains("src=\"http") && !html.contains("href=\"http"),
        "nothing fetched"
    );
    assert!(!html.contains("<script"), "no scripts");
    // A directory without compare runs is refused with what to do.
    let empty = scratch("report-empty");
    let o = tilth(&["report", empty.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no compare run below it"));
}

/// `tilth report` tells the loop's story in order: each compare's errors, the diagnosis's
/// verdict, `next`'s suggestion and the fit's model diff (the effect added and the parameter
/// moved, with standard errors), ordered by `created` or, where a step has none, its file's
/// modification time.
#[test]
fn report_tells_the_loops_story_with_verdicts_and_model_diffs() {
    let dir = scratch("report-story");
    let now = std::time::SystemTime::now();
    let at = |s: u64| now - std::time::Duration::from_secs(1000 - s);
    let epoch = |s: u64| {
        at(s)
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_secs_f64()
    };
    let write = |sub: &str, file: &str, json: serde_json::Value, when: u64| {
        let d = dir.join(sub);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join(file), json.to_string()).unwrap();
        let f = std::fs::File::options()
            .write(true)
            .open(d.join(file))
            .unwrap();
        f.set_modified(at(when)).unwrap();
    };
    let compare = |model: &str, rmse: f64, when: u64| {
        serde_json::json!({
            "created": epoch(when), "model": model, "data": "d.csv", "replicates": 4, "rows": [],
            "observables": {"heap_cone_angle_deg": {"rmse": rmse, "mean_relative_error": 0.1, "n": 4}},
            "verdicts": [], "summary": "", "plots": [],
        })
    };
    write(
        "1-compare",
        "compare.json",
        compare("models/li2022.toml", 6.1675, 10),
        10,
    );
    write(
        "2-diagnose",
        "diagnosis.json",
        serde_json::json!({"verdict": {"verdict": "effect", "alpha": 0.01, "ambiguous": [],
            "effects": [{"name": "fines", "strength": 0.1821, "standard_error": 0.0131, "p_value": 1e-9}],
            "misfit": {"chi2": 12.5, "dof": 13, "noise": 1.0, "p_value": 0.49}, "encompassing": []}}),
        20,
    );
    write(
        "3-next",
        "next.json",
        serde_json::json!({"alpha": 0.01, "rivals": ["plastic_adhesion", "twisting"],
            "options": [{"test": "direct_shear", "conditions": {"moisture_pct": 3.0},
                "observables": ["peak_shear_force_n"], "power": 0.93, "runs": 36, "separation": 4.0}]}),
        30,
    );
    write(
        "4-fit",
        "fit.json",
        serde_json::json!({"model": "models/li2022.toml", "fitted_model": "4-fit/model.toml",
            "chi2": 14.2, "dof": 14, "estimate": [0.0312, 0.1594], "standard_error": [0.011, 0.0072],
            "parameters": [
                {"label": "soil-soil.rolling_friction", "target": {"offset": {"path": "soil-soil.rolling_friction"}}, "start": 0.0, "low": -0.1, "high": 0.2},
                {"label": "fines", "target": {"candidate": {"name": "fines"}}, "start": 0.18, "low": 0.0, "high": 0.5}]}),
        40,
    );
    write(
        "5-compare",
        "compare.json",
        compare("4-fit/model.toml", 1.2, 50),
        50,
    );
    let o = tilth(&["report", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let story = &html[html
        .find("The story, step by step")
        .expect("a story section")..];
    let lines = [
        "<td>1</td><td class=\"l\">compare</td><td class=\"l path\">1-compare</td><td class=\"l\">models/li2022.toml against d.csv: RMSE heap_cone_angle_deg 6.1675</td>",
        "<td>2</td><td class=\"l\">diagnose</td><td class=\"l path\">2-diagnose</td><td class=\"l\">effect: fines (strength 0.1821 ± 0.0131); misfit chi^2 12.5 on 13 degrees of freedom, p 0.490</td>",
        "<td>3</td><td class=\"l\">next</td><td class=\"l path\">3-next</td><td class=\"l\">to tell apart plastic_adhesion, twisting: measure direct_shear at moisture_pct 3.0 (peak_shear_force_n), power 0.93 at alpha 0.01, 36 runs</td>",
        "<td>4</td><td class=\"l\">fit</td><td class=\"l path\">4-fit</td><td class=\"l\">models/li2022.toml -&gt; 4-fit/model.toml: ~ soil-soil.rolling_friction: moved by +0.0312 ± 0.0110; + effect fines: strength 0.1594 ± 0.0072; chi^2 14.2 on 14 degrees of freedom</td>",
        "<td>5</td><td class=\"l\">compare</td><td class=\"l path\">5-compare</td><td class=\"l\">4-fit/model.toml against d.csv: RMSE heap_cone_angle_deg 1.2000</td>",
    ];
    let mut from = 0;
    for line in lines {
        let k = story[from..]
            .find(line)
            .unwrap_or_else(|| panic!("missing or out of order: {line}\n{story}"));
        from += k + line.len();
    }
}

/// A repose run gives several readings: rows of one test at the same conditions share their
/// runs, and with `--replicates N` each value is the mean of N truth runs, its uncertainty
/// sqrt(noise^2 + s^2 / N) with s their scatter (read back from the runs' summaries here).
#[test]
fn synth_shares_runs_between_observables_and_averages_replicates() {
    let dir = scratch("synth-observables");
    let cond = dir.join("conditions.csv");
    std::fs::write(
        &cond,
        "test,moisture_pct,observable\nrepose,6,heap_cone_angle_deg\nrepose,6,funnel_flow_rate_g_s\nrepose,6,tray_mass_g\n",
    )
    .unwrap();
    let out = dir.join("data.csv");
    let o = synth_li2022(&[
        "--conditions",
        cond.to_str().unwrap(),
        "--noise",
        "heap_cone_angle_deg=0,funnel_flow_rate_g_s=0,tray_mass_g=0.5",
        "--replicates",
        "2",
        "--seed",
        "0",
        "--out",
        out.to_str().unwrap(),
        "--work",
        dir.join("runs").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let runs: Vec<serde_json::Value> = (1..=3)
        .filter_map(|k| {
            std::fs::read(dir.join(format!("runs/repose/runs/{k:03}/summary.json"))).ok()
        })
        .map(|b| serde_json::from_slice(&b).unwrap())
        .collect();
    assert_eq!(
        runs.len(),
        2,
        "three observables at one condition: 2 runs, not 6"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 3);
    for row in &rows {
        let key = row[col("observable")];
        let v: Vec<f64> = runs
            .iter()
            .map(|r| r["experiment"][key].as_f64().unwrap())
            .collect();
        let mean = 0.5 * (v[0] + v[1]);
        // Two values: s = |a - b| / sqrt(2), s / sqrt(2) = |a - b| / 2.
        let se = 0.5 * (v[0] - v[1]).abs();
        let value: f64 = row[col("value")].parse().unwrap();
        let u: f64 = row[col("uncertainty")].parse().unwrap();
        let dof: f64 = row[col("uncertainty_dof")].parse().unwrap();
        assert_eq!(row[col("replicates")], "2", "{key}: replicates");
        if key == "tray_mass_g" {
            assert!((u - 0.5f64.hypot(se)).abs() < 1e-9 * u, "{key}: {u}");
            assert!((value - mean).abs() < 5.0 * 0.5, "{key}: noise beyond 5 SD");
            // Welch-Satterthwaite: (0.5^2 + se^2)^2 / (se^4 / 1), the noise exact.
            let want = u.powi(4) / se.powi(4);
            assert!(
                (dof - want).abs() < 1e-9 * want,
                "{key}: dof {dof} vs {want}"
            );
        } else {
            assert!(
                (value - mean).abs() <= 1e-9 * mean.abs(),
                "{key}: {value} vs {mean}"
            );
            assert!((u - se).abs() <= 1e-9 * se, "{key}: {u} vs {se}");
            // All of u is the scatter of 2 runs: 1 degree of freedom.
            assert!((dof - 1.0).abs() < 1e-9, "{key}: dof {dof}");
        }
    }
    // A reading the test does not give is refused, naming the ones it does.
    std::fs::write(&cond, "test,moisture_pct,observable\nrepose,6,ucs_kpa\n").unwrap();
    let o = synth_li2022(&[
        "--conditions",
        cond.to_str().unwrap(),
        "--noise",
        "ucs_kpa=1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("row 2, column observable") && err.contains("`funnel_flow_rate_g_s`"),
        "{err}"
    );
}

/// `--shift PAIR.KEY=DELTA` moves every number of the truth's parameter by DELTA (its
/// interpolation points here), in the truth written next to the data; a shift of a key the
/// laws do not take, or by no number, is refused before any run.
#[test]
fn synth_shifts_a_parameter_of_the_truth() {
    let dir = scratch("synth-shift");
    let cond = dir.join("conditions.csv");
    std::fs::write(
        &cond,
        "test,moisture_pct,observable\nrepose,6,tray_mass_g\n",
    )
    .unwrap();
    let synth = |shift: &str, out: &Path| {
        synth_li2022(&[
            "--shift",
            shift,
            "--conditions",
            cond.to_str().unwrap(),
            "--noise",
            "tray_mass_g=0.5",
            "--out",
            out.to_str().unwrap(),
            "--work",
            dir.join("runs").to_str().unwrap(),
        ])
    };
    let rolling = |path: &Path| -> Vec<f64> {
        let t: toml::Table = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        t["pairs"]["soil-soil"]["rolling_friction"]["y"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect()
    };
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    for (bad, expect) in [
        (
            "soil-soil.rolling_fricton=0.05",
            "unknown key 'rolling_fricton'",
        ),
        (
            "soil-soil.rolling_friction=much",
            "`much` is not a finite number",
        ),
        ("rolling_friction=0.05", "expected PAIR.KEY=DELTA"),
    ] {
        let o = synth(bad, &dir.join("bad.csv"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(expect), "{bad}: {err}");
        assert!(
            !dir.join("runs").exists(),
            "{bad}: runs started before the check"
        );
    }
    let out = dir.join("data.csv");
    let o = synth("soil-soil.rolling_friction=0.05", &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (was, now) = (rolling(&model), rolling(&dir.join("data.truth.toml")));
    assert_eq!(was.len(), now.len());
    for (a, b) in was.iter().zip(&now) {
        assert_eq!(*b, a + 0.05, "{was:?} shifted: {now:?}");
    }
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("shifted soil-soil.rolling_friction=0.05"),
        "{text}"
    );
}
