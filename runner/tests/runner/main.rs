//! Tests of the `tilth` front end: scene files good and bad, and the binary end to end.

mod cache;
mod calibrate;
mod check;
mod config_files;
mod diagnose;
mod discovery_proof;
mod end_to_end;
mod experiments;
mod external;
mod fit;
mod measurements;
mod rsm;
mod settings;
mod sweeps;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `tilth` binary from the repository root (so that paths like
/// `models/li2022.toml` resolve) and waits for it.
pub fn tilth_in_root(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tilth"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .unwrap()
}

/// `runner/tests/configs/<dir>`.
pub fn configs(dir: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/configs")
        .join(dir)
}

/// The `.toml` files of a config directory, sorted.
pub fn scene_files(dir: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(configs(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}
