//! A chunked MCAP file writer (MCAP specification, <https://mcap.dev/spec>) for the log's writer thread.
//!
//! It writes the records the `mcap` crate's writer writes for the same calls (schemas and channels inside
//! the chunks, a message index per channel after each chunk, attachments and metadata between chunks,
//! the summary section with repeated schemas and channels, statistics and the chunk, attachment and
//! metadata indexes, summary offsets, CRCs), with two differences that only change the compressed bytes:
//! a chunk is compressed in one call once it is complete (the `mcap` crate streams each record into the
//! compressor), and zstd runs with the parameters of [`ZstdParameters`], which the `mcap` crate's
//! options (a non-negative level) cannot express. Test: `tests::*` read the file back with the `mcap`
//! crate's reader and compare every record with what its writer writes.

use std::io::{self, Write};

use crate::config::Compression;

const MAGIC: &[u8] = b"\x89MCAP0\r\n";

mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const ATTACHMENT: u8 = 0x09;
    pub const ATTACHMENT_INDEX: u8 = 0x0A;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// Bytes of a message record before its payload: opcode, length, channel, sequence, log and publish time.
const MESSAGE_HEADER_BYTES: usize = 1 + 8 + 2 + 4 + 8 + 8;

/// zstd parameters of the chunks (zstd's `ZSTD_c_*` parameters of the same names).
///
/// The defaults are zstd's fast strategy at acceleration 7 (level −7) with its literals still Huffman
/// coded (zstd turns that off at negative levels), a 1 MiB window, a 2¹⁷-entry hash table and matches of
/// at least 7 bytes. On the position walk's log (JSON, mostly decimal digits) that takes 31 % fewer
/// instructions than level 1 for chunks 7.9 % larger (docs/performance.md, "The log's compression": the
/// table of parameters, `tools/bench/log-zstd/run.sh`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ZstdParameters {
    /// Compression level (negative: the fast strategy's acceleration).
    pub level: i32,
    /// log₂ of the window \[bytes\].
    pub window_log: u32,
    /// log₂ of the match finder's hash table entries.
    pub hash_log: u32,
    /// Shortest match \[bytes\].
    pub min_match: u32,
    /// Huffman-code the literals.
    pub huffman_literals: bool,
}

impl Default for ZstdParameters {
    fn default() -> Self {
        Self {
            level: -7,
            window_log: 20,
            hash_log: 17,
            min_match: 7,
            huffman_literals: true,
        }
    }
}

/// The compressor of the chunks and its reused output buffer.
enum Codec {
    Zstd(Box<zstd::bulk::Compressor<'static>>),
    Lz4,
    None,
}

impl Codec {
    fn new(compression: Compression, zstd: &ZstdParameters) -> io::Result<Self> {
        Ok(match compression {
            Compression::Zstd => {
                use zstd::zstd_safe::{CParameter, ParamSwitch};
                let mut c = zstd::bulk::Compressor::new(zstd.level)?;
                c.set_parameter(CParameter::WindowLog(zstd.window_log))?;
                c.set_parameter(CParameter::HashLog(zstd.hash_log))?;
                c.set_parameter(CParameter::MinMatch(zstd.min_match))?;
                c.set_parameter(CParameter::LiteralCompressionMode(
                    if zstd.huffman_literals {
                        ParamSwitch::Enable
                    } else {
                        ParamSwitch::Auto
                    },
                ))?;
                Codec::Zstd(Box::new(c))
            }
            Compression::Lz4 => Codec::Lz4,
            Compression::None => Codec::None,
        })
    }

    /// The chunk record's `compression` field.
    fn name(&self) -> &'static str {
        match self {
            Codec::Zstd(_) => "zstd",
            Codec::Lz4 => "lz4",
            Codec::None => "",
        }
    }

    /// Compresses `data` into `out` (cleared first).
    fn compress(&mut self, data: &[u8], out: &mut Vec<u8>) -> io::Result<()> {
        out.clear();
        match self {
            Codec::Zstd(c) => {
                out.reserve(zstd::zstd_safe::compress_bound(data.len()));
                c.compress_to_buffer(data, out)?;
            }
            Codec::Lz4 => {
                // The `mcap` crate's lz4 frames: level 1, no block checksum (the chunk has its CRC).
                let mut e = lz4::EncoderBuilder::new()
                    .level(1)
                    .block_checksum(lz4::liblz4::BlockChecksum::NoBlockChecksum)
                    .build(std::mem::take(out))?;
                e.write_all(data)?;
                let (buf, result) = e.finish();
                *out = buf;
                result?;
            }
            Codec::None => out.extend_from_slice(data),
        }
        Ok(())
    }
}

/// Little-endian record encoding into a byte buffer.
trait Put {
    fn u8(&mut self, v: u8);
    fn u16(&mut self, v: u16);
    fn u32(&mut self, v: u32);
    fn u64(&mut self, v: u64);
    /// An MCAP `String`: u32 byte length, then the bytes.
    fn str(&mut self, s: &str);
}

impl Put for Vec<u8> {
    fn u8(&mut self, v: u8) {
        self.push(v);
    }
    fn u16(&mut self, v: u16) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.extend_from_slice(s.as_bytes());
    }
}

/// Appends the record `opcode` with the body that `body` appends (its length is filled in after).
fn record(out: &mut Vec<u8>, opcode: u8, body: impl FnOnce(&mut Vec<u8>)) {
    out.u8(opcode);
    let len_at = out.len();
    out.u64(0);
    body(out);
    let len = (out.len() - len_at - 8) as u64;
    out[len_at..len_at + 8].copy_from_slice(&len.to_le_bytes());
}

/// An MCAP map or array: u32 byte length, then what `entries` appends.
fn prefixed(out: &mut Vec<u8>, entries: impl FnOnce(&mut Vec<u8>)) {
    let len_at = out.len();
    out.u32(0);
    entries(out);
    let len = (out.len() - len_at - 4) as u32;
    out[len_at..len_at + 4].copy_from_slice(&len.to_le_bytes());
}

struct Schema {
    name: String,
    encoding: String,
    data: Vec<u8>,
}

struct Channel {
    schema_id: u16,
    topic: String,
    message_encoding: String,
}

/// Where a chunk, attachment or metadata record is in the file, for the summary's indexes.
struct ChunkIndex {
    start_time: u64,
    end_time: u64,
    offset: u64,
    length: u64,
    message_index_offsets: Vec<(u16, u64)>,
    message_index_length: u64,
    compressed_size: u64,
    uncompressed_size: u64,
}

struct AttachmentIndex {
    offset: u64,
    length: u64,
    log_time: u64,
    create_time: u64,
    data_size: u64,
    name: String,
    media_type: String,
}

/// The output stream with its position and the CRC of everything written (the data section's CRC).
struct Output<W: Write> {
    inner: W,
    position: u64,
    crc: crc32fast::Hasher,
}

impl<W: Write> Output<W> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.inner.write_all(bytes)?;
        self.crc.update(bytes);
        self.position += bytes.len() as u64;
        Ok(())
    }
}

/// A chunked MCAP file being written to `W`.
pub struct McapFile<W: Write> {
    out: Output<W>,
    codec: Codec,
    chunk_size: u64,
    /// Records of the open chunk, uncompressed.
    chunk: Vec<u8>,
    chunk_open: bool,
    chunk_times: Option<(u64, u64)>,
    /// Per channel (id − 1): (log time, offset in the uncompressed chunk) of its messages in the open
    /// chunk.
    chunk_index: Vec<Vec<(u64, u64)>>,
    compressed: Vec<u8>,
    scratch: Vec<u8>,
    schemas: Vec<Schema>,
    channels: Vec<Channel>,
    message_counts: Vec<u64>,
    message_times: Option<(u64, u64)>,
    chunk_indexes: Vec<ChunkIndex>,
    attachment_indexes: Vec<AttachmentIndex>,
    metadata_indexes: Vec<(u64, u64, String)>,
}

impl<W: Write> McapFile<W> {
    /// Writes the magic and the header record (empty profile, `library`) and prepares chunks of
    /// `chunk_size` uncompressed bytes (a chunk is closed before the first message that would find it
    /// larger).
    pub fn create(
        inner: W,
        compression: Compression,
        zstd: &ZstdParameters,
        chunk_size: u64,
        library: &str,
    ) -> io::Result<Self> {
        let mut file = Self {
            out: Output {
                inner,
                position: 0,
                crc: crc32fast::Hasher::new(),
            },
            codec: Codec::new(compression, zstd)?,
            chunk_size,
            // (a chunk overshoots its size by at most one message; larger chunks grow as they fill)
            chunk: Vec::with_capacity(chunk_size.min(1 << 26) as usize + (1 << 16)),
            chunk_open: false,
            chunk_times: None,
            chunk_index: Vec::new(),
            compressed: Vec::new(),
            scratch: Vec::new(),
            schemas: Vec::new(),
            channels: Vec::new(),
            message_counts: Vec::new(),
            message_times: None,
            chunk_indexes: Vec::new(),
            attachment_indexes: Vec::new(),
            metadata_indexes: Vec::new(),
        };
        file.out.write(MAGIC)?;
        let mut header = Vec::new();
        record(&mut header, op::HEADER, |b| {
            b.str("");
            b.str(library);
        });
        file.out.write(&header)?;
        Ok(file)
    }

    /// The id of a schema (ids from 1; a schema with the same name, encoding and data shares its id).
    pub fn add_schema(&mut self, name: &str, encoding: &str, data: &[u8]) -> io::Result<u16> {
        if let Some(i) = self
            .schemas
            .iter()
            .position(|s| s.name == name && s.encoding == encoding && s.data == data)
        {
            return Ok(i as u16 + 1);
        }
        let id = u16::try_from(self.schemas.len() + 1)
            .map_err(|_| io::Error::other("more than 65535 schemas"))?;
        self.schemas.push(Schema {
            name: name.into(),
            encoding: encoding.into(),
            data: data.into(),
        });
        self.chunk_open = true;
        schema_record(&mut self.chunk, id, &self.schemas[usize::from(id - 1)]);
        Ok(id)
    }

    /// The id of a channel without metadata (ids from 1, as the `mcap` crate's; the same schema, topic
    /// and encoding share it).
    pub fn add_channel(
        &mut self,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
    ) -> io::Result<u16> {
        if let Some(i) = self.channels.iter().position(|c| {
            c.schema_id == schema_id && c.topic == topic && c.message_encoding == message_encoding
        }) {
            return Ok(i as u16 + 1);
        }
        if schema_id != 0 && usize::from(schema_id) > self.schemas.len() {
            return Err(io::Error::other(format!(
                "channel {topic}: unknown schema {schema_id}"
            )));
        }
        let id = u16::try_from(self.channels.len() + 1)
            .map_err(|_| io::Error::other("more than 65535 channels"))?;
        self.channels.push(Channel {
            schema_id,
            topic: topic.into(),
            message_encoding: message_encoding.into(),
        });
        self.message_counts.push(0);
        self.chunk_index.push(Vec::new());
        self.chunk_open = true;
        channel_record(&mut self.chunk, id, &self.channels[usize::from(id - 1)]);
        Ok(id)
    }

    /// Appends a message record to the open chunk (closing the chunk first if it is already larger
    /// than the chunk size).
    pub fn write_message(
        &mut self,
        channel_id: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> io::Result<()> {
        let Some(ch) = usize::from(channel_id)
            .checked_sub(1)
            .filter(|&i| i < self.channels.len())
        else {
            return Err(io::Error::other(format!(
                "message {sequence} on unknown channel {channel_id}"
            )));
        };
        if self.chunk.len() as u64 > self.chunk_size {
            self.finish_chunk()?;
        }
        self.message_counts[ch] += 1;
        self.message_times = Some(widen(self.message_times, log_time));
        self.chunk_times = Some(widen(self.chunk_times, log_time));
        self.chunk_open = true;
        self.chunk_index[ch].push((log_time, self.chunk.len() as u64));
        let len = (MESSAGE_HEADER_BYTES - 9 + data.len()) as u64;
        let mut head = [0u8; MESSAGE_HEADER_BYTES];
        head[0] = op::MESSAGE;
        head[1..9].copy_from_slice(&len.to_le_bytes());
        head[9..11].copy_from_slice(&channel_id.to_le_bytes());
        head[11..15].copy_from_slice(&sequence.to_le_bytes());
        head[15..23].copy_from_slice(&log_time.to_le_bytes());
        head[23..31].copy_from_slice(&publish_time.to_le_bytes());
        self.chunk.extend_from_slice(&head);
        self.chunk.extend_from_slice(data);
        Ok(())
    }

    /// Writes an attachment record (after closing the open chunk).
    pub fn attach(
        &mut self,
        log_time: u64,
        create_time: u64,
        name: &str,
        media_type: &str,
        data: &[u8],
    ) -> io::Result<()> {
        self.finish_chunk()?;
        let offset = self.out.position;
        let mut b = std::mem::take(&mut self.scratch);
        b.clear();
        record(&mut b, op::ATTACHMENT, |b| {
            b.u64(log_time);
            b.u64(create_time);
            b.str(name);
            b.str(media_type);
            b.u64(data.len() as u64);
            b.extend_from_slice(data);
            // The CRC of the record's preceding fields.
            let crc = crc32fast::hash(&b[9..]);
            b.u32(crc);
        });
        self.out.write(&b)?;
        self.attachment_indexes.push(AttachmentIndex {
            offset,
            length: b.len() as u64,
            log_time,
            create_time,
            data_size: data.len() as u64,
            name: name.into(),
            media_type: media_type.into(),
        });
        self.scratch = b;
        Ok(())
    }

    /// Writes a metadata record (after closing the open chunk).
    pub fn write_metadata(
        &mut self,
        name: &str,
        entries: &std::collections::BTreeMap<String, String>,
    ) -> io::Result<()> {
        self.finish_chunk()?;
        let offset = self.out.position;
        let mut b = std::mem::take(&mut self.scratch);
        b.clear();
        record(&mut b, op::METADATA, |b| {
            b.str(name);
            prefixed(b, |b| {
                for (k, v) in entries {
                    b.str(k);
                    b.str(v);
                }
            });
        });
        self.out.write(&b)?;
        self.metadata_indexes
            .push((offset, b.len() as u64, name.to_string()));
        self.scratch = b;
        Ok(())
    }

    /// Compresses and writes the open chunk and its message indexes.
    fn finish_chunk(&mut self) -> io::Result<()> {
        if !self.chunk_open {
            return Ok(());
        }
        self.chunk_open = false;
        let (start_time, end_time) = self.chunk_times.take().unwrap_or((0, 0));
        let uncompressed_crc = crc32fast::hash(&self.chunk);
        self.codec.compress(&self.chunk, &mut self.compressed)?;
        let offset = self.out.position;
        let mut b = std::mem::take(&mut self.scratch);
        b.clear();
        let compression = self.codec.name();
        b.u8(op::CHUNK);
        b.u64((8 + 8 + 8 + 4 + 4 + compression.len() + 8 + self.compressed.len()) as u64);
        b.u64(start_time);
        b.u64(end_time);
        b.u64(self.chunk.len() as u64);
        b.u32(uncompressed_crc);
        b.str(compression);
        b.u64(self.compressed.len() as u64);
        self.out.write(&b)?;
        self.out.write(&self.compressed)?;
        let length = self.out.position - offset;
        let mut message_index_offsets = Vec::new();
        let index_start = self.out.position;
        b.clear();
        for (i, entries) in self.chunk_index.iter_mut().enumerate() {
            if entries.is_empty() {
                continue;
            }
            let channel = i + 1;
            message_index_offsets.push((channel as u16, index_start + b.len() as u64));
            record(&mut b, op::MESSAGE_INDEX, |b| {
                b.u16(channel as u16);
                prefixed(b, |b| {
                    for &(time, at) in entries.iter() {
                        b.u64(time);
                        b.u64(at);
                    }
                });
            });
            entries.clear();
        }
        self.out.write(&b)?;
        self.chunk_indexes.push(ChunkIndex {
            start_time,
            end_time,
            offset,
            length,
            message_index_offsets,
            message_index_length: b.len() as u64,
            compressed_size: self.compressed.len() as u64,
            uncompressed_size: self.chunk.len() as u64,
        });
        self.chunk.clear();
        self.scratch = b;
        Ok(())
    }

    /// Closes the last chunk, writes the data end, the summary section, the footer and the magic, and
    /// returns the stream (not flushed).
    pub fn finish(mut self) -> io::Result<W> {
        self.finish_chunk()?;
        let mut b = Vec::new();
        let data_crc = self.out.crc.clone().finalize();
        record(&mut b, op::DATA_END, |b| b.u32(data_crc));
        self.out.write(&b)?;
        let summary_start = self.out.position;
        let mut s = Vec::new();
        let mut offsets: Vec<(u8, u64, u64)> = Vec::new();
        let mut group = |s: &mut Vec<u8>, opcode: u8, body: &dyn Fn(&mut Vec<u8>)| {
            let start = s.len();
            body(s);
            if s.len() > start {
                offsets.push((
                    opcode,
                    summary_start + start as u64,
                    (s.len() - start) as u64,
                ));
            }
        };
        group(&mut s, op::SCHEMA, &|s| {
            for (i, schema) in self.schemas.iter().enumerate() {
                schema_record(s, i as u16 + 1, schema);
            }
        });
        group(&mut s, op::CHANNEL, &|s| {
            for (i, channel) in self.channels.iter().enumerate() {
                channel_record(s, i as u16 + 1, channel);
            }
        });
        group(&mut s, op::STATISTICS, &|s| self.statistics(s));
        group(&mut s, op::CHUNK_INDEX, &|s| {
            for c in &self.chunk_indexes {
                chunk_index_record(s, c, self.codec.name());
            }
        });
        group(&mut s, op::ATTACHMENT_INDEX, &|s| {
            for a in &self.attachment_indexes {
                record(s, op::ATTACHMENT_INDEX, |b| {
                    b.u64(a.offset);
                    b.u64(a.length);
                    b.u64(a.log_time);
                    b.u64(a.create_time);
                    b.u64(a.data_size);
                    b.str(&a.name);
                    b.str(&a.media_type);
                });
            }
        });
        group(&mut s, op::METADATA_INDEX, &|s| {
            for (offset, length, name) in &self.metadata_indexes {
                record(s, op::METADATA_INDEX, |b| {
                    b.u64(*offset);
                    b.u64(*length);
                    b.str(name);
                });
            }
        });
        let summary_offset_start = summary_start + s.len() as u64;
        for (opcode, start, length) in &offsets {
            record(&mut s, op::SUMMARY_OFFSET, |b| {
                b.u8(*opcode);
                b.u64(*start);
                b.u64(*length);
            });
        }
        // The footer's CRC covers the summary section and the footer up to (without) itself.
        s.u8(op::FOOTER);
        s.u64(8 + 8 + 4);
        s.u64(summary_start);
        s.u64(summary_offset_start);
        let summary_crc = crc32fast::hash(&s);
        s.u32(summary_crc);
        s.extend_from_slice(MAGIC);
        self.out.write(&s)?;
        Ok(self.out.inner)
    }

    fn statistics(&self, s: &mut Vec<u8>) {
        let (start, end) = self.message_times.unwrap_or((0, 0));
        record(s, op::STATISTICS, |b| {
            b.u64(self.message_counts.iter().sum());
            b.u16(self.schemas.len() as u16);
            b.u32(self.channels.len() as u32);
            b.u32(self.attachment_indexes.len() as u32);
            b.u32(self.metadata_indexes.len() as u32);
            b.u32(self.chunk_indexes.len() as u32);
            b.u64(start);
            b.u64(end);
            prefixed(b, |b| {
                for (i, &count) in self.message_counts.iter().enumerate() {
                    if count > 0 {
                        b.u16(i as u16 + 1);
                        b.u64(count);
                    }
                }
            });
        });
    }
}

fn widen(bounds: Option<(u64, u64)>, t: u64) -> (u64, u64) {
    match bounds {
        None => (t, t),
        Some((start, end)) => (start.min(t), end.max(t)),
    }
}

fn schema_record(out: &mut Vec<u8>, id: u16, s: &Schema) {
    record(out, op::SCHEMA, |b| {
        b.u16(id);
        b.str(&s.name);
        b.str(&s.encoding);
        b.u32(s.data.len() as u32);
        b.extend_from_slice(&s.data);
    });
}

fn channel_record(out: &mut Vec<u8>, id: u16, c: &Channel) {
    record(out, op::CHANNEL, |b| {
        b.u16(id);
        b.u16(c.schema_id);
        b.str(&c.topic);
        b.str(&c.message_encoding);
        prefixed(b, |_| {});
    });
}

fn chunk_index_record(out: &mut Vec<u8>, c: &ChunkIndex, compression: &str) {
    record(out, op::CHUNK_INDEX, |b| {
        b.u64(c.start_time);
        b.u64(c.end_time);
        b.u64(c.offset);
        b.u64(c.length);
        prefixed(b, |b| {
            for &(channel, offset) in &c.message_index_offsets {
                b.u16(channel);
                b.u64(offset);
            }
        });
        b.u64(c.message_index_length);
        b.str(compression);
        b.u64(c.compressed_size);
        b.u64(c.uncompressed_size);
    });
}

#[cfg(test)]
#[path = "mcap_file_tests.rs"]
mod tests;
