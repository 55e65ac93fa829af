//! Scene files: TOML -> a checked kernel [`Setup`] -> a ready [`Simulation`].
//!
//! One file per section (`simulation`, `materials`, `contact` + `pairs`, `walls`, `factories`,
//! `particles`, `output`). Every struct refuses unknown keys; every value is checked before the
//! run starts, and every error names the file, the key (e.g. `walls[2].radius`, 0-based
//! indices) and the allowed range. Lengths are in metres, times in seconds, SI throughout.

mod check;
mod contact;
mod factories;
mod materials;
mod output;
mod particles;
mod simulation;
pub mod target;
mod walls;

pub use contact::{ContactSection, PairSection};
pub use factories::{BasisSection, FactorySection, RegionSection, SizeClass};
pub use materials::MaterialSection;
pub use output::OutputSection;
pub use particles::ParticleSection;
pub use simulation::{DomainSection, STANDARD_GRAVITY, SimulationSection};
pub use walls::{MotionSection, ShapeSection, WallSection, WallShape};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tilth_kernel::contact::{ContactModel, ModelSpec};
use tilth_kernel::sim::{Setup, Simulation, ThreadStart};

/// The only scene format this build reads.
pub const FORMAT_VERSION: i64 = 1;

/// The demo scene, embedded so that `tilth run` works from any directory.
pub const DEMO: &str = include_str!("../../../sweeps/scenes/pile.toml");
/// The name the embedded demo goes by in messages.
pub const DEMO_NAME: &str = "sweeps/scenes/pile.toml (embedded)";

/// A whole scene file (also written by the virtual lab, which builds its scenes as this).
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene format; only [`FORMAT_VERSION`] is accepted.
    pub format_version: i64,
    pub simulation: SimulationSection,
    /// Materials by name (`[materials.soil]`).
    pub materials: BTreeMap<String, MaterialSection>,
    pub contact: ContactSection,
    /// Contact coefficients of each material pair that can meet.
    #[serde(default)]
    pub pairs: Vec<PairSection>,
    #[serde(default)]
    pub walls: Vec<WallSection>,
    #[serde(default)]
    pub factories: Vec<FactorySection>,
    /// Explicit particles, created before the first step.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<ParticleSection>,
    #[serde(default)]
    pub output: OutputSection,
}

/// Only the version, read first so that a file of another version gets a clear message.
#[derive(Deserialize)]
struct VersionProbe {
    format_version: Option<toml::Value>,
}

/// What a scene describes, kept for the summary.
#[derive(Debug, Clone)]
pub struct SceneInfo {
    /// The file (or the embedded demo's name).
    pub origin: String,
    pub materials: Vec<String>,
    /// Law names in slot order.
    pub laws: Vec<String>,
    /// (name, type) of every wall.
    pub walls: Vec<(String, &'static str)>,
}

/// A scene ready to run.
pub struct Loaded {
    pub sim: Simulation,
    /// Worker threads the simulation uses.
    pub threads: usize,
    pub steps: u64,
    /// Steps between recorded samples (`output.every`).
    pub sample_every: Option<u64>,
    pub info: SceneInfo,
}

/// Loads, checks and prepares the scene in `path`; `threads` overrides `simulation.threads`.
pub fn load(path: &Path, threads: Option<usize>) -> Result<Loaded> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| format!("{origin}: cannot read"))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_str(&text, &origin, &dir, threads)
}

/// Like [`load`] for text already in memory; `origin` names it in messages and mesh files
/// are looked up relative to `base_dir`.
pub fn load_str(
    text: &str,
    origin: &str,
    base_dir: &Path,
    threads: Option<usize>,
) -> Result<Loaded> {
    build(text, origin, base_dir, threads).with_context(|| origin.to_string())
}

fn build(text: &str, origin: &str, base_dir: &Path, threads: Option<usize>) -> Result<Loaded> {
    let probe: VersionProbe = toml::from_str(text)?;
    match probe.format_version {
        None => bail!(
            "format_version is missing; add `format_version = {FORMAT_VERSION}` as the first line"
        ),
        Some(toml::Value::Integer(FORMAT_VERSION)) => {}
        Some(v) => bail!(
            "format_version = {v} is not supported; this tilth reads format_version = {FORMAT_VERSION}"
        ),
    }
    let scene: Scene = toml::from_str(text)?;
    scene.resolve(origin, base_dir, threads)
}

impl Scene {
    /// Checks every value and builds the simulation. `origin` names the scene in the summary;
    /// mesh files are looked up relative to `base_dir`.
    pub fn resolve(self, origin: &str, base_dir: &Path, threads: Option<usize>) -> Result<Loaded> {
        self.prepare(origin, base_dir, threads)?.start(None)
    }

    /// Checks every value and builds the kernel's set-up without starting the simulation.
    pub fn prepare(
        self,
        origin: &str,
        base_dir: &Path,
        threads: Option<usize>,
    ) -> Result<Prepared> {
        let materials = materials::resolve(&self.materials)?;
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
        let spec = ModelSpec {
            normal: self.contact.normal.clone(),
            damping: self.contact.damping.clone(),
            tangential: self.contact.tangential.clone(),
            rolling: self.contact.rolling.clone(),
            extra: self.contact.extra.clone(),
        };
        let pairs: Vec<_> = self.pairs.iter().map(PairSection::to_spec).collect();
        let model = ContactModel::build(&materials, &spec, &pairs)?;
        let particles = particles::resolve(&self.particles, &materials)?;
        let factories = factories::resolve(&self.factories, &materials, self.simulation.seed)?;
        if particles.is_empty() && factories.is_empty() {
            bail!("the scene has no particles: add [[particles]] or [[factories]]");
        }
        let walls = walls::resolve(&self.walls, &names, base_dir)?;
        let sim = self.simulation.resolve(&particles, &self.factories)?;
        let sample_every = self.output.resolve(sim.dt)?;
        let info = SceneInfo {
            origin: origin.to_string(),
            materials: names,
            laws: model.law_names().iter().map(|s| s.to_string()).collect(),
            walls: self
                .walls
                .iter()
                .enumerate()
                .map(|(k, w)| (w.display_name(k), w.shape.kind()))
                .collect(),
        };
        let threads = threads.unwrap_or(sim.threads);
        let setup = Setup {
            model,
            particles,
            walls,
            factories,
            dt: sim.dt,
            gravity: sim.gravity,
            skin: sim.skin,
            threads,
            domain: sim.domain,
        };
        let wall_shapes = self
            .walls
            .iter()
            .map(|w| w.shape.drawing(base_dir))
            .collect();
        Ok(Prepared {
            setup,
            threads,
            steps: sim.steps,
            sample_every,
            info,
            wall_shapes,
        })
    }
}

/// A checked scene whose simulation has not started.
pub struct Prepared {
    pub setup: Setup,
    pub threads: usize,
    pub steps: u64,
    pub sample_every: Option<u64>,
    pub info: SceneInfo,
    /// How each wall is drawn in recordings.
    pub wall_shapes: Vec<WallShape>,
}

impl Prepared {
    /// Starts the simulation; `thread_start` runs first on each worker (to pin it).
    pub fn start(self, thread_start: Option<ThreadStart>) -> Result<Loaded> {
        Ok(Loaded {
            sim: Simulation::with_thread_start(self.setup, thread_start)?,
            threads: self.threads,
            steps: self.steps,
            sample_every: self.sample_every,
            info: self.info,
        })
    }
}

/// Deserializes a scene from a TOML value (a sweep run's scene with its factor values set)
/// and prepares it; `origin` names it in messages.
pub fn prepare_value(
    value: toml::Value,
    origin: &str,
    base_dir: &Path,
    threads: Option<usize>,
) -> Result<Prepared> {
    let scene: Scene = value.try_into().map_err(|e: toml::de::Error| {
        anyhow::anyhow!(
            "{}",
            e.message().split_whitespace().collect::<Vec<_>>().join(" ")
        )
    })?;
    scene.prepare(origin, base_dir, threads)
}

/// `load` or the embedded demo when `path` is `None`.
pub fn load_or_demo(path: Option<&PathBuf>, threads: Option<usize>) -> Result<Loaded> {
    match path {
        Some(p) => load(p, threads),
        None => load_str(DEMO, DEMO_NAME, Path::new("."), threads),
    }
}
