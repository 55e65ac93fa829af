//! Records -> Foxglove's well-known protobuf messages (the `foxglove` crate's types).
//!
//! Everything is in the frame `world` (z up, metres). Timestamps are simulated time.

use super::snapshot::{POINT_STRIDE, WallShape};
use foxglove::bytes::Bytes;
use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, PackedElementField, PointCloud, Pose, Quaternion,
    SceneEntity, SceneUpdate, SpherePrimitive, Timestamp, TriangleListPrimitive, Vector3,
    packed_element_field::NumericType,
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
