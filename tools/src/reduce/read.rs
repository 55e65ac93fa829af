//! Reads a run's MCAP file, complete or cut short, into what the reducers need.
//!
//! The file is streamed once, front to back, with the `mcap` crate's sans-io
//! [`LinearReader`], so a file of many gigabytes is read in constant memory and a file that
//! ends in the middle of a record (a run killed with SIGKILL: `run.mcap.partial`) is read up
//! to the point where it breaks. Two choices make a truncated file safe to reduce:
//!
//! - Chunks are checked against their CRC *before* any message in them is handed out
//!   (`prevalidate_chunk_crcs`), so the numbers come from whole chunks only. The runner
//!   writes a chunk in place and fills in its header when it closes it; the chunk open at a
//!   crash still has the placeholder header and is skipped as a whole.
//! - No record may be longer than [`RECORD_LIMIT`] or the file, whichever is longer
//!   (`record_length_limit`; a chunk's records, decompressed, may be longer than the whole
//!   file), so a placeholder or corrupt length is an error, never an attempt to allocate it.
//!   The placeholder header of an open chunk (lengths `u64::MAX`) is refused before that.
//!
//! A file is [`Completeness::complete`] only if the stream ends with the MCAP end magic and
//! its name does not end in `.partial`: an interrupted run (SIGINT/SIGTERM) writes a valid
//! file but keeps the `.partial` name (runner/MCAP.md), and its numbers are not a finished
//! test's either.

use super::cloud::ParticleCloud;
use super::error::ReduceError;
use super::series::Series;
use foxglove::messages::{PointCloud, Vector3};
use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use prost::Message as _;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Topic of the particle frames.
pub const PARTICLES: &str = "/particles";
/// Prefix of the scalar channels; the rest of the topic is the scalar's name.
pub const SCALARS: &str = "/scalars/";
/// Metadata record written by every run (run id, seed, `factor.<name>`, ...).
pub const RUN_RECORD: &str = "tilth.run";
/// Metadata record that describes the experiment (`type` and its dimensions).
pub const EXPERIMENT_RECORD: &str = "tilth.experiment";

/// Longest record the reader accepts, bytes, unless the file is longer: far above the
/// runner's chunks (4 MiB plus at most `flush_frames` particle frames of about 1 MB each).
pub const RECORD_LIMIT: u64 = 1 << 30;

/// Largest read handed to the MCAP reader at once, bytes: bounds the buffer whatever
/// length a (possibly corrupt) record header claims.
const READ_BLOCK: usize = 1 << 20;

/// Which `/particles` frame to decode (decoding every frame of a long run would cost
/// seconds and gigabytes; only the chosen one is decoded).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum CloudChoice {
    /// No frame (shear and compression reducers need only scalars).
    None,
    /// The last frame in the readable part of the file: the final state.
    #[default]
    Last,
    /// The frame with this 0-based index.
    Index(usize),
    /// The last frame whose time is at or before this simulated time, s.
    AtOrBefore(f64),
}

/// What to read besides the metadata and the scalar channels (always read).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReadOptions {
    pub cloud: CloudChoice,
}

/// Whether the numbers come from a finished run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Completeness {
    pub complete: bool,
    /// Why the file is not complete; `None` when it is.
    pub reason: Option<String>,
}

/// The file a result came from and whether it was complete; flattened into every result, so
/// each result's JSON carries `file`, `complete` and `incomplete_reason`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunSource {
    pub file: String,
    pub complete: bool,
    pub incomplete_reason: Option<String>,
}

/// A run's file as read.
#[derive(Debug, Clone)]
pub struct Run {
    pub path: PathBuf,
    /// `path` as text, the name every message and result uses.
    pub file: String,
    pub completeness: Completeness,
    /// Metadata records by name (`tilth.run`, `tilth.experiment`, ...), each a key/value map.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// `/scalars/<name>` channels by `<name>`, value in the message's `x`.
    pub scalars: BTreeMap<String, Series>,
    /// The chosen `/particles` frame, if asked for and present.
    pub cloud: Option<ParticleCloud>,
    /// Number of `/particles` frames in the readable part of the file.
    pub cloud_frames: usize,
    /// Log time of the last message read, s.
    pub last_time_s: Option<f64>,
}

impl Run {
    /// The `file` / `complete` / `incomplete_reason` block of a result.
    pub fn source(&self) -> RunSource {
        RunSource {
            file: self.file.clone(),
            complete: self.completeness.complete,
            incomplete_reason: self.completeness.reason.clone(),
        }
    }

    /// The value of `key` in metadata record `record`.
    pub fn metadata_value(&self, record: &str, key: &str) -> Result<&str, ReduceError> {
        self.metadata
            .get(record)
            .and_then(|m| m.get(key))
            .map(String::as_str)
            .ok_or_else(|| ReduceError::MissingMetadata {
                file: self.file.clone(),
                record: record.to_string(),
                key: key.to_string(),
            })
    }

    /// The value of `key` in metadata record `record` as a finite number.
    pub fn metadata_number(&self, record: &str, key: &str) -> Result<f64, ReduceError> {
        let text = self.metadata_value(record, key)?;
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| ReduceError::BadMetadata {
                file: self.file.clone(),
                record: record.to_string(),
                key: key.to_string(),
                value: text.to_string(),
            })
    }

    /// A number from the `tilth.experiment` record.
    pub fn experiment_number(&self, key: &str) -> Result<f64, ReduceError> {
        self.metadata_number(EXPERIMENT_RECORD, key)
    }

    /// Refuses a file whose `tilth.experiment` `type` is not `expected`.
    pub fn expect_experiment(&self, expected: &'static str) -> Result<(), ReduceError> {
        let found = self.metadata_value(EXPERIMENT_RECORD, "type")?;
        if found == expected {
            Ok(())
        } else {
            Err(ReduceError::WrongExperiment {
                file: self.file.clone(),
                expected,
                found: found.to_string(),
            })
        }
    }

    /// The `/scalars/<name>` series, or an error naming the topic.
    pub fn scalar(&self, name: &str) -> Result<&Series, ReduceError> {
        self.scalars
            .get(name)
            .filter(|s| !s.is_empty())
            .ok_or_else(|| ReduceError::MissingTopic {
                file: self.file.clone(),
                topic: format!("{SCALARS}{name}"),
            })
    }

    /// The chosen particle frame, or an error naming the topic.
    pub fn cloud(&self) -> Result<&ParticleCloud, ReduceError> {
        self.cloud
            .as_ref()
            .ok_or_else(|| ReduceError::MissingTopic {
                file: self.file.clone(),
                topic: PARTICLES.to_string(),
            })
    }
}

/// What a channel carries, as far as the reader cares.
#[derive(Clone)]
enum Kind {
    Particles,
    Scalar(String),
    Other,
}

/// Reads `path` (see the module documentation for truncated files).
///
/// Errors only when nothing usable can be read (the file cannot be opened, does not start
/// with an MCAP header) or when a channel this reader decodes breaks the contract (wrong
/// schema, undecodable message, bad point layout). A file that breaks off later is returned
/// with `completeness.complete == false` and the reason.
pub fn read_run(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Run, ReduceError> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let io = |cause| ReduceError::Io {
        file: file.clone(),
        cause,
    };
    let mut f = File::open(path).map_err(io)?;
    let size = f.metadata().map_err(io)?.len();
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(
                usize::try_from(size.max(RECORD_LIMIT)).unwrap_or(usize::MAX),
            ),
    );
    let mut stream = Stream::new(path, &file, options.cloud);
    let mut broken: Option<String> = None;

    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(source) if !stream.seen_header => {
                return Err(ReduceError::NotMcap {
                    file,
                    cause: source,
                });
            }
            Err(e) => {
                broken = Some(e.to_string());
                break;
            }
        };
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need.clamp(1, READ_BLOCK));
                let got = f.read(buf).map_err(io)?;
                reader.notify_read(got);
                continue;
            }
            LinearReadEvent::Record { opcode, data } => (opcode, data),
        };
        let record = match mcap::parse_record(opcode, data) {
            Ok(r) => r,
            Err(cause) if !stream.seen_header => {
                return Err(ReduceError::NotMcap { file, cause });
            }
            Err(e) => {
                broken = Some(e.to_string());
                break;
            }
        };
        stream.take(record)?;
    }

    let Stream {
        mut run, chosen, ..
    } = stream;
    run.completeness = completeness(path, broken, size, run.last_time_s);
    if let Some((t, bytes)) = chosen {
        run.cloud = Some(decode_cloud(file, t, &bytes)?);
    }
    Ok(run)
}

/// What the records read so far have given: the channels known and the run being filled.
struct Stream<'a> {
    file: &'a str,
    cloud: CloudChoice,
    /// Schema names by id.
    schemas: HashMap<u16, String>,
    channels: HashMap<u16, Kind>,
    run: Run,
    /// The raw bytes of the chosen frame so far, with its log time; decoded once at the end.
    chosen: Option<(u64, Vec<u8>)>,
    /// Whether the MCAP header has been read: a failure before it means no MCAP file.
    seen_header: bool,
}

impl<'a> Stream<'a> {
    fn new(path: &Path, file: &'a str, cloud: CloudChoice) -> Stream<'a> {
        Stream {
            file,
            cloud,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            run: Run {
                path: path.to_path_buf(),
                file: file.to_string(),
                completeness: Completeness {
                    complete: true,
                    reason: None,
                },
                metadata: BTreeMap::new(),
                scalars: BTreeMap::new(),
                cloud: None,
                cloud_frames: 0,
                last_time_s: None,
            },
            chosen: None,
            seen_header: false,
        }
    }

    /// Takes in one record: the header, a schema, a channel (refused if it breaks the
    /// contract), a metadata record or a message; the rest is skipped.
    fn take(&mut self, record: Record<'_>) -> Result<(), ReduceError> {
        match record {
            Record::Header(_) => self.seen_header = true,
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(ch) => {
                let schema = self.schemas.get(&ch.schema_id).cloned().unwrap_or_default();
                let kind = classify(self.file, &ch.topic, &schema, &ch.message_encoding)?;
                self.channels.insert(ch.id, kind);
            }
            Record::Metadata(m) => {
                self.run.metadata.insert(m.name, m.metadata);
            }
            Record::Message { header, data } => {
                self.message(header.channel_id, header.log_time, &data)?;
            }
            _ => {}
        }
        Ok(())
    }

    /// One message at log time `t` (ns): a scalar's value appended to its series, a particle
    /// frame counted and its bytes kept if it is the one chosen so far.
    fn message(&mut self, channel: u16, t: u64, data: &[u8]) -> Result<(), ReduceError> {
        let run = &mut self.run;
        run.last_time_s = Some(seconds(t));
        match self.channels.get(&channel) {
            Some(Kind::Scalar(name)) => {
                let v = Vector3::decode(data).map_err(|cause| ReduceError::Decode {
                    file: self.file.to_string(),
                    topic: format!("{SCALARS}{name}"),
                    cause,
                })?;
                let s = run.scalars.entry(name.clone()).or_default();
                s.time_s.push(seconds(t));
                s.value.push(v.x);
            }
            Some(Kind::Particles) => {
                let index = run.cloud_frames;
                run.cloud_frames += 1;
                let keep = match self.cloud {
                    CloudChoice::None => false,
                    CloudChoice::Last => true,
                    CloudChoice::Index(k) => k == index,
                    CloudChoice::AtOrBefore(limit) => seconds(t) <= limit,
                };
                if keep {
                    let slot = self.chosen.get_or_insert_with(|| (t, Vec::new()));
                    slot.0 = t;
                    slot.1.clear();
                    slot.1.extend_from_slice(data);
                }
            }
            Some(Kind::Other) | None => {}
        }
        Ok(())
    }
}

/// Whether a file read to its end, or to `broken` (the error where it broke off), is
/// complete: not if it breaks off, nor if it still has its `.partial` name.
fn completeness(
    path: &Path,
    broken: Option<String>,
    size: u64,
    last_time_s: Option<f64>,
) -> Completeness {
    if let Some(error) = broken {
        Completeness {
            complete: false,
            reason: Some(format!(
                "the file breaks off ({error}) in its {size} bytes: the run was cut short; \
                 read up to its last whole chunk{}",
                match last_time_s {
                    Some(t) => format!(", last message at t = {t} s"),
                    None => String::from(", which holds no message"),
                }
            )),
        }
    } else if path.to_string_lossy().ends_with(".partial") {
        Completeness {
            complete: false,
            reason: Some(
                "the file still has its .partial name: the run was interrupted before it \
                 finished"
                    .to_string(),
            ),
        }
    } else {
        Completeness {
            complete: true,
            reason: None,
        }
    }
}

/// Decodes the chosen `/particles` frame, logged at `t` (ns).
fn decode_cloud(file: String, t: u64, bytes: &[u8]) -> Result<ParticleCloud, ReduceError> {
    let msg = PointCloud::decode(bytes).map_err(|cause| ReduceError::Decode {
        file: file.clone(),
        topic: PARTICLES.to_string(),
        cause,
    })?;
    ParticleCloud::from_point_cloud(&msg, seconds(t))
        .map_err(|problem| ReduceError::CloudLayout { file, problem })
}

/// Nanoseconds of log time -> seconds (a division, so whole seconds come out exact).
fn seconds(ns: u64) -> f64 {
    ns as f64 / 1e9
}

/// Which of the reader's channels `topic` is, refusing one whose schema breaks the contract.
fn classify(file: &str, topic: &str, schema: &str, encoding: &str) -> Result<Kind, ReduceError> {
    let (kind, expected) = if topic == PARTICLES {
        (Kind::Particles, "foxglove.PointCloud")
    } else if let Some(name) = topic.strip_prefix(SCALARS) {
        (Kind::Scalar(name.to_string()), "foxglove.Vector3")
    } else {
        return Ok(Kind::Other);
    };
    if schema != expected || encoding != "protobuf" {
        return Err(ReduceError::Schema {
            file: file.to_string(),
            topic: topic.to_string(),
            found: format!("{schema} ({encoding})"),
            expected,
        });
    }
    Ok(kind)
}
