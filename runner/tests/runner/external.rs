//! Tests that use real outside software: the official Python MCAP reader with Foxglove's
//! protobuf schemas, Rerun's MCAP importer, and a Slurm cluster. `.ci/run` installs them
//! and sets TILTH_REQUIRE_PYTHON=1 and TILTH_REQUIRE_SLURM=1, which turn a missing tool
//! into a failure; elsewhere the tests say what is missing and return.

use std::path::{Path, PathBuf};
use std::process::Command;

fn tilth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tilth"))
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
}

/// The Python with tools/python/requirements.txt installed (TILTH_PYTHON, default python3),
/// or `None` (after saying why) when it is not there and not required.
fn python() -> Option<String> {
    let py = std::env::var("TILTH_PYTHON").unwrap_or_else(|_| "python3".into());
    let probe = Command::new(&py)
        .args([
            "-c",
            "import mcap, mcap_protobuf, foxglove_schemas_protobuf, rerun",
        ])
        .output();
    let ok = probe.as_ref().is_ok_and(|o| o.status.success());
    if ok {
        return Some(py);
    }
    let why = match probe {
        Ok(o) => String::from_utf8_lossy(&o.stderr).into_owned(),
        Err(e) => e.to_string(),
    };
    if std::env::var("TILTH_REQUIRE_PYTHON").is_ok_and(|v| v == "1") {
        panic!("{py} lacks tools/python/requirements.txt: {why}");
    }
    eprintln!("SKIPPED: {py} lacks tools/python/requirements.txt ({why}); .ci/run installs it");
    None
}

/// The `rerun` CLI beside the Python interpreter, or on PATH.
fn rerun(py: &str) -> String {
    let out = Command::new(py)
        .args([
            "-c",
            "import sys, os; print(os.path.dirname(sys.executable))",
        ])
        .output()
        .unwrap();
    let dir = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let beside = Path::new(&dir).join("rerun");
    if beside.exists() {
        beside.display().to_string()
    } else {
        "rerun".into()
    }
}

fn script(name: &str) -> PathBuf {
    repo("tools/python").join(name)
}

fn run_ok(c: &mut Command) -> String {
    let out = c.output().unwrap_or_else(|e| panic!("{c:?}: {e}"));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{c:?} failed:\n{text}");
    text
}

/// Runs one run of the tiny test sweep and returns its MCAP file.
fn one_run(tag: &str) -> (PathBuf, PathBuf) {
    let out = std::env::temp_dir().join(format!("tilth-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let sweep = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweeps/tiny.toml");
    run_ok(
        tilth()
            .args(["sweep", "run", "--quiet", "--shard", "0/4", "--out"])
            .arg(&out)
            .arg(&sweep),
    );
    let mcap = out.join("runs/001/run.mcap");
    assert!(mcap.exists());
    (out, mcap)
}

#[test]
fn mcap_reads_with_the_official_reader_and_decodes_with_foxglove_schemas() {
    let Some(py) = python() else { return };
    let (out, mcap) = one_run("py");
    let report = run_ok(Command::new(&py).arg(script("check_mcap.py")).arg(&mcap));
    assert!(report.contains("foxglove.PointCloud"), "{report}");
    // A file cut in the middle is refused as incomplete, or read up to the cut on request.
    let cut = out.join("cut.mcap");
    let bytes = std::fs::read(&mcap).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let refused = Command::new(&py)
        .arg(script("check_mcap.py"))
        .arg(&cut)
        .output()
        .unwrap();
    assert!(!refused.status.success());
    let text = String::from_utf8_lossy(&refused.stdout).to_string()
        + &String::from_utf8_lossy(&refused.stderr);
    assert!(text.contains("incomplete"), "{text}");
    run_ok(
        Command::new(&py)
            .arg(script("check_mcap.py"))
            .arg("--allow-partial")
            .arg(&cut),
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn rerun_converts_the_mcap_and_shows_the_particles() {
    let Some(py) = python() else { return };
    let (out, mcap) = one_run("rerun");
    // Rerun's own MCAP importer.
    let rrd = out.join("imported.rrd");
    run_ok(
        Command::new(rerun(&py))
            .args(["mcap", "convert"])
            .arg(&mcap)
            .arg("-o")
            .arg(&rrd),
    );
    let found = run_ok(
        Command::new(&py)
            .arg(script("check_rrd.py"))
            .arg(&rrd)
            .args(["--entity", "/particles"]),
    );
    assert!(found.contains("Points3D:positions"), "{found}");
    // Our converter keeps what the importer drops: radii and scalar plots.
    let rrd2 = out.join("converted.rrd");
    run_ok(
        Command::new(&py)
            .arg(script("mcap_to_rrd.py"))
            .arg(&mcap)
            .arg(&rrd2),
    );
    run_ok(
        Command::new(&py)
            .arg(script("check_rrd.py"))
            .arg(&rrd2)
            .args([
                "--entity",
                "/particles",
                "--component",
                "/particles=Points3D:radii",
            ])
            .args(["--entity", "/scalars/kinetic_energy"]),
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Whether a Slurm cluster answers (or `None` after saying why).
fn slurm() -> Option<()> {
    let up = Command::new("sinfo")
        .args(["-h", "-o", "%T"])
        .output()
        .is_ok_and(|o| o.status.success() && !o.stdout.is_empty());
    if up {
        return Some(());
    }
    if std::env::var("TILTH_REQUIRE_SLURM").is_ok_and(|v| v == "1") {
        panic!("no Slurm cluster answers `sinfo`; run .ci/slurm-up.sh");
    }
    eprintln!("SKIPPED: no Slurm cluster (sinfo); .ci/run starts one with .ci/slurm-up.sh");
    None
}

#[test]
fn a_slurm_job_array_runs_the_sweep_and_status_merges_the_shards() {
    let Some(()) = slurm() else { return };
    let base = std::env::temp_dir().join(format!("tilth-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let out = base.join("out");
    let job = base.join("job.sh");
    let sweep = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/sweeps/tiny.toml");
    run_ok(
        tilth()
            .args(["sweep", "slurm", "--tasks", "2", "--time", "10:00", "--out"])
            .arg(&out)
            .arg("--write")
            .arg(&job)
            .arg(&sweep),
    );
    run_ok(Command::new("sbatch").arg("--wait").arg(&job));
    for shard in ["manifest.shard-0-of-2.json", "manifest.shard-1-of-2.json"] {
        assert!(out.join(shard).exists(), "{shard} missing");
    }
    let status = run_ok(tilth().args(["sweep", "status", "--json"]).arg(&out));
    let merged: serde_json::Value = serde_json::from_str(&status).unwrap();
    let rows = merged["rows"].as_array().unwrap();
    let ids: Vec<u64> = rows.iter().map(|r| r["id"].as_u64().unwrap()).collect();
    assert_eq!(ids, [1, 2, 3, 4]);
    assert!(rows.iter().all(|r| r["status"] == "done"), "{rows:?}");
    for r in rows {
        let mcap = out.join(r["mcap"].as_str().unwrap());
        assert!(mcap.exists(), "{}", mcap.display());
        if let Some(py) = python() {
            run_ok(Command::new(&py).arg(script("check_mcap.py")).arg(&mcap));
        }
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// A fresh temporary directory for test `name`, holding `data.csv` with these funnel rows
/// under the measurement header.
fn funnel_data(name: &str, rows: &str) -> (PathBuf, PathBuf) {
    let base = std::env::temp_dir().join(format!("tilth-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let data = base.join("data.csv");
    let header = "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source\n";
    std::fs::write(&data, format!("{header}{rows}")).unwrap();
    (base, data)
}

/// Runs lab command `args` (coarse, quiet, `models/li2022.toml`) on `data` into `out`, with
/// `extra` options, and returns its JSON output `file`.
fn lab_json(
    args: &[&str],
    data: &Path,
    out: &Path,
    extra: &[&str],
    file: &str,
) -> serde_json::Value {
    run_ok(
        tilth()
            .args(args)
            .args(["--coarse", "--quiet", "--model"])
            .arg(repo("models/li2022.toml"))
            .arg("--data")
            .arg(data)
            .arg("--out")
            .arg(out)
            .args(extra),
    );
    serde_json::from_str(&std::fs::read_to_string(out.join(file)).unwrap()).unwrap()
}

/// `compare --slurm` of two funnel conditions, 2 replicates each, as a job array of two
/// tasks: the same simulated values, bit for bit, as the same compare on this machine, and
/// the runs really made by the array's tasks (their shard manifests and logs).
#[test]
fn a_lab_command_runs_on_slurm_with_the_numbers_of_a_local_run() {
    let Some(()) = slurm() else { return };
    let (base, data) = funnel_data(
        "slurm-lab",
        "repose,6,,,heap_cone_angle_deg,38,deg,1,1,test\n\
         repose,9,,,heap_cone_angle_deg,40,deg,1,1,test\n",
    );
    let compare = |out: &Path, slurm: &[&str]| {
        let json = lab_json(
            &["compare", "--replicates", "2"],
            &data,
            out,
            slurm,
            "compare.json",
        );
        json["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["simulated"].clone())
            .collect::<Vec<_>>()
    };
    let on_slurm = base.join("slurm");
    let remote = compare(
        &on_slurm,
        &["--slurm", "--slurm-tasks", "2", "--slurm-time", "10:00"],
    );
    let local = compare(&base.join("local"), &[]);
    assert_eq!(remote, local);
    assert!(
        remote.iter().all(|v| v.as_array().unwrap().len() == 2),
        "{remote:?}"
    );
    for shard in ["manifest.shard-0-of-2.json", "manifest.shard-1-of-2.json"] {
        assert!(
            on_slurm.join("repose").join(shard).exists(),
            "{shard} missing"
        );
    }
    let logs = std::fs::read_dir(on_slurm.join("repose/slurm"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "out")
        })
        .count();
    assert_eq!(logs, 2, "one log per array task");
    let _ = std::fs::remove_dir_all(&base);
}

/// `diagnose --slurm` puts all its variants (the model, its second seeds, the free
/// parameter moved, each candidate on) into one job array, and finds what it finds on this
/// machine: the same candidates with the same statistics, bit for bit.
#[test]
fn diagnose_on_slurm_runs_its_variants_as_one_array_with_the_local_numbers() {
    let Some(()) = slurm() else { return };
    let (base, data) = funnel_data(
        "slurm-diag",
        "repose,9,,,heap_cone_angle_deg,40,deg,1,1,test\n\
         repose,9,,,tray_mass_g,14,g,0.5,1,test\n",
    );
    let diagnose = |out: &Path, slurm: &[&str]| {
        let args = [
            "diagnose",
            "--replicates",
            "2",
            "--param",
            "soil-soil.rolling_friction=0.05:0.45",
            "--no-refit",
        ];
        lab_json(&args, &data, out, slurm, "diagnosis.json")["candidates"].clone()
    };
    let on_slurm = base.join("slurm");
    let remote = diagnose(&on_slurm, &["--slurm", "--slurm-time", "10:00"]);
    let local = diagnose(&base.join("local"), &[]);
    assert_eq!(remote, local);
    // The model, its finite-difference seeds, the parameter moved and each candidate: all
    // in the array of the first variant's directory.
    let variants = 3 + remote.as_array().unwrap().len();
    let script = std::fs::read_to_string(on_slurm.join("runs/base/repose/slurm/job.sh")).unwrap();
    assert!(
        script.contains(&format!("runs of {variants} plan(s)")),
        "{script}"
    );
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn bonds_are_recorded_and_decode_with_foxglove_schemas() {
    let Some(py) = python() else { return };
    let out = std::env::temp_dir().join(format!("tilth-bonds-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    run_ok(
        tilth()
            .args(["run", "--coarse", "--quiet", "--out"])
            .arg(&out)
            .arg(repo("sweeps/experiments/direct_shear.toml")),
    );
    let mcap = out.join("runs/001/run.mcap");
    let report = run_ok(Command::new(&py).arg(script("check_mcap.py")).arg(&mcap));
    for topic in [
        "/bonds ",
        "/bonds/lines",
        "/scalars/bonds_intact",
        "/scalars/shear_force",
    ] {
        assert!(report.contains(topic), "{topic} missing:\n{report}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
