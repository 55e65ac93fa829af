//! Records -> Foxglove's well-known protobuf messages (the `foxglove` crate's types).
//!
//! Everything is in the frame `world` (z up, metres). Timestamps are simulated time.

use super::snapshot::{BOND_STRIDE, POINT_STRIDE};
use crate::config::WallShape;
use foxglove::bytes::Bytes;
use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, LinePrimitive, PackedElementField, Point3, PointCloud,
    Pose, Quaternion, SceneEntity, SceneUpdate, SpherePrimitive, Timestamp, TriangleListPrimitive,
    Vector3, line_primitive, packed_element_field::NumericType,
};
use glam::{DQuat, DVec3};

/// The frame every message is expressed in.
pub const FRAME: &str = "world";

/// Simulated time `t` (s) as a message timestamp.
pub fn timestamp(t: f64) -> Timestamp {
    let ns = time_ns(t);
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

/// Simulated time `t` (s) in nanoseconds, the MCAP log time.
pub fn time_ns(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

fn vector(v: [f64; 3]) -> Vector3 {
    Vector3 {
        x: v[0],
        y: v[1],
        z: v[2],
    }
}

fn pose(position: DVec3, orientation: DQuat) -> Pose {
    Pose {
        position: Some(vector(position.to_array())),
        orientation: Some(Quaternion {
            x: orientation.x,
            y: orientation.y,
            z: orientation.z,
            w: orientation.w,
        }),
    }
}

/// The identity pose: the issue asks for it, and Foxglove and Rerun then place the cloud
/// explicitly in `world` instead of relying on a default.
fn identity() -> Pose {
    pose(DVec3::ZERO, DQuat::IDENTITY)
}

/// The point cloud of one [`super::Record::Particles`] frame.
pub fn point_cloud(time: f64, points: Vec<u8>) -> PointCloud {
    let field = |name: &str, offset: u32, kind: NumericType| PackedElementField {
        name: name.to_string(),
        offset,
        r#type: kind as i32,
    };
    PointCloud {
        timestamp: Some(timestamp(time)),
        frame_id: FRAME.to_string(),
        pose: Some(identity()),
        point_stride: POINT_STRIDE as u32,
        fields: vec![
            field("x", 0, NumericType::Float32),
            field("y", 4, NumericType::Float32),
            field("z", 8, NumericType::Float32),
            field("radius", 12, NumericType::Float32),
            field("speed", 16, NumericType::Float32),
            field("id", 20, NumericType::Uint32),
            field("material", 24, NumericType::Uint32),
        ],
        data: Bytes::from(points),
    }
}

fn f32_at(b: &[u8], k: usize) -> f64 {
    f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as f64
}

/// Colour for a speed (m/s): blue at rest to red at `v_max` and above.
fn speed_colour(v: f64, v_max: f64) -> Color {
    let s = (v / v_max).clamp(0.0, 1.0);
    Color {
        r: s,
        g: 0.3 * (1.0 - s),
        b: 1.0 - s,
        a: 1.0,
    }
}

/// Every particle as a sphere of its true diameter, coloured by speed.
pub fn spheres(time: f64, points: &[u8]) -> SceneUpdate {
    let spheres = points
        .chunks_exact(POINT_STRIDE)
        .map(|p| SpherePrimitive {
            pose: Some(pose(
                DVec3::new(f32_at(p, 0), f32_at(p, 4), f32_at(p, 8)),
                DQuat::IDENTITY,
            )),
            size: Some(vector([2.0 * f32_at(p, 12); 3])),
            color: Some(speed_colour(f32_at(p, 16), 1.0)),
        })
        .collect();
    SceneUpdate {
        deletions: vec![],
        entities: vec![SceneEntity {
            timestamp: Some(timestamp(time)),
            frame_id: FRAME.to_string(),
            id: "particles".to_string(),
            spheres,
            ..Default::default()
        }],
    }
}

const WALL_COLOUR: Color = Color {
    r: 0.6,
    g: 0.6,
    b: 0.65,
    a: 0.35,
};

/// Drawn thickness of planes and discs, m.
const THIN: f64 = 1e-4;

/// One entity per wall, moved by its offset.
pub fn walls(
    time: f64,
    names: &[String],
    shapes: &[WallShape],
    offsets: &[[f64; 3]],
) -> SceneUpdate {
    let entities = names
        .iter()
        .zip(shapes)
        .zip(offsets)
        .map(|((name, shape), offset)| {
            let mut e = SceneEntity {
                timestamp: Some(timestamp(time)),
                frame_id: FRAME.to_string(),
                id: name.clone(),
                ..Default::default()
            };
            let offset = DVec3::from_array(*offset);
            match shape {
                WallShape::Plane {
                    point,
                    normal,
                    half_width,
                } => {
                    let n = DVec3::from_array(*normal).normalize();
                    e.cubes.push(CubePrimitive {
                        pose: Some(pose(
                            DVec3::from_array(*point) + offset,
                            DQuat::from_rotation_arc(DVec3::Z, n),
                        )),
                        size: Some(vector([2.0 * half_width, 2.0 * half_width, THIN])),
                        color: Some(WALL_COLOUR),
                    });
                }
                WallShape::Axisymmetric {
                    base,
                    axis,
                    radius_base,
                    radius_top,
                    length,
                } => {
                    let a = DVec3::from_array(*axis).normalize();
                    let r = radius_base.max(*radius_top);
                    let centre = DVec3::from_array(*base) + offset + 0.5 * length * a;
                    e.cylinders.push(CylinderPrimitive {
                        pose: Some(pose(centre, DQuat::from_rotation_arc(DVec3::Z, a))),
                        size: Some(vector([2.0 * r, 2.0 * r, length.max(THIN)])),
                        bottom_scale: radius_base / r,
                        top_scale: radius_top / r,
                        color: Some(WALL_COLOUR),
                    });
                }
                WallShape::Mesh { triangles } => {
                    e.triangles.push(TriangleListPrimitive {
                        pose: Some(pose(offset, DQuat::IDENTITY)),
                        points: triangles
                            .iter()
                            .flatten()
                            .map(|v| foxglove::messages::Point3 {
                                x: v[0],
                                y: v[1],
                                z: v[2],
                            })
                            .collect(),
                        color: Some(WALL_COLOUR),
                        colors: vec![],
                        indices: vec![],
                    });
                }
            }
            e
        })
        .collect();
    SceneUpdate {
        deletions: vec![],
        entities,
    }
}

/// A vector channel value (wall force or torque).
pub fn vector3(v: [f64; 3]) -> Vector3 {
    vector(v)
}

/// A scalar channel value: `foxglove.Vector3` with the value in `x` (Foxglove's schemas
/// have no scalar message; plot `/scalars/<name>.x`).
pub fn scalar(v: f64) -> Vector3 {
    vector([v, 0.0, 0.0])
}

/// Every bond as a point at its middle carrying its whole state (see
/// [`super::snapshot::BOND_STRIDE`]): Foxglove colours the points by any field.
pub fn bond_cloud(time: f64, points: Vec<u8>) -> PointCloud {
    let field = |name: &str, offset: u32, kind: NumericType| PackedElementField {
        name: name.to_string(),
        offset,
        r#type: kind as i32,
    };
    let f32s = [
        "normal_force",
        "shear_force_x",
        "shear_force_y",
        "shear_force_z",
        "normal_moment",
        "shear_moment_x",
        "shear_moment_y",
        "shear_moment_z",
    ];
    let mut fields = vec![
        field("x", 0, NumericType::Float32),
        field("y", 4, NumericType::Float32),
        field("z", 8, NumericType::Float32),
        field("i", 12, NumericType::Uint32),
        field("j", 16, NumericType::Uint32),
    ];
    for (k, name) in f32s.iter().enumerate() {
        fields.push(field(name, 20 + 4 * k as u32, NumericType::Float32));
    }
    fields.push(field("intact", 52, NumericType::Uint32));
    fields.push(field("broken_time", 56, NumericType::Float32));
    PointCloud {
        timestamp: Some(timestamp(time)),
        frame_id: FRAME.to_string(),
        pose: Some(identity()),
        point_stride: BOND_STRIDE as u32,
        fields,
        data: Bytes::from(points),
    }
}

/// Intact bonds as line segments between the bonded particles' centres, coloured by their
/// normal force (red in tension, blue in compression, full colour at `scale` N).
pub fn bond_lines(
    time: f64,
    bonds: &[u8],
    centres: &std::collections::HashMap<u32, [f64; 3]>,
) -> SceneUpdate {
    let mut points = vec![];
    let mut colors = vec![];
    let forces: Vec<f64> = bonds
        .chunks_exact(BOND_STRIDE)
        .map(|b| f32_at(b, 20).abs())
        .collect();
    let scale = forces.iter().cloned().fold(0.0, f64::max).max(1e-12);
    for b in bonds.chunks_exact(BOND_STRIDE) {
        let u = |k: usize| u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        if u(52) == 0 {
            continue;
        }
        let (Some(a), Some(c)) = (centres.get(&u(12)), centres.get(&u(16))) else {
            continue;
        };
        let fnorm = f32_at(b, 20);
        let s = (fnorm.abs() / scale).clamp(0.0, 1.0);
        let colour = if fnorm < 0.0 {
            Color {
                r: 0.4 + 0.6 * s,
                g: 0.4 * (1.0 - s),
                b: 0.4 * (1.0 - s),
                a: 1.0,
            }
        } else {
            Color {
                r: 0.4 * (1.0 - s),
                g: 0.4 * (1.0 - s),
                b: 0.4 + 0.6 * s,
                a: 1.0,
            }
        };
        for q in [a, c] {
            points.push(Point3 {
                x: q[0],
                y: q[1],
                z: q[2],
            });
            colors.push(colour);
        }
    }
    SceneUpdate {
        deletions: vec![],
        entities: vec![SceneEntity {
            timestamp: Some(timestamp(time)),
            frame_id: FRAME.to_string(),
            id: "bonds".to_string(),
            lines: vec![LinePrimitive {
                r#type: line_primitive::Type::LineList as i32,
                pose: Some(identity()),
                thickness: 1.0,
                scale_invariant: true,
                points,
                color: None,
                colors,
                indices: vec![],
            }],
            ..Default::default()
        }],
    }
}
