//! The `tilth` binary: output, exit codes.

use super::configs;
use std::process::{Command, Output};

fn tilth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tilth"))
        .args(args)
        .output()
        .expect("tilth runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn run_json_reports_the_scene() {
    let scene = configs("good").join("drop_onto_plane.toml");
    let out = tilth(&["run", scene.to_str().unwrap(), "--json", "--quiet"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["particles"], 4);
    assert_eq!(v["steps"], 4000);
    assert_eq!(v["threads"], 1);
    assert_eq!(
        v["laws"],
        serde_json::json!(["hertz", "restitution", "mindlin"])
    );
    assert_eq!(v["walls"][0]["name"], "floor");
    assert_eq!(v["walls"][0]["type"], "plane");
    assert_eq!(v["samples"].as_array().unwrap().len(), 5);
    for key in [
        "simulated_time",
        "wall_seconds",
        "particle_steps_per_second",
        "kinetic_energy",
        "total_weight",
        "neighbour_rebuilds",
    ] {
        assert!(
            v[key].as_f64().is_some_and(|x| x >= 0.0),
            "{key}: {}",
            v[key]
        );
    }
    // Where the stepping loop's time went: the step's parts in order, then the rest; they
    // were timed inside the loop, so they add up to its wall time.
    let parts = v["time_breakdown"].as_array().unwrap();
    let names: Vec<&str> = parts.iter().map(|p| p["part"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "integrate",
            "insert",
            "neighbor",
            "pair",
            "particle",
            "other"
        ]
    );
    let seconds: Vec<f64> = parts
        .iter()
        .map(|p| p["seconds"].as_f64().unwrap())
        .collect();
    assert!(seconds.iter().all(|&s| s >= 0.0), "{seconds:?}");
    assert!(
        seconds[3] > 0.0,
        "the pair forces took no time: {seconds:?}"
    );
    let wall = v["wall_seconds"].as_f64().unwrap();
    let sum: f64 = seconds.iter().sum();
    assert!(
        (sum - wall).abs() <= 1e-9 * wall,
        "parts {sum} s, loop {wall} s"
    );
    // The floor carries (part of) the weight: pushed down, not pulled up.
    let fraction = v["walls"][0]["weight_fraction"].as_f64().unwrap();
    assert!(fraction > 0.0 && fraction < 1.5, "{fraction}");
}

#[test]
fn run_text_summary() {
    let scene = configs("good").join("drop_onto_plane.toml");
    let out = tilth(&["run", scene.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    for line in [
        "scene ",
        "steps ",
        "speed ",
        "time per part",
        "neighbour rebuilds",
        "wall floor",
    ] {
        assert!(
            s.lines().any(|l| l.starts_with(line)),
            "no `{line}` line in\n{s}"
        );
    }
}

#[test]
fn bad_input_exits_2_naming_file_and_key() {
    let scene = configs("bad").join("restitution_out_of_range.toml");
    let out = tilth(&["run", scene.to_str().unwrap(), "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("restitution_out_of_range.toml: pairs[soil-soil].restitution = 1.5"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn failed_run_exits_1() {
    let scene = configs("fails").join("escapes_domain.toml");
    let out = tilth(&["run", scene.to_str().unwrap(), "--quiet"]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.contains("escapes_domain.toml") && err.contains("left the domain"),
        "{err}"
    );
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(tilth(&["run", "--threads", "0"]).status.code(), Some(2));
    assert_eq!(tilth(&["frobnicate"]).status.code(), Some(2));
    assert_eq!(tilth(&["run", "no/such/file.toml"]).status.code(), Some(2));
}

#[test]
fn laws_lists_every_law_and_parameter() {
    let out = tilth(&["laws"]);
    assert!(out.status.success());
    let s = text(&out.stdout);
    for law in tilth_kernel::contact::laws::REGISTRY {
        assert!(s.contains(law.name), "{} missing", law.name);
        for p in law.params {
            assert!(
                s.contains(p.key) && s.contains(&p.range_text()),
                "{}.{} missing",
                law.name,
                p.key
            );
        }
    }
}

#[test]
fn thread_count_does_not_change_results() {
    let scene = configs("good").join("drop_onto_plane.toml");
    let run = |threads: &str| {
        let out = tilth(&[
            "run",
            scene.to_str().unwrap(),
            "--json",
            "--quiet",
            "--threads",
            threads,
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            v["kinetic_energy"].clone(),
            v["walls"][0]["force"].clone(),
            v["threads"].clone(),
        )
    };
    let (one, two) = (run("1"), run("2"));
    assert_eq!((&one.0, &one.1), (&two.0, &two.1));
    assert_eq!((one.2, two.2), (1.into(), 2.into()));
}

#[test]
fn bench_lab_refuses_a_scene_file_before_any_run() {
    let scratch = std::env::temp_dir().join("tilth-bench-lab-refuses");
    let _ = std::fs::remove_dir_all(&scratch);
    let out = crate::tilth_in_root(&[
        "bench",
        "lab",
        "sweeps/experiments/repose.toml",
        "sweeps/scenes/pile.toml",
        "--scratch",
        scratch.to_str().unwrap(),
    ]);
    let err = text(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("sweeps/scenes/pile.toml"), "{err}");
    // Checked before the first run: the valid file was not run either.
    assert!(!err.contains("run 1/"), "{err}");
    assert!(!scratch.exists());
}

#[test]
fn bench_lab_times_a_coarse_funnel_and_removes_its_files() {
    let scratch = std::env::temp_dir().join("tilth-bench-lab-times");
    let _ = std::fs::remove_dir_all(&scratch);
    let out = crate::tilth_in_root(&[
        "bench",
        "lab",
        "sweeps/experiments/repose.toml",
        "--threads",
        "1",
        "--quiet",
        "--scratch",
        scratch.to_str().unwrap(),
    ]);
    let table = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let rows: Vec<&str> = table.lines().filter(|l| l.starts_with("sweeps/")).collect();
    assert_eq!(rows.len(), 1, "{table}");
    let cols: Vec<&str> = rows[0].split_whitespace().collect();
    assert_eq!(
        &cols[..3],
        ["sweeps/experiments/repose.toml", "coarse", "1"]
    );
    let wall: f64 = cols[3].parse().unwrap();
    let per_hour: f64 = cols[4].parse().unwrap();
    // Two cores filled with one-thread runs: twice 3600 s over the wall time.
    assert!(
        (per_hour - 7200.0 / wall).abs() <= 0.05 * per_hour + 0.1,
        "{table}"
    );
    let particles: u64 = cols[5].parse().unwrap();
    assert!(particles > 0, "{table}");
    // The runs' files are scratch: nothing is left in the directory.
    let left = std::fs::read_dir(&scratch).map(|d| d.count()).unwrap_or(0);
    assert_eq!(left, 0, "{}", scratch.display());
}
