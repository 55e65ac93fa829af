//! The virtual lab: bad experiment files are refused before anything runs.

use std::path::Path;
use std::process::Command;

fn tilth() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tilth"))
}

#[test]
fn bad_experiment_files_are_refused_before_the_run() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/experiments/bad");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let file = e.unwrap().path();
        let text = std::fs::read_to_string(&file).unwrap();
        let want: Vec<&str> = text
            .lines()
            .filter_map(|l| l.strip_prefix("# error: "))
            .collect();
        assert!(!want.is_empty(), "{}: no `# error:` line", file.display());
        let out_dir = std::env::temp_dir().join(format!("tilth-badexp-{}", std::process::id()));
        let out = tilth()
            .arg("run")
            .arg(&file)
            .arg("--out")
            .arg(&out_dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {err}", file.display());
        for w in &want {
            assert!(
                err.contains(w),
                "{}: wanted `{w}` in: {err}",
                file.display()
            );
        }
        assert!(
            err.contains(&*file.file_name().unwrap().to_string_lossy()),
            "{err}"
        );
        assert!(
            !out_dir.exists(),
            "{}: wrote {}",
            file.display(),
            out_dir.display()
        );
        n += 1;
    }
    assert!(n >= 8);
}

/// Runs an experiment file in its coarse preset and returns its summary.
fn coarse(name: &str) -> serde_json::Value {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../sweeps/experiments")
        .join(format!("{name}.toml"));
    let out = std::env::temp_dir().join(format!("tilth-coarse-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let r = tilth()
        .args(["run", "--coarse", "--quiet", "--json", "--out"])
        .arg(&out)
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        r.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&r.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(summary["status"], "done");
    // The reducer, run on the file by the binary, agrees with what the run reported.
    let mcap = out.join("runs/001/run.mcap");
    let what = match name {
        "direct_shear" => "shear",
        other => other,
    };
    let red = tilth()
        .args(["reduce", what, "--json"])
        .arg(&mcap)
        .output()
        .unwrap();
    assert!(
        red.status.success(),
        "{}",
        String::from_utf8_lossy(&red.stderr)
    );
    let reduced: serde_json::Value = serde_json::from_slice(&red.stdout).unwrap();
    assert_eq!(reduced["complete"], true);
    let _ = std::fs::remove_dir_all(&out);
    serde_json::json!({ "summary": summary, "reduced": reduced })
}

#[test]
fn repose_coarse_runs_to_rest_and_reduces_to_an_angle() {
    let r = coarse("repose");
    let angle = r["reduced"]["repose_angle_deg"].as_f64().unwrap();
    assert!(angle > 0.0 && angle < 90.0, "{angle}");
    assert_eq!(
        r["summary"]["reduced"]["repose_angle_deg"]
            .as_f64()
            .unwrap(),
        angle
    );
    // Comes to rest: 200 of 200 seeds (1-200) of this coarse test settled, the last at
    // 0.62 s of simulated time against max_time's 8 s. A heap on which a grain rocks for ever
    // (docs/li2022-compare.md, "Grains that never stop") is a possible outcome of a chaotic
    // pour, not a fault of the instrument; the instrument's duty then is to say so.
    let e = &r["summary"]["experiment"];
    let says_why = e["warning"]
        .as_str()
        .is_some_and(|w| w.starts_with("the heap was not at rest at max_time"));
    assert!(e["settled"] == true || says_why, "{}", r["summary"]);
}

/// The bars against what 24 seeds (1-24) of this coarse test gave: the two halves' force
/// gap at most 0.17 % of the peak (bar 2 %), the mean normal stress within 0.034 % of the set
/// load (bar 2 %), the worst block within 1.0 % (bar 5 %; mean 0.44 %, sd 0.2 %), the
/// inertial number at most 5.03e-4 (bar 1e-3). Each bar is 5 or more times the worst seen,
/// so a redrawn trajectory does not flip it.
#[test]
fn direct_shear_coarse_shears_5_mm_under_the_set_pressure() {
    let r = coarse("direct_shear");
    let e = &r["summary"]["experiment"];
    assert_eq!(e["completed"], true);
    // The reducer's peak is the largest recorded shear force; the protocol saw every block.
    let peak = r["reduced"]["peak_shear_force_n"].as_f64().unwrap();
    assert!(peak > 0.0);
    assert!(e["max_inertial_number"].as_f64().unwrap() <= 1e-3);
    // Quasi-static: the force read on the fixed half and the force the moving half pushes
    // with differ only by the soil's change of momentum, small against the peak.
    let gap = e["max_force_gap_n"].as_f64().unwrap();
    assert!(
        gap < 0.02 * peak,
        "the two halves read forces {gap} N apart, against a peak of {peak} N"
    );
    // The platen holds the set load while the specimen contracts under it: on average
    // (a proportional servo alone trailed it by 5 % here, by 10-15 % at 2 mm) and in every
    // block past the first 10 % of the displacement.
    let sigma = r["reduced"]["mean_normal_stress_pa"].as_f64().unwrap();
    assert!(
        (sigma - 1e5).abs() < 0.02 * 1e5,
        "normal stress {sigma} Pa, set 1e5"
    );
    let worst = e["max_normal_deviation"].as_f64().unwrap();
    assert!(
        worst < 0.05,
        "a block's normal force strayed {:.1} % from the set load",
        100.0 * worst
    );
}

#[test]
fn ucs_coarse_compresses_the_free_specimen_to_failure_or_15_percent() {
    let r = coarse("ucs");
    let e = &r["summary"]["experiment"];
    assert_eq!(e["completed"], true);
    let ucs = r["reduced"]["ucs_kpa"].as_f64().unwrap();
    assert!(ucs > 0.0);
    assert!(r["reduced"]["strain_at_failure"].as_f64().unwrap() <= 0.15 + 1e-3);
}

/// The soil-steel friction coefficient of models/li2022.toml at `moisture` % (a point of its
/// interpolation table).
fn soil_steel_friction(moisture: f64) -> f64 {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    let model: toml::Value = toml::from_str(&std::fs::read_to_string(model).unwrap()).unwrap();
    let friction = &model["pairs"]["soil-steel"]["friction"];
    let (x, y) = (
        friction["x"].as_array().unwrap(),
        friction["y"].as_array().unwrap(),
    );
    let k = x
        .iter()
        .position(|v| v.as_float().or(v.as_integer().map(|i| i as f64)) == Some(moisture))
        .unwrap();
    y[k].as_float().unwrap()
}

/// A sample on a plate tilted at omega cannot stay put beyond tan(theta_c) = mu, the
/// soil-steel friction (the model has no soil-steel adhesion): its grains' friction on the
/// plate carries at most mu N. The reading comes later by the time the sample takes to
/// reach the slide speed v once it moves, accelerating from rest at g omega (cos theta_c +
/// mu sin theta_c) t: omega t = sqrt(2 v omega / (g (cos theta_c + mu sin theta_c))). It
/// may slide earlier (its bottom grains turn against their bonds and roll on the plate:
/// docs/experiments.md), so only the upper bound is a law. One seed of a small sample.
#[test]
fn tilt_coarse_cannot_hold_a_sample_beyond_the_soil_steel_friction() {
    let dir = std::env::temp_dir().join(format!("tilth-tilt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    let (rate, speed) = (5.0_f64, 0.005);
    let file = dir.join("tilt.toml");
    std::fs::write(
        &file,
        format!(
            "format_version = 1\nexperiment = \"tilt\"\nmodel = {:?}\ncoarse = true\n\
             [conditions]\nmoisture_pct = 6\nfirmness_mpa = 1.55\n[tilt]\n\
             sample_diameter = 0.032\nsample_height = 0.016\nstart_angle = 30\n\
             tilt_rate = {rate}\nslide_speed = {speed}\n",
            model.display().to_string()
        ),
    )
    .unwrap();
    let r = tilth()
        .args(["run", "--quiet", "--json", "--threads", "1", "--out"])
        .arg(dir.join("out"))
        .arg(&file)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let angle = summary["reduced"]["slide_angle_deg"].as_f64().unwrap();
    let mu = soil_steel_friction(6.0);
    let theta_c = mu.atan();
    let omega = rate.to_radians();
    let lag = (2.0 * speed * omega / (9.81 * (theta_c.cos() + mu * theta_c.sin()))).sqrt();
    assert!(
        angle > 0.0 && angle.to_radians() <= theta_c + lag,
        "slid at {angle:.2} deg; atan(mu = {mu}) = {:.2} deg, lag {:.2} deg",
        theta_c.to_degrees(),
        lag.to_degrees()
    );
    let friction = summary["reduced"]["static_friction"].as_f64().unwrap();
    assert_eq!(friction, angle.to_radians().tan());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_puts_simulated_next_to_measured_with_errors_from_their_definition() {
    let base = std::env::temp_dir().join(format!("tilth-compare-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let data = base.join("m.csv");
    std::fs::write(
        &data,
        "test,moisture_pct,firmness_mpa,normal_pressure_pa,observable,value,unit,uncertainty,replicates,source\n\
         repose,6,,,repose_angle_deg,35.53,deg,,10,table 1\n\
         direct_shear,6,1.55,100000,peak_shear_force_n,197.4,N,,,table 12\n",
    )
    .unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    let out = base.join("out");
    let r = tilth()
        .args(["compare", "--coarse", "--quiet", "--model"])
        .arg(&model)
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("compare.json")).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for row in rows {
        let sim = row["simulated_mean"]
            .as_f64()
            .unwrap_or_else(|| panic!("{row}"));
        let meas = row["value"].as_f64().unwrap();
        let rel = row["relative_error"].as_f64().unwrap();
        assert!((rel - (sim - meas) / meas).abs() < 1e-12);
    }
    assert!(out.join("compare.md").exists() && out.join("compare.csv").exists());
    // A bad row is refused with its file and line before anything runs.
    std::fs::write(&data, "test,observable,value,unit\ntriaxial,q,1,kPa\n").unwrap();
    let r = tilth()
        .args(["compare", "--quiet", "--model"])
        .arg(&model)
        .arg("--data")
        .arg(&data)
        .arg("--out")
        .arg(base.join("bad"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{err}");
    assert!(
        err.contains("m.csv: row 2, column test: test `triaxial` is unknown"),
        "{err}"
    );
    assert!(!base.join("bad").exists());
    let _ = std::fs::remove_dir_all(&base);
}

/// A coarse funnel test of models/li2022.toml at `moisture` % with one `[repose]` line,
/// written to a fresh temporary directory: (the directory, the experiment file).
fn li2022_funnel(
    tag: &str,
    moisture: f64,
    repose: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("tilth-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    let file = dir.join(format!("{tag}.toml"));
    std::fs::write(
        &file,
        format!(
            "format_version = 1\nexperiment = \"repose\"\nmodel = {:?}\ncoarse = true\n[conditions]\nmoisture_pct = {moisture}\n[repose]\n{repose}\n",
            model.display().to_string()
        ),
    )
    .unwrap();
    (dir, file)
}

/// A funnel whose outlet arches over: the run stops with the jam named, instead of reporting
/// the few grains that got through as a heap "at rest". The arch is not a near thing: over
/// 40 seeds (1-40) every run jammed, with 843 to 860 of the 865 grains held above the outlet
/// where the jam check needs a fifth of them.
#[test]
fn a_jammed_funnel_is_an_error_not_a_heap() {
    let (dir, file) = li2022_funnel("jam", 12.0, "funnel_outlet_diameter = 0.0125");
    let out = tilth()
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(dir.join("out"))
        .arg("--quiet")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("the funnel jammed at t = ")
            && err.contains("particles are at rest above the outlet"),
        "{err}"
    );
}

/// A run stopped by `max_time` says why it was not at rest: here the pour is still going, so
/// the soil below the outlet moves on average and more time is the answer.
#[test]
fn a_funnel_stopped_before_rest_says_why() {
    let (dir, file) = li2022_funnel("early", 6.0, "max_time = 0.15");
    let e = &experiment_summary(&file, &dir.join("out"));
    assert_eq!(e["settled"], false, "{e}");
    let warning = e["warning"].as_str().unwrap();
    assert!(
        warning.starts_with(
            "the heap was not at rest at max_time = 0.15 s (mean speed below the outlet "
        ) && warning.ends_with("m/s, rest_speed 0.005); raise repose.max_time"),
        "{warning}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `tilth run --json FILE --out OUT`, which must succeed: the experiment's part of its summary.
fn experiment_summary(file: &Path, out: &Path) -> serde_json::Value {
    let r = tilth()
        .args(["run", "--quiet", "--json", "--out"])
        .arg(out)
        .arg(file)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    summary["experiment"].clone()
}

/// The funnel's skin is a speed setting: a run with the kernel's usual 0.2 diameters and one
/// with the funnel's default list different pairs out of contact, rebuild the list at
/// different steps, and end in the same state to the bit.
#[test]
fn the_funnel_skin_changes_the_rebuilds_not_the_bits() {
    let dir = std::env::temp_dir().join(format!("tilth-skin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/li2022.toml");
    let run = |skin: &str| -> serde_json::Value {
        let file = dir.join(format!("skin{skin}.toml"));
        std::fs::write(
            &file,
            format!(
                "format_version = 1\nexperiment = \"repose\"\nmodel = {:?}\ncoarse = true\n[conditions]\nmoisture_pct = 6\n[simulation]\nseed = 3\n{skin}\n[repose]\nmass_g = 12\n",
                model.display().to_string()
            ),
        )
        .unwrap();
        let out = tilth()
            .args(["run", "--quiet", "--json", "--out"])
            .arg(dir.join(format!("out{}", skin.len())))
            .arg(&file)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let usual = run("skin_fraction = 0.2");
    let funnel = run("");
    let (f, u) = (&funnel["report"], &usual["report"]);
    assert!(
        f["neighbour_rebuilds"].as_u64().unwrap() < u["neighbour_rebuilds"].as_u64().unwrap(),
        "{} {}",
        f["neighbour_rebuilds"],
        u["neighbour_rebuilds"]
    );
    for key in [
        "kinetic_energy",
        "rotational_kinetic_energy",
        "max_speed",
        "steps",
        "contacts",
        "walls",
    ] {
        assert!(!f[key].is_null(), "{key}");
        assert_eq!(f[key], u[key], "{key}");
    }
    assert_eq!(funnel["heap"], usual["heap"]);
    assert_eq!(funnel["reduced"], usual["reduced"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The coarse direct shear test of a remoulded specimen (`bonded = false`) at `pressure` Pa:
/// the experiment's part of its summary.
fn unbonded_shear(pressure: f64) -> serde_json::Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let preset =
        std::fs::read_to_string(root.join("sweeps/experiments/direct_shear.toml")).unwrap();
    let model = root.join("models/li2022.toml").canonicalize().unwrap();
    let text = preset
        .replace(
            "model = \"../../models/li2022.toml\"",
            &format!("model = {:?}", model.display().to_string()),
        )
        .replace(
            "experiment = \"direct_shear\"",
            "experiment = \"direct_shear\"\ncoarse = true",
        )
        .replace(
            "normal_pressure = 1.0e5",
            &format!("normal_pressure = {pressure:e}\nbonded = false\n#"),
        );
    assert!(
        text.contains("bonded = false") && text.contains("coarse = true"),
        "the preset's lines moved"
    );
    let dir =
        std::env::temp_dir().join(format!("tilth-unbonded-{pressure}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("shear.toml");
    std::fs::write(&file, text).unwrap();
    let e = experiment_summary(&file, &dir.join("out"));
    let _ = std::fs::remove_dir_all(&dir);
    e
}

/// Without bonds the specimen's strength is its contacts' friction: no bond forms, and the
/// shear force at a four times higher normal pressure is higher. (Coulomb: tau = c + sigma
/// tan phi with tan phi > 0; at 25 and 100 kPa with the soil's sliding friction of 0.8 the
/// two differ by tens of newtons, where seeds move a coarse reading by a few.)
#[test]
fn an_unbonded_shear_specimen_is_held_by_friction_alone() {
    let low = unbonded_shear(2.5e4);
    let high = unbonded_shear(1.0e5);
    for e in [&low, &high] {
        assert_eq!(e["bonds_formed"], 0, "{e}");
        assert_eq!(e["completed"], true, "{e}");
    }
    let force = |e: &serde_json::Value| e["peak_shear_force_n"].as_f64().unwrap();
    assert!(
        force(&high) > force(&low) && force(&low) > 0.0,
        "peak shear force {} N at 25 kPa, {} N at 100 kPa",
        force(&low),
        force(&high)
    );
}
