//! MCAP logging on a writer thread.
//!
//! The control loop serializes each message to JSON into a buffer taken from a pool of preallocated
//! buffers and hands it to a bounded channel; a dedicated thread writes it into a chunked, compressed
//! MCAP file ([`crate::mcap_file`]) and returns the buffer to the pool. Every message that can be in flight owns a buffer from
//! the start, sized above the largest per-tick message, so nothing allocates on the loop side. If the writer ever falls behind by `queue_capacity` messages the loop
//! waits for it (logs stay complete and deterministic) and the wait is counted in [`LogStats::stalls`].
//!
//! Schemas are JSON Schema (`jsonschema`), messages JSON (`json`); see docs/logging.md for why. `/tf` uses
//! the exact `foxglove.FrameTransforms` schema. Each topic's schema is either given when the topic is
//! registered or derived from the first message written to it.
//!
//! [`LogWriter`] finishes the file when dropped, so a run that ends by an error or a panic (the loop runs
//! inside `catch_unwind`, the writer outside it) still leaves a valid file.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::thread::JoinHandle;

use serde::Serialize;

use crate::config::Compression;
use crate::mcap_file::{McapFile, ZstdParameters};

/// Why the log could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// File system error.
    #[error("log file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// OS error.
        source: std::io::Error,
    },
    /// The MCAP library failed.
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be serialized.
    #[error("serializing a message for topic {topic}: {source}")]
    Serialize {
        /// The topic.
        topic: String,
        /// serde_json's error.
        source: serde_json::Error,
    },
    /// The writer thread stopped early (its error is reported when the log is finished).
    #[error("the log writer thread stopped")]
    WriterGone,
    /// The log does not hold what was asked for.
    #[error("{0}")]
    Content(String),
}

/// Options of a log file.
#[derive(Debug, Clone)]
pub struct LogOptions {
    /// Chunk compression.
    pub compression: Compression,
    /// Target uncompressed chunk size \[bytes\].
    pub chunk_size: u64,
    /// Bounded queue length between loop and writer \[messages\]; `queue_capacity + 2` buffers of
    /// [`POOLED_BUFFER_BYTES`] are preallocated.
    pub queue_capacity: usize,
}

impl Default for LogOptions {
    fn default() -> Self {
        Self {
            compression: Compression::Zstd,
            chunk_size: DEFAULT_CHUNK_BYTES,
            queue_capacity: 1024,
        }
    }
}

/// Default target size of a chunk before compression \[bytes\]: 1 MiB, the window of the chunks' zstd
/// parameters ([`ZstdParameters`]); each chunk is compressed in one call once complete, so a chunk that
/// fits in the window is matched against all of itself (docs/performance.md, "The log's compression").
pub const DEFAULT_CHUNK_BYTES: u64 = 1 << 20;

/// Handle of a registered topic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TopicId(u16);

enum Msg {
    Topic {
        id: u16,
        topic: String,
        schema_name: String,
        schema: Option<String>,
    },
    Message {
        id: u16,
        sequence: u32,
        time_ns: u64,
        buf: Vec<u8>,
    },
    Attachment {
        name: String,
        media_type: String,
        data: Vec<u8>,
    },
    Metadata {
        name: String,
        entries: BTreeMap<String, String>,
    },
}

/// Counters of a finished log.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct LogStats {
    /// Messages written.
    pub messages: u64,
    /// Times the loop had to wait for the writer.
    pub stalls: u64,
    /// File size \[bytes\].
    pub bytes: u64,
}

/// The loop-side handle of a log being written.
pub struct LogWriter {
    path: PathBuf,
    tx: Option<SyncSender<Msg>>,
    pool: Receiver<Vec<u8>>,
    thread: Option<JoinHandle<Result<u64, LogError>>>,
    sequences: Vec<u32>,
    topics: Vec<String>,
    messages: u64,
    stalls: u64,
    finished: Option<Result<LogStats, String>>,
}

impl LogWriter {
    /// Creates the file and starts the writer thread.
    pub fn create(path: &Path, options: &LogOptions) -> Result<Self, LogError> {
        if let Some(dir) = path.parent() {
            if !dir.as_os_str().is_empty() {
                std::fs::create_dir_all(dir).map_err(|e| LogError::Io {
                    path: path.to_path_buf(),
                    source: e,
                })?;
            }
        }
        let file = File::create(path).map_err(|e| LogError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let writer = McapFile::create(
            BufWriter::with_capacity(1 << 16, file),
            options.compression,
            &ZstdParameters::default(),
            options.chunk_size,
            concat!("stride-", env!("CARGO_PKG_VERSION")),
        )
        .map_err(|e| LogError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let capacity = options.queue_capacity.max(1);
        let (tx, rx) = mpsc::sync_channel::<Msg>(capacity);
        // (queued messages + the one the writer holds + the one the loop is serializing)
        let (pool_tx, pool_rx) = mpsc::sync_channel::<Vec<u8>>(capacity + 2);
        // Every message the loop may have in flight owns a preallocated buffer, large enough for any per-tick
        // message: the loop never allocates one nor grows one, whatever the writer's timing. (With 1 KB
        // buffers and a smaller pool, buffers grew or were created on the loop thread for seconds, each
        // time the writer paused to compress a chunk.)
        for _ in 0..capacity + 2 {
            let _ = pool_tx.try_send(Vec::with_capacity(POOLED_BUFFER_BYTES));
        }
        let thread_path = path.to_path_buf();
        let thread = std::thread::Builder::new()
            .name("stride-log".into())
            .spawn(move || writer_thread(writer, rx, pool_tx, thread_path))
            .map_err(|e| LogError::Io {
                path: path.to_path_buf(),
                source: e,
            })?;
        Ok(Self {
            path: path.to_path_buf(),
            tx: Some(tx),
            pool: pool_rx,
            thread: Some(thread),
            sequences: Vec::new(),
            topics: Vec::new(),
            messages: 0,
            stalls: 0,
            finished: None,
        })
    }

    /// Path of the file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn send(&mut self, msg: Msg) -> Result<(), LogError> {
        let tx = self.tx.as_ref().ok_or(LogError::WriterGone)?;
        match tx.try_send(msg) {
            Ok(()) => Ok(()),
            Err(TrySendError::Full(msg)) => {
                self.stalls += 1;
                tx.send(msg).map_err(|_| LogError::WriterGone)
            }
            Err(TrySendError::Disconnected(_)) => Err(LogError::WriterGone),
        }
    }

    /// Registers a topic. `schema` is a JSON Schema text; `None` derives one from the first message.
    pub fn topic(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: Option<String>,
    ) -> Result<TopicId, LogError> {
        let id = u16::try_from(self.topics.len())
            .map_err(|_| LogError::Content("more than 65535 topics".into()))?;
        self.topics.push(topic.to_string());
        self.sequences.push(0);
        self.send(Msg::Topic {
            id,
            topic: topic.into(),
            schema_name: schema_name.into(),
            schema,
        })?;
        Ok(TopicId(id))
    }

    /// The id of an already registered topic, registering it (schema from the first message) if new.
    pub fn topic_id(&mut self, topic: &str) -> Result<TopicId, LogError> {
        match self.topics.iter().position(|t| t == topic) {
            Some(i) => Ok(TopicId(i as u16)),
            None => self.topic(topic, &format!("stride{}", topic.replace('/', ".")), None),
        }
    }

    /// Serializes `value` as JSON and queues it on `topic` at simulated time `time_ns`.
    pub fn write<T: Serialize + ?Sized>(
        &mut self,
        topic: TopicId,
        time_ns: u64,
        value: &T,
    ) -> Result<(), LogError> {
        self.write_encoded(topic, time_ns, |buf| serde_json::to_writer(buf, value))
    }

    /// Queues on `topic` at simulated time `time_ns` the JSON that `encode` appends to the (empty) message
    /// buffer: for the messages written without serde's dispatch, byte for byte what [`LogWriter::write`]
    /// writes for the same value.
    pub fn write_encoded(
        &mut self,
        topic: TopicId,
        time_ns: u64,
        encode: impl FnOnce(&mut Vec<u8>) -> Result<(), serde_json::Error>,
    ) -> Result<(), LogError> {
        let mut buf = self.pool.try_recv().unwrap_or_default();
        buf.clear();
        if let Err(source) = encode(&mut buf) {
            return Err(LogError::Serialize {
                topic: self.topics[usize::from(topic.0)].clone(),
                source,
            });
        }
        let seq = &mut self.sequences[usize::from(topic.0)];
        *seq = seq.wrapping_add(1);
        let sequence = *seq;
        self.messages += 1;
        self.send(Msg::Message {
            id: topic.0,
            sequence,
            time_ns,
            buf,
        })
    }

    /// Stores a file (URDF, config, ...) in the log.
    pub fn attach(&mut self, name: &str, media_type: &str, data: Vec<u8>) -> Result<(), LogError> {
        self.send(Msg::Attachment {
            name: name.into(),
            media_type: media_type.into(),
            data,
        })
    }

    /// Stores a metadata record (string map).
    pub fn metadata(
        &mut self,
        name: &str,
        entries: BTreeMap<String, String>,
    ) -> Result<(), LogError> {
        self.send(Msg::Metadata {
            name: name.into(),
            entries,
        })
    }

    /// Flushes everything, writes the summary and closes the file. Idempotent.
    pub fn finish(&mut self) -> Result<LogStats, LogError> {
        if let Some(done) = &self.finished {
            return done.clone().map_err(LogError::Content);
        }
        self.tx = None; // closes the channel: the thread drains it and finishes the file
        let result = match self.thread.take() {
            Some(t) => match t.join() {
                Ok(Ok(bytes)) => Ok(LogStats {
                    messages: self.messages,
                    stalls: self.stalls,
                    bytes,
                }),
                Ok(Err(e)) => Err(e.to_string()),
                Err(_) => Err("the log writer thread panicked".to_string()),
            },
            None => Err("the log writer was already stopped".to_string()),
        };
        self.finished = Some(result.clone());
        result.map_err(LogError::Content)
    }
}

impl Drop for LogWriter {
    fn drop(&mut self) {
        if self.finished.is_none() {
            if let Err(e) = self.finish() {
                tracing::error!("closing log {}: {e}", self.path.display());
            }
        }
    }
}

fn writer_thread(
    mut w: McapFile<BufWriter<File>>,
    rx: Receiver<Msg>,
    pool: SyncSender<Vec<u8>>,
    path: PathBuf,
) -> Result<u64, LogError> {
    let io = |source: std::io::Error| LogError::Io {
        path: path.clone(),
        source,
    };
    // Topic id → (mcap channel id, pending registration when the schema is derived from data).
    let mut channels: Vec<Option<u16>> = Vec::new();
    let mut pending: BTreeMap<u16, (String, String)> = BTreeMap::new();
    let mut first_error: Option<LogError> = None;
    for msg in rx.iter() {
        let r: Result<(), LogError> = (|| {
            match msg {
                Msg::Topic {
                    id,
                    topic,
                    schema_name,
                    schema,
                } => {
                    let idx = usize::from(id);
                    if channels.len() <= idx {
                        channels.resize(idx + 1, None);
                    }
                    match schema {
                        Some(s) => {
                            let sid = w
                                .add_schema(&schema_name, "jsonschema", s.as_bytes())
                                .map_err(io)?;
                            channels[idx] = Some(w.add_channel(sid, &topic, "json").map_err(io)?);
                        }
                        None => {
                            pending.insert(id, (topic, schema_name));
                        }
                    }
                }
                Msg::Message {
                    id,
                    sequence,
                    time_ns,
                    buf,
                } => {
                    let idx = usize::from(id);
                    if channels.get(idx).copied().flatten().is_none() {
                        if let Some((topic, schema_name)) = pending.remove(&id) {
                            let value: serde_json::Value =
                                serde_json::from_slice(&buf).map_err(|e| LogError::Serialize {
                                    topic: topic.clone(),
                                    source: e,
                                })?;
                            let schema = schema_from_example(&value, &schema_name);
                            let sid = w
                                .add_schema(
                                    &schema_name,
                                    "jsonschema",
                                    schema.to_string().as_bytes(),
                                )
                                .map_err(io)?;
                            if channels.len() <= idx {
                                channels.resize(idx + 1, None);
                            }
                            channels[idx] = Some(w.add_channel(sid, &topic, "json").map_err(io)?);
                        }
                    }
                    let channel_id = channels.get(idx).copied().flatten().ok_or_else(|| {
                        LogError::Content(format!("message for unregistered topic {id}"))
                    })?;
                    w.write_message(channel_id, sequence, time_ns, time_ns, &buf)
                        .map_err(io)?;
                    let _ = pool.try_send(buf);
                }
                Msg::Attachment {
                    name,
                    media_type,
                    data,
                } => {
                    w.attach(0, 0, &name, &media_type, &data).map_err(io)?;
                }
                Msg::Metadata { name, entries } => {
                    w.write_metadata(&name, &entries).map_err(io)?;
                }
            }
            Ok(())
        })();
        if let Err(e) = r {
            tracing::error!("log writer: {e}");
            if first_error.is_none() {
                first_error = Some(e);
            }
        }
    }
    let mut inner = w.finish().map_err(io)?;
    inner.flush().map_err(io)?;
    drop(inner);
    if let Some(e) = first_error {
        return Err(e);
    }
    let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    Ok(bytes)
}

/// A JSON Schema (draft 2020-12) describing `example`'s shape: objects with their properties, arrays
/// with the item schema of their first element, numbers, strings, booleans; `null` accepts anything.
pub fn schema_from_example(example: &serde_json::Value, title: &str) -> serde_json::Value {
    let mut s = schema_of(example);
    if let serde_json::Value::Object(m) = &mut s {
        m.insert(
            "$schema".into(),
            "https://json-schema.org/draft/2020-12/schema".into(),
        );
        m.insert("title".into(), title.into());
    }
    s
}

fn schema_of(v: &serde_json::Value) -> serde_json::Value {
    use serde_json::{json, Value};
    match v {
        Value::Null => json!({}),
        Value::Bool(_) => json!({"type": "boolean"}),
        Value::Number(n) if n.is_u64() || n.is_i64() => json!({"type": "number"}),
        Value::Number(_) => json!({"type": "number"}),
        Value::String(_) => json!({"type": "string"}),
        Value::Array(a) => match a.first() {
            Some(first) => json!({"type": "array", "items": schema_of(first)}),
            None => json!({"type": "array"}),
        },
        Value::Object(m) => {
            let props: serde_json::Map<String, Value> =
                m.iter().map(|(k, v)| (k.clone(), schema_of(v))).collect();
            json!({"type": "object", "properties": props})
        }
    }
}

/// Capacity of each pooled buffer \[bytes\]: above the largest per-tick message (`/tf` of a 33-body model
/// ≈ 10 KB, `/wbc/input` ≈ 3 KB). A rarer, larger message (`/tf_static` of a model with hundreds of frames)
/// grows the buffer it lands in once. The pool holds `queue_capacity + 2` of them (16 MB by default).
pub const POOLED_BUFFER_BYTES: usize = 16 * 1024;

/// The JSON Schema of `foxglove.FrameTransforms` (Foxglove's published schema, JSON encoding).
pub const FRAME_TRANSFORMS_SCHEMA: &str = r#"{
  "title": "foxglove.FrameTransforms",
  "description": "An array of FrameTransform messages",
  "$comment": "Generated by https://github.com/foxglove/foxglove-sdk",
  "type": "object",
  "properties": {
    "transforms": {
      "type": "array",
      "items": {
        "title": "foxglove.FrameTransform",
        "description": "A transform between two reference frames in 3D space",
        "type": "object",
        "properties": {
          "timestamp": {
            "type": "object",
            "title": "time",
            "properties": {
              "sec": {"type": "integer", "minimum": 0},
              "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}
            },
            "description": "Timestamp of transform"
          },
          "parent_frame_id": {"type": "string", "description": "Name of the parent frame"},
          "child_frame_id": {"type": "string", "description": "Name of the child frame"},
          "translation": {
            "title": "foxglove.Vector3",
            "description": "Translation component of the transform",
            "type": "object",
            "properties": {
              "x": {"type": "number", "description": "x coordinate length"},
              "y": {"type": "number", "description": "y coordinate length"},
              "z": {"type": "number", "description": "z coordinate length"}
            }
          },
          "rotation": {
            "title": "foxglove.Quaternion",
            "description": "Rotation component of the transform",
            "type": "object",
            "properties": {
              "x": {"type": "number", "description": "x value"},
              "y": {"type": "number", "description": "y value"},
              "z": {"type": "number", "description": "z value"},
              "w": {"type": "number", "description": "w value"}
            }
          }
        }
      },
      "description": "Array of transforms"
    }
  }
}"#;

/// A Foxglove `time` value.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Eq, Default)]
pub struct FoxgloveTime {
    /// Seconds.
    pub sec: u32,
    /// Nanoseconds.
    pub nsec: u32,
}

impl FoxgloveTime {
    /// From an integer nanosecond count.
    pub fn from_ns(ns: u64) -> Self {
        Self {
            sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `foxglove.Vector3`.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Default)]
pub struct FoxgloveVector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `foxglove.Quaternion`.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Default)]
pub struct FoxgloveQuaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// `foxglove.FrameTransform`.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct FrameTransform {
    /// Time of the transform.
    pub timestamp: FoxgloveTime,
    /// Parent frame (`world`).
    pub parent_frame_id: String,
    /// Child frame (a link name).
    pub child_frame_id: String,
    /// Translation \[m\].
    pub translation: FoxgloveVector3,
    /// Rotation.
    pub rotation: FoxgloveQuaternion,
}

/// `foxglove.FrameTransforms`.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct FrameTransforms {
    /// The transforms.
    pub transforms: Vec<FrameTransform>,
}

/// One message read back from a log.
#[derive(Debug, Clone)]
pub struct LoggedMessage {
    /// Topic.
    pub topic: String,
    /// Log time \[ns\].
    pub time_ns: u64,
    /// JSON payload.
    pub data: Vec<u8>,
}

/// Everything in a log file, read with the mcap crate's reader.
#[derive(Debug, Clone, Default)]
pub struct LogContents {
    /// Messages in file order.
    pub messages: Vec<LoggedMessage>,
    /// Attachments by name.
    pub attachments: BTreeMap<String, Vec<u8>>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Schemas by topic: (schema name, encoding, schema text).
    pub schemas: BTreeMap<String, (String, String, String)>,
}

impl LogContents {
    /// Messages on one topic, in order.
    pub fn topic<'a>(&'a self, topic: &'a str) -> impl Iterator<Item = &'a LoggedMessage> + 'a {
        self.messages.iter().filter(move |m| m.topic == topic)
    }
}

/// Reads a whole MCAP file: messages (through the summary-less linear reader, so files of interrupted
/// runs that still have their footer read the same way), attachments and metadata.
pub fn read_log(path: &Path) -> Result<LogContents, LogError> {
    read_log_topics(path, |_| true)
}

/// [`read_log`] keeping only the messages (and schemas) of the topics `keep` accepts; attachments and
/// metadata are read whole. A tool that needs two topics of a long log holds those alone in memory.
pub fn read_log_topics(path: &Path, keep: impl Fn(&str) -> bool) -> Result<LogContents, LogError> {
    let bytes = std::fs::read(path).map_err(|e| LogError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let mut out = LogContents::default();
    for m in mcap::MessageStream::new(&bytes)? {
        let m = m?;
        if !keep(&m.channel.topic) {
            continue;
        }
        let topic = m.channel.topic.clone();
        if !out.schemas.contains_key(&topic) {
            if let Some(s) = &m.channel.schema {
                out.schemas.insert(
                    topic.clone(),
                    (
                        s.name.clone(),
                        s.encoding.clone(),
                        String::from_utf8_lossy(&s.data).into_owned(),
                    ),
                );
            }
        }
        out.messages.push(LoggedMessage {
            topic,
            time_ns: m.log_time,
            data: m.data.into_owned(),
        });
    }
    for rec in mcap::read::LinearReader::new(&bytes)? {
        match rec? {
            mcap::records::Record::Attachment { header, data, .. } => {
                out.attachments
                    .insert(header.name.clone(), data.into_owned());
            }
            mcap::records::Record::Metadata(m) => {
                out.metadata.insert(m.name.clone(), m.metadata.clone());
            }
            _ => {}
        }
    }
    Ok(out)
}
