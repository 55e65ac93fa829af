//! `--cache DIR`: runs are keyed by the model file's content, the test, the conditions and
//! the seeds, so a second command with a copy of the model at another path reuses them,
//! and a changed model gets runs of its own.

use std::path::{Path, PathBuf};

use crate::tilth_in_root as tilth;

const DATA: &str = "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source
repose,6,,,heap_cone_angle_deg,41.0,deg,0.8,4,made up for the test
repose,6,,,tray_mass_g,20.0,g,0.5,4,made up for the test
";

fn run_dirs(cache: &Path) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("repose-")
        })
        .collect();
    dirs.sort();
    dirs
}

fn mtimes(dir: &Path) -> Vec<std::time::SystemTime> {
    let mut out = vec![];
    for e in std::fs::read_dir(dir.join("runs")).unwrap() {
        let summary = e.unwrap().path().join("summary.json");
        out.push(std::fs::metadata(summary).unwrap().modified().unwrap());
    }
    out.sort();
    out
}

#[test]
fn a_cache_is_shared_by_commands_and_keyed_by_the_models_content() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cache-shared");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("data.csv");
    std::fs::write(&data, DATA).unwrap();
    let cache = dir.join("cache");
    let model = std::fs::read_to_string("../models/li2022.toml").unwrap();
    let copy = dir.join("copy.toml");
    std::fs::write(&copy, &model).unwrap();
    let common = |model: &Path, out: &str| -> Vec<String> {
        [
            "--model",
            model.to_str().unwrap(),
            "--data",
            data.to_str().unwrap(),
            "--out",
            dir.join(out).to_str().unwrap(),
            "--replicates",
            "2",
            "--cache",
            cache.to_str().unwrap(),
            "--coarse",
            "--quiet",
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |args: Vec<String>| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = tilth(&args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let mut first = vec!["compare".to_string()];
    first.extend(common(Path::new("models/li2022.toml"), "compare"));
    run(first);
    let dirs = run_dirs(&cache);
    assert_eq!(dirs.len(), 1, "one sweep for one test: {dirs:?}");
    let before = mtimes(&dirs[0]);
    assert_eq!(before.len(), 2, "one condition x 2 replicates");

    // The same model at another path (as `diagnose` writes its `base` variant): nothing is
    // run again.
    let mut again = vec!["compare".to_string()];
    again.extend(common(&copy, "compare-copy"));
    run(again);
    assert_eq!(run_dirs(&cache), dirs);
    assert_eq!(mtimes(&dirs[0]), before, "the runs were redone");
    let a = std::fs::read_to_string(dir.join("compare/compare.csv")).unwrap();
    let b = std::fs::read_to_string(dir.join("compare-copy/compare.csv")).unwrap();
    assert_eq!(a, b);

    // The same values under other comments (as `tilth fit` writes its fitted model, with a
    // header): the same model, nothing run again.
    let relaid = format!("# fitted, say\n{model}").replacen(
        "restitution = 0.45",
        "restitution = 0.45 # the same number",
        1,
    );
    assert_ne!(relaid, model);
    std::fs::write(&copy, &relaid).unwrap();
    let mut relaid_run = vec!["compare".to_string()];
    relaid_run.extend(common(&copy, "compare-relaid"));
    run(relaid_run);
    assert_eq!(run_dirs(&cache), dirs, "comments made another model");
    assert_eq!(mtimes(&dirs[0]), before, "the runs were redone");

    // Another model (one number changed): runs of its own, the first ones untouched.
    let changed = model.replace("restitution = 0.45", "restitution = 0.5");
    assert_ne!(changed, model);
    std::fs::write(&copy, changed).unwrap();
    let mut other = vec!["compare".to_string()];
    other.extend(common(&copy, "compare-changed"));
    run(other);
    assert_eq!(run_dirs(&cache).len(), 2);
    assert_eq!(mtimes(&dirs[0]), before);
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn simulated(compare_json: &Path) -> Vec<f64> {
    read_json(compare_json)["rows"][0]["simulated"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Asking for more replicates in a directory that holds fewer runs only the new seeds: the
/// finished runs stay (summary files untouched, the same values first in `compare.json`),
/// in an output directory and in a cache alike.
#[test]
fn more_replicates_later_run_only_the_new_seeds() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cache-more-replicates");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let data = dir.join("data.csv");
    std::fs::write(&data, DATA).unwrap();
    let cache = dir.join("cache");
    // `tilth compare` on the test's data into `out`, with `extra` arguments.
    let run_compare = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "compare",
            "--model",
            "models/li2022.toml",
            "--data",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ];
        args.extend(extra);
        tilth(&args)
    };
    let compare = |replicates: &str, cached: bool| {
        let out = dir.join(if cached { "cached" } else { "plain" });
        let mut extra = vec!["--replicates", replicates, "--coarse"];
        if cached {
            extra.extend(["--cache", cache.to_str().unwrap()]);
        }
        let o = run_compare(&out, &extra);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        simulated(&out.join("compare.json"))
    };
    let summaries = |runs: &Path| -> Vec<(PathBuf, std::time::SystemTime)> {
        let mut v: Vec<_> = std::fs::read_dir(runs)
            .unwrap()
            .map(|e| e.unwrap().path().join("summary.json"))
            .map(|p| {
                let t = std::fs::metadata(&p).unwrap().modified().unwrap();
                (p, t)
            })
            .collect();
        v.sort();
        v
    };

    let one = compare("1", false);
    let runs = dir.join("plain/repose/runs");
    let before = summaries(&runs);
    assert_eq!((one.len(), before.len()), (1, 1));
    let three = compare("3", false);
    let after = summaries(&runs);
    assert_eq!(three.len(), 3, "{three:?}");
    assert_eq!(three[0].to_bits(), one[0].to_bits(), "seed 1 changed");
    assert_eq!(after.len(), 3);
    assert_eq!(after[0], before[0], "the finished run was redone");
    assert!(
        three[1] != three[0] || three[2] != three[0],
        "new seeds gave the same heap: {three:?}"
    );

    let cached_one = compare("1", true);
    assert_eq!(cached_one[0].to_bits(), one[0].to_bits());
    let dirs = run_dirs(&cache);
    assert_eq!(dirs.len(), 1, "{dirs:?}");
    let before = summaries(&dirs[0].join("runs"));
    let cached_two = compare("2", true);
    assert_eq!(
        run_dirs(&cache),
        dirs,
        "more replicates made another cache entry"
    );
    let after = summaries(&dirs[0].join("runs"));
    assert_eq!(after.len(), 2);
    assert_eq!(after[0], before[0], "the cached run was redone");
    assert_eq!(
        cached_two[..],
        three[..2],
        "the cache and the plain directory disagree"
    );
    // A validation's own seeds: --first-seed 2 with one replicate is the same run as the
    // second of three from seed 1, and its compare.json says which seeds it took.
    let out = dir.join("from-2");
    let o = run_compare(&out, &["--first-seed", "2", "--coarse"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        simulated(&out.join("compare.json"))[0].to_bits(),
        three[1].to_bits()
    );
    assert_eq!(read_json(&out.join("compare.json"))["first_seed"], 2);
    let refused = dir.join("from-0");
    let o = run_compare(&refused, &["--first-seed", "0"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("--first-seed 0 is out of range"),
        "{err}"
    );
    assert!(
        !refused.exists(),
        "a refused command wrote its output directory"
    );
}
