//! The manifest: one row per run (id, factor values, seed, status, MCAP path, wall time,
//! error), written atomically after every change. A sharded sweep writes one manifest per
//! shard (`manifest.shard-I-of-N.json`); `tilth sweep status` merges them with what the run
//! directories hold.

use super::job::{RunSummary, Status, read_summary, run_dir, write_atomic};
use super::plan::{Plan, PlannedRun};
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One row of the manifest.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row {
    pub id: usize,
    pub values: BTreeMap<String, f64>,
    pub seed: u64,
    pub status: Status,
    /// Relative to the sweep's output directory.
    pub mcap: Option<String>,
    pub wall_seconds: Option<f64>,
    pub error: Option<String>,
}

/// What `manifest*.json` holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    pub sweep: String,
    pub fingerprint: String,
    /// `I/N` for a shard, `null` for the whole sweep.
    pub shard: Option<String>,
    pub rows: Vec<Row>,
}

/// `manifest.json` or `manifest.shard-I-of-N.json`.
pub fn path(out: &Path, shard: Option<(usize, usize)>) -> PathBuf {
    match shard {
        None => out.join("manifest.json"),
        Some((i, n)) => out.join(format!("manifest.shard-{i}-of-{n}.json")),
    }
}

impl Row {
    /// A row from the run's directory: done or failed from its summary, interrupted when a
    /// partial MCAP is left, pending otherwise.
    pub fn observe(out: &Path, run: &PlannedRun, fingerprint: &str) -> Row {
        let dir = run_dir(out, run.id);
        let rel = |name: &str| format!("runs/{:03}/{name}", run.id);
        let mut row = Row {
            id: run.id,
            values: run.values.clone(),
            seed: run.seed,
            status: Status::Pending,
            mcap: None,
            wall_seconds: None,
            error: None,
        };
        // The run's own seed and values too: a sweep whose identity leaves out its number of
        // replicates (`tilth compare`) must not take another run's summary for this one.
        let ours = |s: &RunSummary| {
            s.fingerprint == fingerprint && s.run.seed == run.seed && s.run.values == run.values
        };
        match read_summary(&dir).filter(ours) {
            Some(s) if s.status == Status::Done && dir.join("run.mcap").exists() => {
                row.status = Status::Done;
                row.mcap = Some(rel("run.mcap"));
                row.wall_seconds = Some(s.wall_seconds);
            }
            Some(s) if s.status == Status::Failed => {
                row.status = Status::Failed;
                row.mcap = s.mcap.map(|m| rel(&m));
                row.wall_seconds = Some(s.wall_seconds);
                row.error = s.error;
            }
            _ if dir.join("run.mcap.partial").exists() => {
                row.status = Status::Interrupted;
                row.mcap = Some(rel("run.mcap.partial"));
            }
            _ => {}
        }
        row
    }

    /// The row of a summary just produced.
    pub fn from_summary(s: &RunSummary) -> Row {
        Row {
            id: s.run.id,
            values: s.run.values.clone(),
            seed: s.run.seed,
            status: s.status,
            mcap: s.mcap.as_ref().map(|m| format!("runs/{:03}/{m}", s.run.id)),
            wall_seconds: Some(s.wall_seconds),
            error: s.error.clone(),
        }
    }
}

impl Manifest {
    pub fn write(&self, out: &Path, shard: Option<(usize, usize)>) -> Result<()> {
        write_atomic(&path(out, shard), &serde_json::to_vec_pretty(self)?)
    }
}

/// `DIR/sweep.json`: which sweep the directory holds. A second sweep into the same
/// directory is refused instead of mixing results.
#[derive(Debug, Serialize, Deserialize)]
pub struct Stamp {
    pub sweep: String,
    pub origin: String,
    pub fingerprint: String,
    pub runs: usize,
}

/// Claims `out` for `plan` (or checks that it already holds it) and keeps copies of the
/// sweep and scene files there.
pub fn claim(out: &Path, plan: &Plan) -> Result<()> {
    std::fs::create_dir_all(out.join("runs"))
        .with_context(|| format!("{}: cannot create", out.display()))?;
    let stamp_path = out.join("sweep.json");
    if let Ok(text) = std::fs::read_to_string(&stamp_path) {
        let stamp: Stamp = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a tilth sweep stamp", stamp_path.display()))?;
        if stamp.fingerprint != plan.fingerprint {
            bail!(
                "{} holds the sweep `{}` from {} with other inputs (fingerprint {} here, {} now); \
                 use another --out, or delete the directory to start over",
                out.display(),
                stamp.sweep,
                stamp.origin,
                stamp.fingerprint,
                plan.fingerprint
            );
        }
        if stamp.runs != plan.runs.len() {
            // The same sweep with more (or fewer) replicates: the runs done stay.
            let grown = Stamp {
                runs: plan.runs.len(),
                ..stamp
            };
            write_atomic(&stamp_path, &serde_json::to_vec_pretty(&grown)?)?;
        }
        return Ok(());
    }
    write_atomic(&out.join("sweep.toml"), plan.sweep_text.as_bytes())?;
    write_atomic(&out.join("scene.toml"), plan.scene.text.as_bytes())?;
    let stamp = Stamp {
        sweep: plan.name.clone(),
        origin: plan.origin.clone(),
        fingerprint: plan.fingerprint.clone(),
        runs: plan.runs.len(),
    };
    write_atomic(&stamp_path, &serde_json::to_vec_pretty(&stamp)?)
}

/// Merges the manifests of all shards, refreshing each row from its run directory (a
/// shard's manifest may be older than its runs' summaries).
pub fn merge(out: &Path, manifests: Vec<Manifest>) -> Result<Manifest> {
    let first = manifests[0].clone();
    let mut rows: BTreeMap<usize, Row> = BTreeMap::new();
    for m in manifests {
        if m.fingerprint != first.fingerprint {
            bail!(
                "{}: manifests of different sweeps ({} and {})",
                out.display(),
                first.fingerprint,
                m.fingerprint
            );
        }
        for row in m.rows {
            rows.insert(row.id, row);
        }
    }
    for row in rows.values_mut() {
        let run = PlannedRun {
            id: row.id,
            std: 0,
            replicate: 0,
            coded: BTreeMap::new(),
            values: row.values.clone(),
            seed: row.seed,
        };
        let seen = Row::observe(out, &run, &first.fingerprint);
        // A summary is final; a partial file means interrupted unless a shard still runs it.
        let fin = matches!(seen.status, Status::Done | Status::Failed);
        let stopped = seen.status == Status::Interrupted && row.status != Status::Running;
        if fin || stopped {
            *row = seen;
        }
    }
    Ok(Manifest {
        sweep: first.sweep,
        fingerprint: first.fingerprint,
        shard: None,
        rows: rows.into_values().collect(),
    })
}

/// Every `manifest*.json` in the sweep directory `dir` (one per shard) merged into one.
pub fn read_all(dir: &Path) -> Result<Manifest> {
    let mut manifests = vec![];
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot read", dir.display()))?;
    for e in entries {
        let p = e?.path();
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with("manifest") && name.ends_with(".json") {
            let text = std::fs::read_to_string(&p)?;
            let m: Manifest = serde_json::from_str(&text)
                .with_context(|| format!("{}: not a tilth manifest", p.display()))?;
            manifests.push(m);
        }
    }
    if manifests.is_empty() {
        bail!(
            "{}: no manifest*.json; is it a sweep's output directory?",
            dir.display()
        );
    }
    merge(dir, manifests)
}
