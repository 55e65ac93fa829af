//! `tilth sweep`: plans against the study's tables, bad sweep files, resume after SIGKILL,
//! a clean stop on SIGTERM.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn tilth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tilth"))
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
}

fn sweeps(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/sweeps")
        .join(p)
}

fn plan_json(file: &Path) -> serde_json::Value {
    let out = tilth()
        .args(["sweep", "plan", "--json"])
        .arg(file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Rows of a CSV file as maps column -> text.
fn csv(path: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            head.iter()
                .map(|h| h.to_string())
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

#[test]
fn plackett_burman_plan_is_table_6() {
    let plan = plan_json(&repo("sweeps/li2022/pb.toml"));
    let table = csv(&repo("sweeps/li2022/data/table06_pb_runs.csv"));
    let runs = plan["runs"].as_array().unwrap();
    assert_eq!(runs.len(), table.len());
    let levels = csv(&repo("sweeps/li2022/data/table05_pb_factors.csv"));
    for (run, row) in runs.iter().zip(&table) {
        assert_eq!(run["id"].to_string(), row["run"]);
        for (k, lv) in levels.iter().enumerate() {
            let x = format!("x{}", k + 1);
            let coded: f64 = row[&x].parse().unwrap();
            assert_eq!(
                run["coded"][&x].as_f64().unwrap(),
                coded,
                "run {} {x}",
                row["run"]
            );
            // Real units: the linear map between table 5's low and high levels.
            let (lo, hi): (f64, f64) = (lv["low"].parse().unwrap(), lv["high"].parse().unwrap());
            let real = run["values"][&x].as_f64().unwrap();
            assert!((real - (lo + (hi - lo) * (coded + 1.0) / 2.0)).abs() < 1e-12);
        }
    }
}

#[test]
fn box_behnken_plan_is_table_9() {
    let plan = plan_json(&repo("sweeps/li2022/bbd.toml"));
    let table = csv(&repo("sweeps/li2022/data/table09_bbd_runs.csv"));
    let runs = plan["runs"].as_array().unwrap();
    // 14 printed runs plus the missing centre point.
    assert_eq!(runs.len(), 15);
    assert_eq!(table.len(), 14);
    for (run, row) in runs.iter().zip(&table) {
        for x in ["x4", "x6", "x7"] {
            let coded: f64 = row[&format!("{x}_coded")].parse().unwrap();
            assert_eq!(
                run["coded"][x].as_f64().unwrap(),
                coded,
                "run {} {x}",
                row["run"]
            );
        }
    }
    assert!(
        ["x4", "x6", "x7"]
            .iter()
            .all(|x| runs[14]["coded"][x] == 0.0)
    );
    let levels = csv(&repo("sweeps/li2022/data/table09_bbd_levels.csv"));
    for lv in &levels {
        let x = &lv["factor"];
        for (code, key) in [(-1.0, "minus1"), (0.0, "zero"), (1.0, "plus1")] {
            let run = runs.iter().find(|r| r["coded"][x] == code).unwrap();
            let want: f64 = lv[key].parse().unwrap();
            assert!(
                (run["values"][x].as_f64().unwrap() - want).abs() < 1e-12,
                "{x} at {code}"
            );
        }
    }
}

#[test]
fn steepest_ascent_plan_is_table_8() {
    let plan = plan_json(&repo("sweeps/li2022/steepest_ascent.toml"));
    let table = csv(&repo("sweeps/li2022/data/table08_steepest_ascent.csv"));
    let runs = plan["runs"].as_array().unwrap();
    assert_eq!(runs.len(), table.len());
    for (run, row) in runs.iter().zip(&table) {
        for x in ["x4", "x6", "x7"] {
            let want: f64 = row[x].parse().unwrap();
            assert!(
                (run["values"][x].as_f64().unwrap() - want).abs() < 1e-12,
                "{x}: {row:?}"
            );
        }
    }
}

#[test]
fn bad_sweep_files_are_refused_with_file_line_and_reason() {
    let dir = sweeps("bad");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let file = e.unwrap().path();
        let text = std::fs::read_to_string(&file).unwrap();
        let expected: Vec<&str> = text
            .lines()
            .filter_map(|l| l.strip_prefix("# error: "))
            .collect();
        assert!(
            !expected.is_empty(),
            "{} has no `# error:` line",
            file.display()
        );
        let out_dir = std::env::temp_dir().join(format!("tilth-bad-{}", std::process::id()));
        for cmd in ["plan", "run"] {
            let mut c = tilth();
            c.args(["sweep", cmd]).arg(&file);
            if cmd == "run" {
                c.arg("--out").arg(&out_dir);
            }
            let out = c.output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{}: {err}", file.display());
            for want in &expected {
                assert!(
                    err.contains(want),
                    "{}: wanted `{want}` in: {err}",
                    file.display()
                );
            }
        }
        // Refused before any run starts: nothing was written.
        assert!(
            !out_dir.exists(),
            "{}: the run wrote {}",
            file.display(),
            out_dir.display()
        );
        n += 1;
    }
    assert!(n >= 10, "only {n} bad sweep files");
}

fn manifest_rows(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    m["rows"].as_array().unwrap().clone()
}

fn run_sweep(out: &Path) -> Output {
    tilth()
        .args(["sweep", "run", "--cores", "1", "--quiet", "--out"])
        .arg(out)
        .arg(sweeps("tiny.toml"))
        .output()
        .unwrap()
}

/// Starts the tiny sweep on one core and waits until `done` runs are done.
#[expect(
    clippy::zombie_processes,
    reason = "the caller kills the child and waits for it"
)]
fn start_and_wait(out: &Path, done: usize) -> std::process::Child {
    let child = tilth()
        .args(["sweep", "run", "--cores", "1", "--quiet", "--out"])
        .arg(out)
        .arg(sweeps("tiny.toml"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    loop {
        std::thread::sleep(Duration::from_millis(50));
        let n = std::fs::read_to_string(out.join("manifest.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .map(|m| {
                m["rows"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|r| r["status"] == "done")
                    .count()
            })
            .unwrap_or(0);
        // ... and the next run has started writing its MCAP: the kill lands mid-run.
        let next = out.join(format!("runs/{:03}/run.mcap.partial", done + 1));
        if n >= done && next.exists() {
            return child;
        }
        assert!(t0.elapsed() < Duration::from_secs(120), "no progress");
    }
}

#[test]
fn a_sweep_killed_with_sigkill_resumes_without_duplicates_or_losses() {
    let out = std::env::temp_dir().join(format!("tilth-kill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let mut child = start_and_wait(&out, 1);
    child.kill().unwrap();
    child.wait().unwrap();
    let first = std::fs::read(out.join("runs/001/summary.json")).unwrap();
    let rows = manifest_rows(&out);
    assert!(
        rows.iter().any(|r| r["status"] != "done"),
        "finished before the kill"
    );
    let again = run_sweep(&out);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let rows = manifest_rows(&out);
    let ids: Vec<u64> = rows.iter().map(|r| r["id"].as_u64().unwrap()).collect();
    assert_eq!(ids, [1, 2, 3, 4]);
    assert!(rows.iter().all(|r| r["status"] == "done"), "{rows:?}");
    // The completed run was not run again.
    assert_eq!(
        std::fs::read(out.join("runs/001/summary.json")).unwrap(),
        first
    );
    for id in 1..=4 {
        let dir = out.join(format!("runs/{id:03}"));
        assert!(dir.join("run.mcap").exists());
        assert!(
            !dir.join("run.mcap.partial").exists(),
            "run {id} left a partial file"
        );
    }
    let results = csv(&out.join("results.csv"));
    assert_eq!(results.len(), 4);
    assert!(results.iter().all(|r| r["status"] == "done"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn sigterm_stops_cleanly_and_the_same_command_finishes() {
    let out = std::env::temp_dir().join(format!("tilth-term-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let child = start_and_wait(&out, 1);
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-TERM", &pid])
            .status()
            .unwrap()
            .success()
    );
    let status = child.wait_with_output().unwrap().status;
    assert_eq!(status.code(), Some(130));
    let rows = manifest_rows(&out);
    let stopped: Vec<&serde_json::Value> = rows
        .iter()
        .filter(|r| r["status"] == "interrupted")
        .collect();
    assert_eq!(stopped.len(), 1, "{rows:?}");
    // The interrupted run's MCAP was closed properly but keeps its .partial name.
    let partial = out.join(stopped[0]["mcap"].as_str().unwrap());
    assert!(partial.to_string_lossy().ends_with("run.mcap.partial"));
    let bytes = std::fs::read(&partial).unwrap();
    assert_eq!(
        &bytes[bytes.len() - 8..],
        b"\x89MCAP0\r\n",
        "no MCAP footer magic"
    );
    let again = run_sweep(&out);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(manifest_rows(&out).iter().all(|r| r["status"] == "done"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_sweep_logged_to_a_file_writes_one_line_per_finished_run() {
    let out = std::env::temp_dir().join(format!("tilth-log-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    // `output()` pipes stderr: not a terminal, as under nohup or a batch system.
    let logged = tilth()
        .args(["sweep", "run", "--cores", "1", "--out"])
        .arg(&out)
        .arg(sweeps("tiny.toml"))
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&logged.stderr);
    assert!(logged.status.success(), "{log}");
    let lines: Vec<&str> = log.lines().filter(|l| l.contains("] run ")).collect();
    assert_eq!(lines.len(), 4, "{log}");
    for row in manifest_rows(&out) {
        let id = row["id"].as_u64().unwrap();
        let summary: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out.join(format!("runs/{id:03}/summary.json"))).unwrap(),
        )
        .unwrap();
        let run = &summary["run"];
        let friction = run["values"]["friction"].as_f64().unwrap();
        let line = lines
            .iter()
            .find(|l| l.contains(&format!("] run {id} (")))
            .unwrap_or_else(|| panic!("no line for run {id}: {log}"));
        assert!(line.contains(&format!("friction = {friction}")), "{line}");
        assert!(line.contains(&format!("seed {}", run["seed"])), "{line}");
        assert!(line.contains(" done in "), "{line}");
        let secs = summary["wall_seconds"].as_f64().unwrap();
        assert!(line.contains(&format!("in {secs:.0} s")), "{line}");
    }
    // Runs finish in order on one core: the counter climbs 1/4 .. 4/4.
    for (k, line) in lines.iter().enumerate() {
        assert!(line.starts_with(&format!("[{}/4] ", k + 1)), "{line}");
    }
    // `--quiet` keeps the log empty; a finished sweep has nothing left to run.
    let quiet = run_sweep(&out);
    assert!(quiet.status.success());
    assert!(
        !String::from_utf8_lossy(&quiet.stderr).contains("] run "),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn two_thread_runs_take_two_cores_and_give_the_same_results() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let base = std::env::temp_dir().join(format!("tilth-two-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let text = std::fs::read_to_string(sweeps("tiny.toml"))
        .unwrap()
        .replace(
            "scene = \"tiny_scene.toml\"",
            &format!("scene = {:?}\nthreads = 2", sweeps("tiny_scene.toml")),
        );
    let two = base.join("two.toml");
    std::fs::write(&two, text).unwrap();
    // A budget of one core cannot hold a 2-thread run: refused before anything runs.
    let refused = tilth()
        .args(["sweep", "run", "--cores", "1", "--quiet", "--out"])
        .arg(base.join("refused"))
        .arg(&two)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("experiment.threads = 2"));
    if cores < 2 {
        eprintln!("SKIPPED: the rest needs 2 cores");
        return;
    }
    let out2 = base.join("out2");
    let r = tilth()
        .args(["sweep", "run", "--cores", "2", "--quiet", "--out"])
        .arg(&out2)
        .arg(&two)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let out1 = base.join("out1");
    assert!(run_sweep(&out1).status.success());
    for id in 1..=4 {
        let s: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out2.join(format!("runs/{id:03}/summary.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(s["cores"].as_array().unwrap().len(), 2, "run {id}");
        assert_eq!(s["report"]["threads"], 2);
    }
    // Same seeds, 1 or 2 threads: the same bits, so the same observables.
    let (a, b) = (
        csv(&out1.join("results.csv")),
        csv(&out2.join("results.csv")),
    );
    for (x, y) in a.iter().zip(&b) {
        for k in ["heap_cone_angle_deg", "kinetic_energy_j", "particles"] {
            assert_eq!(x[k], y[k], "{k}");
        }
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// `[design] type = "replicates"`: one setting over several seeds, its scatter printed; run
/// again with more replicates, the runs done stay (the same bits) and only the new seeds run.
#[test]
fn one_setting_over_several_seeds_grows_by_the_new_seeds_only() {
    let base = std::env::temp_dir().join(format!("tilth-seeds-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let text = std::fs::read_to_string(sweeps("tiny_seeds.toml")).unwrap();
    let scene = sweeps("tiny_scene.toml");
    let text = text.replace(
        "\"tiny_scene.toml\"",
        &format!("{:?}", scene.display().to_string()),
    );
    let file = base.join("seeds.toml");
    let out = base.join("out");
    let run = |replicates: usize| {
        std::fs::write(
            &file,
            text.replace("replicates = 3", &format!("replicates = {replicates}")),
        )
        .unwrap();
        let o = tilth()
            .args(["sweep", "run", "--cores", "1", "--out"])
            .arg(&out)
            .arg(&file)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (stdout, log) = run(3);
    let first = csv(&out.join("results.csv"));
    assert_eq!(first.len(), 3);
    let seeds: Vec<&str> = first.iter().map(|r| r["seed"].as_str()).collect();
    assert_eq!(seeds, ["21", "22", "23"]);
    // No factor columns: the run's settings are the fixed values.
    assert!(!first[0].contains_key("friction"), "{:?}", first[0]);
    assert_eq!(
        log.lines().filter(|l| l.contains("] run ")).count(),
        3,
        "{log}"
    );
    assert!(log.contains("(seed 21)"), "{log}");
    // The printed scatter is the mean, sd and s.e. of the table's angles.
    let angles: Vec<f64> = first
        .iter()
        .map(|r| r["repose_angle_deg"].parse().unwrap())
        .collect();
    let n = angles.len() as f64;
    let mean = angles.iter().sum::<f64>() / n;
    let sd = (angles.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let line = stdout
        .lines()
        .find(|l| l.starts_with("repose_angle_deg over 3 seeds: "))
        .unwrap_or_else(|| panic!("no scatter line: {stdout}"));
    let field = |name: &str| -> f64 {
        line.split(&format!("{name} "))
            .nth(1)
            .and_then(|s| s.split([',', ' ']).next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no {name} in {line}"))
    };
    assert!((field("mean") - mean).abs() <= 1e-5 * mean.abs(), "{line}");
    assert!((field("sd") - sd).abs() <= 1e-5 * sd.max(1e-9), "{line}");
    assert!(
        (field("s.e.") - sd / n.sqrt()).abs() <= 1e-5 * sd.max(1e-9),
        "{line}"
    );
    // Five replicates later: two new runs (seeds 24 and 25), the first three untouched.
    let (_, log) = run(5);
    assert_eq!(
        log.lines().filter(|l| l.contains("] run ")).count(),
        2,
        "{log}"
    );
    let grown = csv(&out.join("results.csv"));
    assert_eq!(grown.len(), 5);
    assert_eq!(grown[3]["seed"], "24");
    assert_eq!(grown[4]["seed"], "25");
    for (a, b) in first.iter().zip(&grown) {
        assert_eq!(a["repose_angle_deg"], b["repose_angle_deg"]);
        assert_eq!(
            a["wall_seconds"], b["wall_seconds"],
            "run {} ran again",
            a["run"]
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}
