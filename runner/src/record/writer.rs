//! One writer thread per run: encodes [`Record`]s and writes them to `run.mcap.partial`.
//!
//! The simulation thread only copies state and sends it over a bounded channel
//! ([`QUEUE`] records); when the writer falls behind, the sender waits instead of memory
//! growing. Compression runs on the writer thread itself (`compression_threads(0)`): the
//! `mcap` crate's default of one zstd thread per physical core would ignore the core budget.
//! The caller pins the writer to its run's core through `on_start`.

use super::encode;
use super::snapshot::Record;
use crate::config::WallShape;
use anyhow::{Context, Result, anyhow};
use crossbeam::channel::{Sender, bounded};
use foxglove::Encode;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Compression, WriteOptions};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Records in flight between the simulation and the writer.
const QUEUE: usize = 8;
/// Uncompressed bytes per MCAP chunk (a chunk also closes every `flush_frames` clouds).
const CHUNK_BYTES: u64 = 4 << 20;
/// A chunk is closed at least this often, so a crash loses little.
const FLUSH_PERIOD: Duration = Duration::from_secs(5);

/// What the writer needs to know before the first record.
#[derive(Debug, Clone)]
pub struct RunLayout {
    pub wall_names: Vec<String>,
    pub wall_shapes: Vec<WallShape>,
    /// MCAP metadata records: name -> key/value map (e.g. "tilth.run").
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Units of scalar channels by name (written as channel metadata).
    pub units: BTreeMap<String, String>,
    /// Also write `/spheres`.
    pub spheres: bool,
    /// Close a chunk after this many particle frames.
    pub flush_frames: u32,
}

/// What the writer did, for the run summary and the logging-cost benchmark.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize)]
pub struct RecorderStats {
    pub messages: u64,
    pub particle_frames: u64,
    pub bytes: u64,
    /// Time the writer thread spent encoding, compressing and writing, s.
    pub busy_seconds: f64,
    /// Time the simulation thread spent waiting for a full queue, s.
    pub blocked_seconds: f64,
}

/// A run's MCAP file being written.
pub struct Recorder {
    tx: Option<Sender<Record>>,
    handle: Option<JoinHandle<Result<RecorderStats>>>,
    partial: PathBuf,
    path: PathBuf,
    blocked: Duration,
}

/// `run.mcap` -> `run.mcap.partial`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".partial");
    PathBuf::from(s)
}

impl Recorder {
    /// Creates `<path>.partial` and starts the writer thread, which first runs `on_start`.
    pub fn start(
        path: &Path,
        layout: RunLayout,
        on_start: impl FnOnce() + Send + 'static,
    ) -> Result<Recorder> {
        let partial = partial_path(path);
        let file = File::create(&partial)
            .with_context(|| format!("{}: cannot create", partial.display()))?;
        let (tx, rx) = bounded::<Record>(QUEUE);
        let name = partial.display().to_string();
        let handle = std::thread::Builder::new()
            .name("tilth-mcap".into())
            .spawn(move || {
                on_start();
                let mut w = Writer::new(file, &layout)?;
                for record in rx {
                    w.write(record, &layout)?;
                }
                w.finish()
            })
            .map_err(|e| anyhow!("{name}: cannot start the writer thread: {e}"))?;
        Ok(Recorder {
            tx: Some(tx),
            handle: Some(handle),
            partial,
            path: path.to_path_buf(),
            blocked: Duration::ZERO,
        })
    }

    /// Hands a record to the writer, waiting if it is [`QUEUE`] records behind.
    pub fn send(&mut self, record: Record) -> Result<()> {
        let t = Instant::now();
        let sent = self.tx.as_ref().map(|tx| tx.send(record));
        self.blocked += t.elapsed();
        match sent {
            Some(Ok(())) => Ok(()),
            // The writer stopped early: its error comes out of `finish`.
            _ => self.join().map(|_| ()).and(Err(anyhow!(
                "{}: the writer stopped",
                self.partial.display()
            ))),
        }
    }

    fn join(&mut self) -> Result<RecorderStats> {
        self.tx = None;
        let handle = self
            .handle
            .take()
            .ok_or_else(|| anyhow!("{}: writer already joined", self.partial.display()))?;
        let mut stats = handle
            .join()
            .map_err(|_| anyhow!("{}: the writer thread panicked", self.partial.display()))?
            .with_context(|| self.partial.display().to_string())?;
        stats.blocked_seconds = self.blocked.as_secs_f64();
        Ok(stats)
    }

    /// Writes the summary section and, if `complete`, renames `<path>.partial` to `<path>`.
    /// An interrupted run keeps the `.partial` name: the file is valid but incomplete.
    pub fn finish(mut self, complete: bool) -> Result<RecorderStats> {
        let stats = self.join()?;
        if complete {
            std::fs::rename(&self.partial, &self.path).with_context(|| {
                format!(
                    "cannot rename {} to {}",
                    self.partial.display(),
                    self.path.display()
                )
            })?;
        }
        Ok(stats)
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.handle.is_some() {
            let _ = self.join();
        }
    }
}

/// The writer thread's state.
struct Writer {
    mcap: mcap::Writer<BufWriter<File>>,
    schemas: HashMap<String, u16>,
    channels: HashMap<String, (u16, u32)>,
    stats: RecorderStats,
    clouds_since_flush: u32,
    last_flush: Instant,
    busy: Duration,
    /// Particle centres by id, from the last particle frame (for bond lines).
    centres: HashMap<u32, [f64; 3]>,
}

impl Writer {
    fn new(file: File, layout: &RunLayout) -> Result<Writer> {
        let mut mcap = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .compression_threads(0)
            .chunk_size(Some(CHUNK_BYTES))
            .library(concat!("tilth ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))?;
        for (name, map) in &layout.metadata {
            mcap.write_metadata(&Metadata {
                name: name.clone(),
                metadata: map.clone(),
            })?;
        }
        Ok(Writer {
            mcap,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            stats: RecorderStats::default(),
            clouds_since_flush: 0,
            last_flush: Instant::now(),
            busy: Duration::ZERO,
            centres: HashMap::new(),
        })
    }

    /// Writes one message of type `M` on `topic`, adding schema and channel on first use.
    fn put<M: Encode>(
        &mut self,
        topic: &str,
        unit: Option<&str>,
        time: f64,
        msg: &M,
    ) -> Result<()> {
        let (channel_id, sequence) = match self.channels.get_mut(topic) {
            Some((id, seq)) => {
                *seq += 1;
                (*id, *seq)
            }
            None => {
                let schema = M::get_schema().ok_or_else(|| anyhow!("{topic}: no schema"))?;
                let schema_id = match self.schemas.get(&schema.name) {
                    Some(&id) => id,
                    None => {
                        let id =
                            self.mcap
                                .add_schema(&schema.name, &schema.encoding, &schema.data)?;
                        self.schemas.insert(schema.name.clone(), id);
                        id
                    }
                };
                let mut meta = BTreeMap::new();
                if let Some(u) = unit {
                    meta.insert("unit".to_string(), u.to_string());
                }
                let id =
                    self.mcap
                        .add_channel(schema_id, topic, &M::get_message_encoding(), &meta)?;
                self.channels.insert(topic.to_string(), (id, 0));
                (id, 0)
            }
        };
        let mut buf = Vec::with_capacity(msg.encoded_len().unwrap_or(64));
        msg.encode(&mut buf)
            .map_err(|e| anyhow!("{topic}: cannot encode: {e}"))?;
        let t = encode::time_ns(time);
        self.mcap.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence,
                log_time: t,
                publish_time: t,
            },
            &buf,
        )?;
        self.stats.messages += 1;
        self.stats.bytes += buf.len() as u64;
        Ok(())
    }

    fn write(&mut self, record: Record, layout: &RunLayout) -> Result<()> {
        let start = Instant::now();
        match record {
            Record::Particles {
                time,
                count: _,
                points,
            } => {
                if layout.spheres {
                    let s = encode::spheres(time, &points);
                    self.put("/spheres", None, time, &s)?;
                }
                // Bond lines need the centres of the last particle frame.
                self.centres = points
                    .chunks_exact(super::snapshot::POINT_STRIDE)
                    .map(|q| {
                        let f = |k: usize| {
                            f32::from_le_bytes([q[k], q[k + 1], q[k + 2], q[k + 3]]) as f64
                        };
                        let id = u32::from_le_bytes([q[20], q[21], q[22], q[23]]);
                        (id, [f(0), f(4), f(8)])
                    })
                    .collect();
                let cloud = encode::point_cloud(time, points);
                self.put("/particles", None, time, &cloud)?;
                self.stats.particle_frames += 1;
                self.clouds_since_flush += 1;
            }
            Record::Walls {
                time,
                offsets,
                forces,
                torques,
            } => {
                let scene = encode::walls(time, &layout.wall_names, &layout.wall_shapes, &offsets);
                self.put("/walls", None, time, &scene)?;
                for (k, name) in layout.wall_names.iter().enumerate() {
                    let f = encode::vector3(forces[k]);
                    self.put(&format!("/walls/{name}/force"), Some("N"), time, &f)?;
                    let m = encode::vector3(torques[k]);
                    self.put(&format!("/walls/{name}/torque"), Some("N m"), time, &m)?;
                }
            }
            Record::Bonds { time, points } => {
                let lines = encode::bond_lines(time, &points, &self.centres);
                self.put("/bonds/lines", None, time, &lines)?;
                let cloud = encode::bond_cloud(time, points);
                self.put("/bonds", None, time, &cloud)?;
            }
            Record::Scalars { time, values } => {
                for (name, v) in values {
                    let unit = layout.units.get(&name).map(String::as_str);
                    self.put(&format!("/scalars/{name}"), unit, time, &encode::scalar(v))?;
                }
            }
        }
        if self.clouds_since_flush >= layout.flush_frames
            || self.last_flush.elapsed() >= FLUSH_PERIOD
        {
            // Close the chunk: everything up to here survives a crash.
            self.mcap.flush()?;
            self.clouds_since_flush = 0;
            self.last_flush = Instant::now();
        }
        self.busy += start.elapsed();
        Ok(())
    }

    fn finish(mut self) -> Result<RecorderStats> {
        let start = Instant::now();
        self.mcap.finish()?;
        self.busy += start.elapsed();
        self.stats.busy_seconds = self.busy.as_secs_f64();
        Ok(self.stats)
    }
}
