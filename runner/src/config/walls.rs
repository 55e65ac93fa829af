//! `[[walls]]`: rigid surfaces, each with a shape, a material and a motion.
//!
//! Shapes (`type`): `plane` {point, normal} (infinite, one-sided: particles live on the side the
//! normal points to), `disc` {centre, axis, radius}, `cylinder` {base, axis, radius, length}
//! (open, two-sided), `cone` {base, axis, radius_base, radius_top, length} (open frustum) and
//! `mesh` {file, scale} (an STL file, relative to the scene file's directory). Lengths in m.

use super::check;
use anyhow::{Result, anyhow, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tilth_kernel::wall::axisymmetric::Axisymmetric;
use tilth_kernel::wall::mesh::Mesh;
use tilth_kernel::wall::plane::Plane;
use tilth_kernel::wall::{Motion, Shape, Wall};

/// One wall: `name`, `material`, `motion` and the keys of its shape `type`, in one table.
/// Unknown keys are refused (by the shape, which is told the common keys apart).
/// Written as one table too: the shape's keys beside the common ones.
#[derive(Debug, Serialize)]
pub struct WallSection {
    /// Shown in the summary (default `walls[k]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Material name.
    pub material: String,
    /// Default `{ type = "fixed" }`.
    pub motion: MotionSection,
    #[serde(flatten)]
    pub shape: ShapeSection,
}

/// The keys every wall takes besides its shape's.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Common {
    name: Option<String>,
    material: String,
    #[serde(default)]
    motion: MotionSection,
}

const COMMON: [&str; 3] = ["name", "material", "motion"];

/// A nested error's text ("unknown field `x`\nin `motion`\n") on one line.
fn one_line(e: toml::de::Error) -> String {
    e.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

impl<'de> Deserialize<'de> for WallSection {
    /// serde cannot refuse unknown keys across a flattened enum, so the table is split by hand.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut shape = toml::Table::deserialize(d)?;
        let mut common = toml::Table::new();
        for key in COMMON {
            if let Some(v) = shape.remove(key) {
                common.insert(key.to_string(), v);
            }
        }
        let Common {
            name,
            material,
            motion,
        } = Common::deserialize(toml::Value::Table(common))
            .map_err(|e| D::Error::custom(one_line(e)))?;
        let shape = ShapeSection::deserialize(toml::Value::Table(shape)).map_err(|e| {
            D::Error::custom(format!(
                "{}; every wall also takes {}",
                one_line(e),
                COMMON.join(", ")
            ))
        })?;
        Ok(WallSection {
            name,
            material,
            motion,
            shape,
        })
    }
}

/// The shape keys of a wall, chosen by `type`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ShapeSection {
    /// Infinite plane through `point` (m) with `normal` pointing into the particle side.
    Plane { point: [f64; 3], normal: [f64; 3] },
    /// Flat disc of `radius` (m) centred at `centre` (m), normal to `axis`; with
    /// `inner_radius` (m, default 0) a ring with a hole, such as a shear box's flange.
    Disc {
        centre: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        #[serde(default)]
        inner_radius: f64,
    },
    /// Open cylinder of `radius` (m) from `base` (m) to `length` (m) along `axis`.
    Cylinder {
        base: [f64; 3],
        axis: [f64; 3],
        radius: f64,
        length: f64,
    },
    /// Open cone frustum: `radius_base` at `base`, `radius_top` at `length` along `axis` (m).
    Cone {
        base: [f64; 3],
        axis: [f64; 3],
        radius_base: f64,
        radius_top: f64,
        length: f64,
    },
    /// Triangles of an STL file (relative to the scene file), coordinates times `scale`
    /// (default 1; 1e-3 for a file in mm).
    Mesh {
        file: PathBuf,
        #[serde(default = "unit_scale")]
        scale: f64,
    },
}

impl ShapeSection {
    /// How the wall is drawn in recordings (a mesh that cannot be read is drawn empty; the
    /// run itself reports the error).
    pub fn drawing(&self, base_dir: &Path) -> WallShape {
        match self {
            ShapeSection::Plane { point, normal } => WallShape::Plane {
                point: *point,
                normal: *normal,
                half_width: 0.1,
            },
            ShapeSection::Disc {
                centre,
                axis,
                radius,
                ..
            } => WallShape::Axisymmetric {
                base: *centre,
                axis: *axis,
                radius_base: *radius,
                radius_top: *radius,
                length: 0.0,
            },
            ShapeSection::Cylinder {
                base,
                axis,
                radius,
                length,
            } => WallShape::Axisymmetric {
                base: *base,
                axis: *axis,
                radius_base: *radius,
                radius_top: *radius,
                length: *length,
            },
            ShapeSection::Cone {
                base,
                axis,
                radius_base,
                radius_top,
                length,
            } => WallShape::Axisymmetric {
                base: *base,
                axis: *axis,
                radius_base: *radius_base,
                radius_top: *radius_top,
                length: *length,
            },
            ShapeSection::Mesh { file, scale } => WallShape::Mesh {
                triangles: Mesh::from_stl(&base_dir.join(file), *scale)
                    .map(|m| {
                        m.triangles
                            .iter()
                            .map(|t| t.map(|v| v.to_array()))
                            .collect()
                    })
                    .unwrap_or_default(),
            },
        }
    }
}

fn unit_scale() -> f64 {
    1.0
}

/// `{ type = "fixed" }`, `{ type = "velocity", velocity }` or
/// `{ type = "servo", axis, target_force, gain, max_speed }`.
#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum MotionSection {
    /// At rest. (An empty struct variant, so that stray keys are refused.)
    Fixed {},
    /// Constant translation, m/s.
    Velocity { velocity: [f64; 3] },
    /// Moves along `axis` at v = clamp(gain (target_force - F), +-max_speed) to make the force
    /// the particles exert against the motion equal `target_force` (N); `gain` in m/s/N,
    /// `max_speed` in m/s.
    Servo {
        axis: [f64; 3],
        target_force: f64,
        gain: f64,
        max_speed: f64,
    },
}

impl Default for MotionSection {
    fn default() -> Self {
        MotionSection::Fixed {}
    }
}

impl ShapeSection {
    /// The `type` name.
    pub fn kind(&self) -> &'static str {
        match self {
            ShapeSection::Plane { .. } => "plane",
            ShapeSection::Disc { .. } => "disc",
            ShapeSection::Cylinder { .. } => "cylinder",
            ShapeSection::Cone { .. } => "cone",
            ShapeSection::Mesh { .. } => "mesh",
        }
    }

    fn build(&self, key: &dyn Fn(&str) -> String, base_dir: &Path) -> Result<Box<dyn Shape>> {
        let bad = || anyhow!("{}: degenerate {} geometry", key("type"), self.kind());
        Ok(match *self {
            ShapeSection::Plane { point, normal } => Box::new(
                Plane::new(
                    check::vec3(&key("point"), point)?,
                    check::direction(&key("normal"), normal)?,
                )
                .ok_or_else(bad)?,
            ),
            ShapeSection::Disc {
                centre,
                axis,
                radius,
                inner_radius,
            } => {
                let outer = check::positive(&key("radius"), radius, "m")?;
                let inner = check::non_negative(&key("inner_radius"), inner_radius, "m")?;
                if inner >= outer {
                    bail!(
                        "{} = {inner} m is out of range: allowed [0, radius = {outer}) m",
                        key("inner_radius")
                    );
                }
                Box::new(
                    Axisymmetric::annulus(
                        check::vec3(&key("centre"), centre)?,
                        check::direction(&key("axis"), axis)?,
                        inner,
                        outer,
                    )
                    .ok_or_else(bad)?,
                )
            }
            ShapeSection::Cylinder {
                base,
                axis,
                radius,
                length,
            } => Box::new(
                Axisymmetric::cylinder(
                    check::vec3(&key("base"), base)?,
                    check::direction(&key("axis"), axis)?,
                    check::positive(&key("radius"), radius, "m")?,
                    check::positive(&key("length"), length, "m")?,
                )
                .ok_or_else(bad)?,
            ),
            ShapeSection::Cone {
                base,
                axis,
                radius_base,
                radius_top,
                length,
            } => {
                let r0 = check::non_negative(&key("radius_base"), radius_base, "m")?;
                let r1 = check::non_negative(&key("radius_top"), radius_top, "m")?;
                if r0 == 0.0 && r1 == 0.0 {
                    bail!(
                        "{} and {} are both 0; one must be positive",
                        key("radius_base"),
                        key("radius_top")
                    );
                }
                Box::new(
                    Axisymmetric::frustum(
                        check::vec3(&key("base"), base)?,
                        check::direction(&key("axis"), axis)?,
                        r0,
                        r1,
                        check::positive(&key("length"), length, "m")?,
                    )
                    .ok_or_else(bad)?,
                )
            }
            ShapeSection::Mesh { ref file, scale } => {
                let scale = check::positive(&key("scale"), scale, "-")?;
                let path = base_dir.join(file);
                // The mesh error names its cause itself; keep it out of the chain.
                Box::new(Mesh::from_stl(&path, scale).map_err(|e| anyhow!("{}: {e}", key("file")))?)
            }
        })
    }
}

impl MotionSection {
    fn build(&self, key: &dyn Fn(&str) -> String) -> Result<Motion> {
        Ok(match *self {
            MotionSection::Fixed {} => Motion::Fixed,
            MotionSection::Velocity { velocity } => {
                Motion::Velocity(check::vec3(&key("motion.velocity"), velocity)?)
            }
            MotionSection::Servo {
                axis,
                target_force,
                gain,
                max_speed,
            } => Motion::Servo {
                axis: check::direction(&key("motion.axis"), axis)?.normalize(),
                target_force: check::finite(&key("motion.target_force"), target_force, "N")?,
                gain: check::positive(&key("motion.gain"), gain, "m/s/N")?,
                max_speed: check::positive(&key("motion.max_speed"), max_speed, "m/s")?,
            },
        })
    }
}

impl WallSection {
    pub fn display_name(&self, k: usize) -> String {
        self.name.clone().unwrap_or_else(|| format!("walls[{k}]"))
    }
}

pub fn resolve(
    sections: &[WallSection],
    materials: &[String],
    base_dir: &Path,
) -> Result<Vec<Wall>> {
    if sections.len() > u16::MAX as usize {
        bail!("too many walls ({}); at most {}", sections.len(), u16::MAX);
    }
    let mut out = vec![];
    for (k, w) in sections.iter().enumerate() {
        let key = |s: &str| format!("walls[{k}].{s}");
        let material = check::material(&key("material"), &w.material, materials)?;
        let shape = w.shape.build(&key, base_dir)?;
        let motion = w.motion.build(&key)?;
        out.push(Wall::new(&w.display_name(k), shape, material, motion));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_key_inside_a_wall_is_refused() {
        let ok: WallSection = toml::from_str(
            "name = 'floor'\ntype = 'plane'\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = 'soil'",
        )
        .unwrap();
        assert_eq!(ok.shape.kind(), "plane");
        let err = toml::from_str::<WallSection>(
            "type = 'plane'\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1.0\nmaterial = 'soil'",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("unknown field `radius`") && err.contains("also takes name"),
            "{err}"
        );
        let err = toml::from_str::<WallSection>(
            "type = 'plane'\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = 'soil'\nmotion = { type = 'fixed', speed = 1 }",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("unknown field `speed`"), "{err}");
        let err =
            toml::from_str::<WallSection>("type = 'plane'\npoint = [0, 0, 0]\nnormal = [0, 0, 1]")
                .unwrap_err()
                .to_string();
        assert!(err.contains("missing field `material`"), "{err}");
    }
}

/// How a wall is drawn (its initial pose; the recorded offset moves it).
#[derive(Debug, Clone)]
pub enum WallShape {
    /// Drawn as a thin square of `half_width` around `point`.
    Plane {
        point: [f64; 3],
        normal: [f64; 3],
        half_width: f64,
    },
    /// A cylinder, cone frustum or disc (length 0) along `axis` from `base`.
    Axisymmetric {
        base: [f64; 3],
        axis: [f64; 3],
        radius_base: f64,
        radius_top: f64,
        length: f64,
    },
    /// Triangles (m), drawn as a triangle list.
    Mesh { triangles: Vec<[[f64; 3]; 3]> },
}
