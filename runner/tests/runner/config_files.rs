//! Good scene files load; each bad one fails with the error its first line announces
//! (`# error: <text>`), and the message names the file.

use super::{configs, scene_files};
use tilth::config;

#[test]
fn good_files_load() {
    let files = scene_files("good");
    assert!(files.len() >= 3);
    for f in files {
        if let Err(e) = config::load(&f, None) {
            panic!("{} should load: {e:#}", f.display());
        }
    }
}

#[test]
fn bad_files_fail_with_their_error() {
    let mut failures = vec![];
    for f in scene_files("bad") {
        let text = std::fs::read_to_string(&f).unwrap();
        let expected = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# error: "))
            .unwrap_or_else(|| panic!("{} must start with `# error: <text>`", f.display()))
            .trim();
        let name = f.file_name().unwrap().to_str().unwrap();
        match config::load(&f, None) {
            Ok(_) => failures.push(format!("{name}: loaded, expected `{expected}`")),
            Err(e) => {
                let msg = format!("{e:#}");
                if !msg.contains(expected) || !msg.contains(name) {
                    failures.push(format!(
                        "{name}: expected `{expected}` and the file name in:\n{msg}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

#[test]
fn the_required_bad_cases_exist() {
    for case in [
        "unknown_top_level_key",
        "unknown_key_in_wall",
        "restitution_out_of_range",
        "negative_wall_radius",
        "zero_youngs_modulus",
        "negative_friction",
        "unknown_law",
        "unknown_law_parameter",
        "overlapping_particles",
        "unknown_material",
        "missing_format_version",
        "duration_and_steps",
    ] {
        let f = configs("bad").join(format!("{case}.toml"));
        assert!(f.exists(), "{} is missing", f.display());
    }
}

#[test]
fn the_demo_loads_embedded_and_from_disk() {
    let embedded = config::load_or_demo(None, None).unwrap();
    assert_eq!(embedded.info.origin, config::DEMO_NAME);
    assert_eq!(embedded.steps, 60_000);
    assert_eq!(embedded.sim.factories[0].spec.count, 1500);
    let on_disk = concat!(env!("CARGO_MANIFEST_DIR"), "/../sweeps/scenes/pile.toml");
    assert_eq!(std::fs::read_to_string(on_disk).unwrap(), config::DEMO);
}

#[test]
fn threads_override_and_defaults() {
    let f = configs("good").join("minimal_jkr.toml");
    let loaded = config::load(&f, Some(2)).unwrap();
    assert_eq!(loaded.threads, 2);
    let loaded = config::load(&f, None).unwrap();
    assert_eq!(loaded.threads, 1);
    assert_eq!(loaded.steps, 10);
    assert_eq!(loaded.info.laws, ["jkr", "restitution", "mindlin", "epsd"]);
}
