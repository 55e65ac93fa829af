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
mod walls;

pub use contact::{ContactSection, PairSection};
pub use factories::{BasisSection, FactorySection, RegionSection, SizeClass};
pub use materials::MaterialSection;
pub use output::OutputSection;
pub use particles::ParticleSection;
pub use simulation::{DomainSection, SimulationSection};
pub use walls::{MotionSection, ShapeSection, WallSection};

use anyhow::{Context, Result, bail};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tilth_kernel::contact::{ContactModel, ModelSpec};
use tilth_kernel::sim::{Setup, Simulation};

/// The only scene format this build reads.
pub const FORMAT_VERSION: i64 = 1;

/// The demo scene, embedded so that `tilth run` works from any directory.
pub const DEMO: &str = include_str!("../../../sweeps/demo.toml");
/// The name the embedded demo goes by in messages.
pub const DEMO_NAME: &str = "sweeps/demo.toml (embedded)";

/// A whole scene file.
#[derive(Debug, Deserialize)]
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
    #[serde(default)]
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
        Ok(Loaded {
            sim: Simulation::new(setup)?,
            threads,
            steps: sim.steps,
            sample_every,
            info,
        })
    }
}

/// `load` or the embedded demo when `path` is `None`.
pub fn load_or_demo(path: Option<&PathBuf>, threads: Option<usize>) -> Result<Loaded> {
    match path {
        Some(p) => load(p, threads),
        None => load_str(DEMO, DEMO_NAME, Path::new("."), threads),
    }
}
