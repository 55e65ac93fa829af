//! `tilth rsm` from the command line: the JSON contract, the published-table check, solving
//! and its pictures, and refusals.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::tilth_in_root as tilth;

const T6: &str = "sweeps/li2022/data/table06_pb_runs.csv";
const T7: &str = "sweeps/li2022/data/table07_pb_anova_reported.csv";
const T9: &str = "sweeps/li2022/data/table09_bbd_runs.csv";

#[test]
fn fit_json_has_the_documented_keys() {
    let out = tilth(&[
        "rsm",
        "fit",
        T6,
        "--response",
        "repose_angle_deg",
        "--factors",
        "x1,x2,x3,x4,x5,x6,x7",
        "--model",
        "linear",
        "--centre-curvature",
        "--json",
        "--reported",
        T7,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let terms = v["terms"].as_array().unwrap();
    assert_eq!(terms.len(), 8);
    for t in terms {
        for key in ["name", "coefficient", "sum_sq", "df", "f", "p"] {
            assert!(!t[key].is_null(), "term {t} lacks {key}");
        }
    }
    assert_eq!(terms[3]["name"], "x4");
    for key in ["r2", "adj_r2", "pred_r2", "adeq_precision"] {
        assert!(v[key].is_f64(), "{key}");
    }
    assert!(v["lack_of_fit"]["f"].is_f64() && v["lack_of_fit"]["p"].is_f64());
    assert!(v["curvature"]["sum_sq"].is_f64() && v["curvature"]["p"].is_f64());
    let bad: Vec<String> = v["reported_check"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["agrees"] == false)
        .map(|c| {
            format!(
                "{} {}",
                c["source"].as_str().unwrap(),
                c["field"].as_str().unwrap()
            )
        })
        .collect();
    assert_eq!(bad, ["x4 p"]);
}

#[test]
fn fit_text_shows_the_x4_discrepancy() {
    let out = tilth(&[
        "rsm",
        "fit",
        T6,
        "--response",
        "repose_angle_deg",
        "--factors",
        "x1,x2,x3,x4,x5,x6,x7",
        "--centre-curvature",
        "--reported",
        T7,
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(text.contains("45 of 46 reported values agree"), "{text}");
    assert!(
        text.contains("DIFFERS: x4 p: the source prints 0.007, its data give 0.0022"),
        "{text}"
    );
}

/// `tilth rsm solve` on table 9's quadratic in the study's units, `fix`ed, drawing into `plot`.
fn solve_t9(fix: &str, targets: &str, plot: &Path) -> Output {
    tilth(&[
        "rsm",
        "solve",
        T9,
        "--response",
        "repose_angle_deg",
        "--factors",
        "x4_coded,x6_coded,x7_coded",
        "--names",
        "x4,x6,x7",
        "--levels",
        "x4_coded=0.25:0.65,x6_coded=0.15:0.35,x7_coded=0.125:0.625",
        "--model",
        "quadratic",
        "--fix",
        fix,
        "--target",
        targets,
        "--plot",
        plot.to_str().unwrap(),
    ])
}

#[test]
fn solve_states_the_ridge_and_draws_it() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rsm-solve");
    let _ = std::fs::remove_dir_all(&dir);
    let out = solve_t9("x4=0.45", "3%=32.76,6%=35.53,9%=37.89,12%=43.87", &dir);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        text.matches("one target cannot separate x6 and x7").count(),
        4,
        "{text}"
    );
    for m in ["3_", "6_", "9_", "12_"] {
        let svg =
            std::fs::read_to_string(dir.join(format!("contour-repose_angle_deg-{m}.svg"))).unwrap();
        assert!(svg.contains("<svg") && svg.contains("x7"));
    }
}

#[test]
fn solve_draws_the_response_against_one_free_factor_with_its_runs_and_targets() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("rsm-solve-curve");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // y = 10 + 2 x plus fixed scatter, two runs per level.
    let noise = [0.3, -0.2, 0.1, -0.4, 0.2, 0.0, -0.1, 0.4, -0.3, 0.1];
    let mut csv = String::from("x,y\n");
    for (k, e) in noise.iter().enumerate() {
        let x = (k % 5) as f64;
        csv += &format!("{x},{}\n", 10.0 + 2.0 * x + e);
    }
    let data = dir.join("runs.csv");
    std::fs::write(&data, csv).unwrap();
    let plots = dir.join("plots");
    let out = tilth(&[
        "rsm",
        "solve",
        data.to_str().unwrap(),
        "--response",
        "y",
        "--factors",
        "x",
        "--target",
        "low=12.5,high=16.25",
        "--plot",
        plots.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(plots.join("solve-y.svg")).unwrap();
    // Ten runs as points (plus the legend's), both targets labelled with their setting.
    assert!(svg.matches("<circle").count() >= noise.len(), "{svg}");
    assert!(
        svg.contains("low: x = 1.2") && svg.contains("high: x = 3.1"),
        "{svg}"
    );

    // Three factors, two held: the curve along the third, without runs (they lie elsewhere).
    let plots = dir.join("plots-t9");
    let out = solve_t9("x4=0.45,x7=0.375", "6%=35.53", &plots);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(plots.join("solve-repose_angle_deg.svg")).unwrap();
    assert!(svg.contains("x4 = 0.45") && svg.contains("6%: "), "{svg}");
    assert!(!svg.contains("runs ("), "{svg}");
}

#[test]
fn refusals_name_the_problem() {
    let out = tilth(&[
        "rsm",
        "fit",
        T9,
        "--response",
        "err_6pct",
        "--factors",
        "x6_coded,x7_coded",
        "--model",
        "quadratic",
        "--where",
        "x4_coded=0",
    ]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("6 runs are too few for the quadratic model of 2 factors")
            && e.contains("at least 7"),
        "{e}"
    );
    let out = tilth(&[
        "rsm",
        "fit",
        T9,
        "--response",
        "err_6pct",
        "--factors",
        "x4_coded",
        "--model",
        "cubic",
    ]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("--model \"cubic\" is not a model: allowed linear, 2fi, quadratic"),
        "{e}"
    );
    let out = tilth(&[
        "rsm",
        "solve",
        T9,
        "--response",
        "repose_angle_deg",
        "--factors",
        "x4_coded,x6_coded,x7_coded",
        "--model",
        "quadratic",
        "--fix",
        "x4_coded=3",
        "--target",
        "35",
    ]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("outside the design's range of x4_coded, allowed [-1, 1]"),
        "{e}"
    );
}

/// `text` as `results.csv` in a fresh test directory `name`.
fn table_in(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("results.csv");
    std::fs::write(&csv, text).unwrap();
    csv
}

/// A sweep's results table: runs that did not finish are left out, with a warning naming
/// their lines.
#[test]
fn unfinished_runs_are_left_out() {
    let csv = table_in(
        "rsm-status",
        "run,a,b,status,y\n1,-1,-1,done,1\n2,1,-1,done,3\n3,-1,1,done,2\n4,1,1,done,4.5\n5,0,0,failed,99\n6,0,0,done,2.6\n",
    );
    let out = tilth(&[
        "rsm",
        "fit",
        csv.to_str().unwrap(),
        "--response",
        "y",
        "--factors",
        "a,b",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("1 run(s) whose status is not `done` left out (lines 6)"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["runs"], 5);
    // The mean of the five finished runs, not the failed run's 99.
    assert!((v["mean"].as_f64().unwrap() - 13.1 / 5.0).abs() < 1e-12);
}

/// `--where COLUMN=LO:HI` keeps the rows inside a closed range (either end open), as a user
/// fitting part of a curve needs; a malformed range is refused with what it takes.
#[test]
fn where_takes_a_range_of_a_column() {
    // y = 2 x on x <= 400, flat above: a line fitted to the first part has slope 2 exactly.
    let csv = table_in(
        "rsm-where",
        "tau,y\n100,200\n200,400\n300,600\n400,800\n500,810\n600,805\n",
    );
    let fit = |filter: &str| {
        tilth(&[
            "rsm",
            "fit",
            csv.to_str().unwrap(),
            "--response",
            "y",
            "--factors",
            "tau",
            "--model",
            "linear",
            "--where",
            filter,
            "--json",
        ])
    };
    for (filter, runs, mean) in [
        ("tau=100:400", 4, 500.0),
        ("tau=:400", 4, 500.0),
        ("tau=200:", 5, (400.0 + 600.0 + 800.0 + 810.0 + 805.0) / 5.0),
    ] {
        let out = fit(filter);
        assert!(
            out.status.success(),
            "{filter}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["runs"], runs, "{filter}");
        assert!(
            (v["mean"].as_f64().unwrap() - mean).abs() < 1e-9,
            "{filter}: {v}"
        );
    }
    // On the straight part the fit is exact: R^2 = 1.
    let v: serde_json::Value = serde_json::from_slice(&fit("tau=100:400").stdout).unwrap();
    assert!((v["r2"].as_f64().unwrap() - 1.0).abs() < 1e-12, "{v}");
    for (filter, words) in [
        ("tau=500:100", "low end 500 is above its high end 100"),
        ("tau=a:400", "\"a\" is not a number"),
        ("tau=:", "a range needs at least one end"),
        ("tau=700:800", "no row has tau in [700, 800]"),
    ] {
        let out = fit(filter);
        assert_eq!(out.status.code(), Some(2), "{filter}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(words), "{filter}: {e}");
    }
}
