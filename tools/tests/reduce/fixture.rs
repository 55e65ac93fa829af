//! Writes MCAP files in exactly the layout a tilth run writes (runner/MCAP.md, and the
//! channel contract of the reducers), so the reducers are tested through the real reading
//! path: zstd chunks closed on `flush`, schemas and channels added on first use with the
//! `foxglove` crate's schemas, metadata records `tilth.run` and `tilth.experiment`,
//! `/particles` as a `foxglove.PointCloud` (x, y, z, radius, speed f32 at 0..16, id, material
//! u32 at 20, 24, stride 28) and `/scalars/<name>` as `foxglove.Vector3` with the value in x.
//!
//! The file lives in memory while it is written, so a test can take the bytes a crash at
//! this moment would leave on disk ([`Fixture::killed_now`]): the chunk being written is
//! there with its placeholder header, exactly as the runner's writer (mcap's direct chunk
//! mode) leaves it.

use foxglove::Encode;
use foxglove::bytes::Bytes;
use foxglove::messages::packed_element_field::NumericType;
use foxglove::messages::{PackedElementField, PointCloud, Pose, Quaternion, Timestamp, Vector3};
use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::io::{Cursor, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use tilth_tools::reduce::ParticleCloud;

/// An in-memory file the MCAP writer and the test share.
#[derive(Clone, Default)]
struct Shared(Rc<RefCell<Cursor<Vec<u8>>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for Shared {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.0.borrow_mut().seek(pos)
    }
}

/// A run's MCAP file being written.
pub struct Fixture {
    mcap: mcap::Writer<Shared>,
    file: Shared,
    schemas: HashMap<String, u16>,
    channels: HashMap<String, (u16, u32)>,
}

impl Fixture {
    /// Starts a file with the `tilth.run` and `tilth.experiment` metadata records.
    pub fn new(run: &[(&str, &str)], experiment: &[(&str, &str)]) -> Fixture {
        let file = Shared::default();
        let mut mcap = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .compression_threads(0)
            // Chunks close on `flush` only, as the runner's do after `flush_frames` frames.
            .chunk_size(Some(u64::MAX))
            .library("tilth-tools test fixture")
            .create(file.clone())
            .expect("mcap writer");
        for (name, pairs) in [("tilth.run", run), ("tilth.experiment", experiment)] {
            let metadata: BTreeMap<String, String> = pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            mcap.write_metadata(&Metadata {
                name: name.to_string(),
                metadata,
            })
            .expect("metadata");
        }
        Fixture {
            mcap,
            file,
            schemas: HashMap::new(),
            channels: HashMap::new(),
        }
    }

    fn put<M: Encode>(&mut self, topic: &str, unit: Option<&str>, t: f64, msg: &M) {
        let (channel_id, sequence) = match self.channels.get_mut(topic) {
            Some((id, seq)) => {
                *seq += 1;
                (*id, *seq)
            }
            None => {
                let schema = M::get_schema().expect("schema");
                let schema_id = match self.schemas.get(&schema.name) {
                    Some(&id) => id,
                    None => {
                        let id = self
                            .mcap
                            .add_schema(&schema.name, &schema.encoding, &schema.data)
                            .expect("schema");
                        self.schemas.insert(schema.name.clone(), id);
                        id
                    }
                };
                let mut meta = BTreeMap::new();
                if let Some(u) = unit {
                    meta.insert("unit".to_string(), u.to_string());
                }
                let id = self
                    .mcap
                    .add_channel(schema_id, topic, &M::get_message_encoding(), &meta)
                    .expect("channel");
                self.channels.insert(topic.to_string(), (id, 0));
                (id, 0)
            }
        };
        let mut buf = Vec::new();
        msg.encode(&mut buf).expect("encode");
        let ns = (t * 1e9).round() as u64;
        self.mcap
            .write_to_known_channel(
                &MessageHeader {
                    channel_id,
                    sequence,
                    log_time: ns,
                    publish_time: ns,
                },
                &buf,
            )
            .expect("message");
    }

    /// Writes one `/particles` frame at simulated time `t` (s).
    pub fn cloud(&mut self, t: f64, c: &ParticleCloud) {
        let mut data = Vec::with_capacity(28 * c.len());
        for k in 0..c.len() {
            for v in [c.x[k], c.y[k], c.z[k], c.radius[k], c.speed[k]] {
                data.extend_from_slice(&(v as f32).to_le_bytes());
            }
            data.extend_from_slice(&c.id[k].to_le_bytes());
            data.extend_from_slice(&c.material[k].to_le_bytes());
        }
        let field = |name: &str, offset: u32, kind: NumericType| PackedElementField {
            name: name.to_string(),
            offset,
            r#type: kind as i32,
        };
        let ns = (t * 1e9).round() as u64;
        let msg = PointCloud {
            timestamp: Some(Timestamp::new(
                (ns / 1_000_000_000) as u32,
                (ns % 1_000_000_000) as u32,
            )),
            frame_id: "world".to_string(),
            pose: Some(Pose {
                position: Some(Vector3 {
                    x: 0.0,
                    y: 0.0,
                    z: 0.0,
                }),
                orientation: Some(Quaternion {
                    x: 0.0,
                    y: 0.0,
                    z: 0.0,
                    w: 1.0,
                }),
            }),
            point_stride: 28,
            fields: vec![
                field("x", 0, NumericType::Float32),
                field("y", 4, NumericType::Float32),
                field("z", 8, NumericType::Float32),
                field("radius", 12, NumericType::Float32),
                field("speed", 16, NumericType::Float32),
                field("id", 20, NumericType::Uint32),
                field("material", 24, NumericType::Uint32),
            ],
            data: Bytes::from(data),
        };
        self.put("/particles", None, t, &msg);
    }

    /// Writes one record of scalars at simulated time `t` (s): `/scalars/<name>`, value in x.
    pub fn scalars(&mut self, t: f64, values: &[(&str, f64)]) {
        for &(name, v) in values {
            let msg = Vector3 {
                x: v,
                y: 0.0,
                z: 0.0,
            };
            self.put(&format!("/scalars/{name}"), None, t, &msg);
        }
    }

    /// Closes the chunk being written: everything so far survives a crash.
    pub fn flush(&mut self) {
        self.mcap.flush().expect("flush");
    }

    /// The bytes on disk if the run were killed now (SIGKILL: no chunk closed, no summary).
    pub fn killed_now(&self) -> Vec<u8> {
        self.file.0.borrow().get_ref().clone()
    }

    /// Finishes the file (summary section, footer, end magic) and returns its bytes.
    pub fn finish(mut self) -> Vec<u8> {
        self.mcap.finish().expect("finish");
        self.file.0.borrow().get_ref().clone()
    }
}

/// Writes `bytes` to `<target tmp>/reduce-tests/<name>` and returns the path.
pub fn write_file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reduce-tests");
    std::fs::create_dir_all(&dir).expect("test directory");
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("test file");
    path
}
