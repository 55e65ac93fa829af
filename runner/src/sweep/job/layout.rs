//! What a run's recording says about itself: the walls, the units of its scalar channels,
//! and metadata naming the sweep, the run and the experiment whose reducer reads it.

use crate::config::Prepared;
use crate::lab::observe::Tray;
use crate::lab::protocol::Protocol;
use crate::record::writer::RunLayout;
use crate::sweep::plan::{Plan, PlannedRun};
use std::collections::BTreeMap;

/// The recording's layout (walls, metadata, units, what to record), and the experiment type
/// whose reducer reads the finished recording, if any.
pub(super) fn run_layout(
    plan: &Plan,
    run: &PlannedRun,
    prepared: &Prepared,
    protocol: &dyn Protocol,
    wall_names: Vec<String>,
    tray: Option<Tray>,
) -> (RunLayout, Option<String>) {
    let mut units = units();
    units.extend(protocol.units());
    let mut metadata = metadata(plan, run);
    let experiment = experiment_metadata(protocol, tray);
    let kind = experiment.get("type").cloned();
    if !experiment.is_empty() {
        metadata.insert("tilth.experiment".into(), experiment);
    }
    let layout = RunLayout {
        wall_names,
        wall_shapes: prepared.wall_shapes.clone(),
        metadata,
        units,
        spheres: plan.record.spheres,
        flush_frames: plan.record.flush_frames,
    };
    (layout, kind)
}

/// The `tilth.experiment` metadata: the protocol's own, or for a plain scene with a tray
/// what the repose reducer needs to measure its heap.
fn experiment_metadata(protocol: &dyn Protocol, tray: Option<Tray>) -> BTreeMap<String, String> {
    let experiment = protocol.metadata();
    match tray {
        Some(t) if experiment.is_empty() => [
            ("type", "repose".to_string()),
            ("tray_radius_m", t.radius.to_string()),
            ("tray_top_z_m", t.centre[2].to_string()),
            ("tray_centre_x_m", t.centre[0].to_string()),
            ("tray_centre_y_m", t.centre[1].to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
        _ => experiment,
    }
}

/// MCAP metadata records: what the run is and what made it.
fn metadata(plan: &Plan, run: &PlannedRun) -> BTreeMap<String, BTreeMap<String, String>> {
    let mut r = BTreeMap::new();
    r.insert("sweep".into(), plan.origin.clone());
    r.insert("sweep_name".into(), plan.name.clone());
    r.insert("design".into(), plan.title.clone());
    r.insert("scene".into(), plan.scene.origin.clone());
    r.insert("run_id".into(), run.id.to_string());
    r.insert("std_order".into(), run.std.to_string());
    r.insert("replicate".into(), run.replicate.to_string());
    r.insert("seed".into(), run.seed.to_string());
    r.insert("fingerprint".into(), plan.fingerprint.clone());
    r.insert("tilth_version".into(), env!("CARGO_PKG_VERSION").into());
    r.insert("git_commit".into(), crate::provenance::GIT_COMMIT.into());
    for (k, v) in &run.values {
        r.insert(format!("factor.{k}"), v.to_string());
    }
    for (k, v) in &run.coded {
        r.insert(format!("coded.{k}"), v.to_string());
    }
    let mut channels = BTreeMap::new();
    channels.insert(
        "/particles".into(),
        "foxglove.PointCloud in frame world: x, y, z, radius (m), speed (m/s), id, material".into(),
    );
    channels.insert(
        "/walls".into(),
        "foxglove.SceneUpdate: one entity per wall, moved by its motion".into(),
    );
    channels.insert(
        "/walls/<name>/force".into(),
        "foxglove.Vector3: force of the particles on the wall, N".into(),
    );
    channels.insert(
        "/walls/<name>/torque".into(),
        "foxglove.Vector3: torque about the wall's reference point, N m".into(),
    );
    channels.insert(
        "/scalars/<name>".into(),
        "foxglove.Vector3 with the value in x (Foxglove's schemas have no scalar type)".into(),
    );
    for (k, u) in units() {
        channels.insert(format!("/scalars/{k}"), u);
    }
    let mut m = BTreeMap::new();
    m.insert("tilth.run".to_string(), r);
    m.insert("tilth.channels".to_string(), channels);
    m
}

/// Units of the scalar channels.
fn units() -> BTreeMap<String, String> {
    [
        ("kinetic_energy", "J"),
        ("particles", "count"),
        ("contacts", "count"),
        ("heap_cone_angle_deg", "degree"),
        ("heap_height", "m"),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect()
}
