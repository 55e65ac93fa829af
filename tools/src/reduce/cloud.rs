//! One `/particles` frame as struct-of-arrays, decoded from a `foxglove.PointCloud`.
//!
//! The runner packs each particle as `x, y, z, radius, speed` (f32, m and m/s) at byte
//! offsets 0, 4, 8, 12, 16 and `id, material` (u32) at 20, 24, stride 28 (runner/MCAP.md).
//! The decoder finds the fields by name and type in the message's own field list instead of
//! assuming those offsets, so a reordered layout still decodes and a wrong one is refused.

use foxglove::messages::PointCloud;
use foxglove::messages::packed_element_field::NumericType;
use serde::{Deserialize, Serialize};

/// The particles of one frame, one entry per particle in every vector (metres, m/s).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ParticleCloud {
    /// Simulated time of the frame, s.
    pub time_s: f64,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
    pub radius: Vec<f64>,
    pub speed: Vec<f64>,
    pub id: Vec<u32>,
    pub material: Vec<u32>,
}

impl ParticleCloud {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when the frame holds no particle.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Decodes the points of `msg`; `time_s` is the message's log time. `Err` is a sentence
    /// saying what in the layout is wrong.
    pub fn from_point_cloud(msg: &PointCloud, time_s: f64) -> Result<ParticleCloud, String> {
        let stride = msg.point_stride as usize;
        let field = |name: &str, kind: NumericType| -> Result<usize, String> {
            let f = msg
                .fields
                .iter()
                .find(|f| f.name == name)
                .ok_or_else(|| format!("no field {name:?}"))?;
            if f.r#type != kind as i32 {
                return Err(format!(
                    "field {name:?} has numeric type {}, expected {kind:?}",
                    f.r#type
                ));
            }
            let offset = f.offset as usize;
            if offset + 4 > stride {
                return Err(format!(
                    "field {name:?} at byte {offset} does not fit a point of {stride} bytes"
                ));
            }
            Ok(offset)
        };
        let [ox, oy, oz, or, os] =
            ["x", "y", "z", "radius", "speed"].map(|n| field(n, NumericType::Float32));
        let [oi, om] = ["id", "material"].map(|n| field(n, NumericType::Uint32));
        let (ox, oy, oz, or, os, oi, om) = (ox?, oy?, oz?, or?, os?, oi?, om?);
        let data = &msg.data[..];
        if stride == 0 || data.len() % stride != 0 {
            return Err(format!(
                "{} bytes of data are not a whole number of {stride}-byte points",
                data.len()
            ));
        }
        let n = data.len() / stride;
        let word = |p: &[u8], k: usize| [p[k], p[k + 1], p[k + 2], p[k + 3]];
        let float = |p: &[u8], k: usize| f32::from_le_bytes(word(p, k)) as f64;
        let mut c = ParticleCloud {
            time_s,
            ..ParticleCloud::default()
        };
        for v in [&mut c.x, &mut c.y, &mut c.z, &mut c.radius, &mut c.speed] {
            v.reserve_exact(n);
        }
        c.id.reserve_exact(n);
        c.material.reserve_exact(n);
        for p in data.chunks_exact(stride) {
            c.x.push(float(p, ox));
            c.y.push(float(p, oy));
            c.z.push(float(p, oz));
            c.radius.push(float(p, or));
            c.speed.push(float(p, os));
            c.id.push(u32::from_le_bytes(word(p, oi)));
            c.material.push(u32::from_le_bytes(word(p, om)));
        }
        Ok(c)
    }
}
