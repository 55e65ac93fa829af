//! Lab scenes, built as the scene file's own sections ([`Scene`]) so that a misspelt key or a
//! value of the wrong type is a compile error, not a scene the checks refuse at run time;
//! and [`WallId`], a wall a protocol finds by its name.
//!
//! Every rig stands on the z axis; lengths in m, times in s.

use super::experiment::Common;
use super::model::SceneParts;
use super::sizes::SizeMix;
use crate::config::{
    BasisSection, DomainSection, FORMAT_VERSION, FactorySection, MotionSection, OutputSection,
    RegionSection, STANDARD_GRAVITY, Scene, ShapeSection, SimulationSection, WallSection,
};
use anyhow::{Result, anyhow};
use tilth_kernel::sim::Simulation;
use tilth_kernel::wall::Wall;
use toml::Value;

/// The rigs' axis: walls and fill regions are built around it, pointing up.
pub const UP: [f64; 3] = [0.0, 0.0, 1.0];

/// A point on the axis at height `z`, m.
pub fn on_axis(z: f64) -> [f64; 3] {
    [0.0, 0.0, z]
}

/// A scene of the model's materials and contact laws (`parts`) with the test's own
/// simulation settings, walls and factories.
pub fn scene(
    parts: SceneParts,
    simulation: SimulationSection,
    walls: Vec<WallSection>,
    factories: Vec<FactorySection>,
) -> Scene {
    Scene {
        format_version: FORMAT_VERSION,
        simulation,
        materials: parts.materials,
        contact: parts.contact,
        pairs: parts.pairs,
        walls,
        factories,
        particles: vec![],
        output: OutputSection::default(),
    }
}

/// The scene as a TOML value: factor targets (`scene:PATH`) are set on it by path, and it
/// is checked and loaded like any scene file.
pub fn to_value(scene: &Scene) -> Result<Value> {
    Value::try_from(scene).map_err(|e| anyhow!("the lab's scene cannot be written as TOML: {e}"))
}

/// `[simulation]` of a lab test: steps of `dt` s for `duration` s, a Verlet skin of `skin`
/// m, particles kept inside `domain`; the seed and threads are the experiment's.
pub fn simulation(
    c: &Common,
    dt: f64,
    duration: f64,
    skin: f64,
    domain: DomainSection,
) -> SimulationSection {
    SimulationSection {
        dt,
        duration: Some(duration),
        steps: None,
        gravity: STANDARD_GRAVITY,
        skin: Some(skin),
        threads: c.sim.threads,
        seed: c.sim.seed,
        domain,
    }
}

/// The domain box from (-half, -half, `bottom`) to (half, half, `top`), m.
pub fn domain(half: f64, bottom: f64, top: f64) -> DomainSection {
    DomainSection {
        min: [-half, -half, bottom],
        max: [half, half, top],
    }
}

/// A steel wall at rest named `name`: every wall of the lab's rigs is one.
pub fn steel(name: &str, shape: ShapeSection) -> WallSection {
    WallSection {
        name: Some(name.to_string()),
        material: "steel".to_string(),
        motion: MotionSection::default(),
        shape,
    }
}

/// A horizontal steel disc of `radius` centred on the axis at height `z`.
pub fn disc(name: &str, z: f64, radius: f64) -> WallSection {
    flange(name, z, 0.0, radius)
}

/// A flat steel ring between radii `inner` and `outer` at height `z` (a shear box's
/// flange; a disc when `inner` is 0).
pub fn flange(name: &str, z: f64, inner: f64, outer: f64) -> WallSection {
    steel(
        name,
        ShapeSection::Disc {
            centre: on_axis(z),
            axis: UP,
            radius: outer,
            inner_radius: inner,
        },
    )
}

/// An open steel cylinder of `radius` on the axis from height `z0` to `z1`.
pub fn ring(name: &str, z0: f64, z1: f64, radius: f64) -> WallSection {
    steel(
        name,
        ShapeSection::Cylinder {
            base: on_axis(z0),
            axis: UP,
            radius,
            length: z1 - z0,
        },
    )
}

/// The steel plane z = 0, particles above it.
pub fn floor(name: &str) -> WallSection {
    steel(
        name,
        ShapeSection::Plane {
            point: on_axis(0.0),
            normal: UP,
        },
    )
}

/// A factory of `count` soil particles of the size mix `mix` (by mass) in `region`, at
/// `rate` particles/s, starting at `velocity` m/s.
pub fn soil_factory(
    region: RegionSection,
    count: usize,
    rate: f64,
    velocity: [f64; 3],
    mix: &SizeMix,
) -> FactorySection {
    FactorySection {
        region,
        material: "soil".to_string(),
        count,
        rate: Some(rate),
        velocity,
        basis: BasisSection::Mass,
        sizes: mix.size_classes(),
        start_time: 0.0,
    }
}

/// A vertical cylinder on the axis of `radius` from height `z0` to `z1`: where a factory
/// makes particles.
pub fn cylinder_region(radius: f64, z0: f64, z1: f64) -> RegionSection {
    RegionSection::Cylinder {
        base: on_axis(z0),
        radius,
        height: z1 - z0,
    }
}

/// A wall of a lab scene, found by its name. Protocols move and weigh walls through these,
/// so that reordering a scene's walls cannot make them act on the wrong one. The simulation
/// holds the walls in the scene's order (`config` builds them in file order), so a wall's
/// position in the scene is its index in [`Simulation::walls`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WallId(usize);

impl WallId {
    /// The wall named `name` among `walls` (a scene's, before it is loaded).
    pub fn find(walls: &[WallSection], name: &str) -> Result<WallId> {
        walls
            .iter()
            .position(|w| w.name.as_deref() == Some(name))
            .map(WallId)
            .ok_or_else(|| anyhow!("the lab's scene has no wall named `{name}`"))
    }

    /// The wall's index in the simulation.
    pub fn index(self) -> usize {
        self.0
    }

    /// The wall in `sim`.
    pub fn of(self, sim: &Simulation) -> &Wall {
        &sim.walls[self.0]
    }

    /// The wall in `sim`, to move it.
    pub fn of_mut(self, sim: &mut Simulation) -> &mut Wall {
        &mut sim.walls[self.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall written as one TOML table (the shape's keys beside the common ones) reads
    /// back as the same wall, so that what the lab builds is what the run loads.
    #[test]
    fn a_wall_written_as_toml_reads_back_as_the_same_wall() {
        for wall in [
            flange("lower_flange", 0.01, 0.031, 0.045),
            ring("mould", 0.0, 0.1, 0.0309),
            floor("base"),
        ] {
            let written = Value::try_from(&wall).unwrap();
            let read: WallSection = written.clone().try_into().unwrap();
            assert_eq!(Value::try_from(&read).unwrap(), written);
            assert_eq!(read.name.as_deref(), wall.name.as_deref());
        }
    }

    /// Walls are found wherever the scene lists them; a missing one is named.
    #[test]
    fn walls_are_found_by_name_and_a_missing_one_is_named() {
        let walls = [floor("base"), disc("platen", 0.1, 0.03)];
        assert_eq!(WallId::find(&walls, "platen").unwrap().index(), 1);
        assert_eq!(WallId::find(&walls, "base").unwrap().index(), 0);
        let e = WallId::find(&walls, "mould").unwrap_err().to_string();
        assert!(e.contains("no wall named `mould`"), "{e}");
    }
}
