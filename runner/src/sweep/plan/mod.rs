//! A sweep file expanded into runs, each checked against the scene before anything runs.
//!
//! [`load`] reads a sweep file into a plan, [`check`] refuses it before anything runs,
//! [`build`] turns one run into the scene it simulates, [`generated`] makes plans without a
//! sweep file and [`print`] shows a plan.

mod build;
mod check;
mod generated;
mod load;
mod print;

use crate::record::RecordSection;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

pub use load::{DEMO_SCENE, DEMO_SWEEP};
pub use print::{describe, num};

/// A factor as the plan shows it.
#[derive(Debug, Clone, Serialize)]
pub struct Factor {
    pub name: String,
    pub target: String,
    pub label: Option<String>,
    pub unit: Option<String>,
    /// Real value at coded -1 (or the lowest level).
    pub low: f64,
    /// Real value at coded +1 (or the highest level).
    pub high: f64,
}

/// One run of the sweep.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct PlannedRun {
    /// Run number, 1-based, in run order.
    pub id: usize,
    /// Standard-order number, 1-based.
    pub std: usize,
    /// Replicate, 1-based.
    pub replicate: usize,
    /// Factor name -> coded value.
    pub coded: BTreeMap<String, f64>,
    /// Factor name -> real value.
    pub values: BTreeMap<String, f64>,
    pub seed: u64,
}

/// A scene as text, with the name and directory it came from.
#[derive(Debug, Clone)]
pub struct SceneSource {
    pub origin: String,
    pub dir: PathBuf,
    pub text: String,
    /// An experiment file (`experiment = "..."`) rather than a scene.
    pub experiment: bool,
}

/// An expanded, checked sweep.
#[derive(Debug, Clone)]
pub struct Plan {
    pub name: String,
    /// The sweep file (or the embedded demo's name).
    pub origin: String,
    pub sweep_text: String,
    pub description: Option<String>,
    /// The design in words.
    pub title: String,
    pub factors: Vec<Factor>,
    pub runs: Vec<PlannedRun>,
    pub scene: SceneSource,
    /// Scene values set in every run (path, value).
    pub fixed: Vec<(String, toml::Value)>,
    /// Threads per run.
    pub threads: usize,
    pub record: RecordSection,
    /// Fingerprint of the sweep and scene texts: a resumed sweep must match it.
    pub fingerprint: String,
}

/// FNV-1a, 64 bit: a fingerprint that stays the same across builds and platforms.
pub fn fnv1a(parts: &[&str]) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    for p in parts {
        for b in p.bytes().chain([0xff]) {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    }
    format!("{h:016x}")
}

/// The last (most specific) message of an error chain, on one line.
pub fn innermost(e: &anyhow::Error) -> String {
    e.chain()
        .last()
        .map(|c| c.to_string())
        .unwrap_or_default()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}
