//! [`McapFile`] against the `mcap` crate's writer and reader.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Cursor;

use mcap::records::Record;

use super::*;

/// What a log writer does to a file, in order.
enum Op {
    Schema(&'static str, &'static [u8]),
    Channel(u16, &'static str),
    Message(u16, u32, u64, Vec<u8>),
    Attach(&'static str, Vec<u8>),
    Metadata(&'static str, BTreeMap<String, String>),
}

/// Pseudo-random bytes (xorshift), JSON-like: digits mostly, so that compression has work to do.
fn payload(seed: u64, len: usize) -> Vec<u8> {
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..len)
        .map(|i| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            if i % 7 == 0 {
                b','
            } else {
                b'0' + (x % 10) as u8
            }
        })
        .collect()
}

/// Two schemas (one shared by two channels), channels registered before and between messages, messages
/// from 0 bytes to more than a chunk, attachments and metadata between them.
fn operations() -> Vec<Op> {
    let mut ops = vec![
        Op::Schema("a", b"{\"type\":\"object\"}"),
        Op::Channel(1, "/a"),
        Op::Attach("model.urdf", payload(1, 3000)),
        Op::Metadata(
            "stride",
            BTreeMap::from([("k".into(), "v".into()), ("x".into(), String::new())]),
        ),
    ];
    for i in 0..400u32 {
        let len = [0, 17, 300, 2500, 9000][i as usize % 5];
        ops.push(Op::Message(
            1,
            i + 1,
            1_000 * u64::from(i),
            payload(10 + u64::from(i), len),
        ));
        if i == 150 {
            ops.push(Op::Schema("a", b"{\"type\":\"object\"}"));
            ops.push(Op::Schema("b", b"{}"));
            ops.push(Op::Channel(1, "/a2"));
            ops.push(Op::Channel(2, "/b"));
        }
        if i > 150 && i % 3 == 0 {
            ops.push(Op::Message(
                2,
                i,
                1_000 * u64::from(i) + 500,
                payload(u64::from(i), 700),
            ));
            ops.push(Op::Message(
                3,
                i,
                1_000 * u64::from(i) - 700,
                payload(7 * u64::from(i), 40),
            ));
        }
        if i == 300 {
            ops.push(Op::Attach("late", payload(3, 10)));
        }
    }
    ops
}

const CHUNK: u64 = 16 * 1024;

fn ours(ops: &[Op], compression: Compression) -> Vec<u8> {
    let mut f = McapFile::create(
        Vec::new(),
        compression,
        &ZstdParameters::default(),
        CHUNK,
        "stride-test",
    )
    .expect("create");
    let mut schemas = vec![0u16];
    for op in ops {
        match op {
            Op::Schema(name, data) => schemas.push(f.add_schema(name, "jsonschema", data).unwrap()),
            Op::Channel(schema, topic) => {
                f.add_channel(schemas[usize::from(*schema)], topic, "json")
                    .unwrap();
            }
            Op::Message(ch, seq, t, data) => f.write_message(*ch, *seq, *t, *t, data).unwrap(),
            Op::Attach(name, data) => f.attach(0, 0, name, "application/xml", data).unwrap(),
            Op::Metadata(name, entries) => f.write_metadata(name, entries).unwrap(),
        }
    }
    f.finish().expect("finish")
}

fn the_mcap_crates(ops: &[Op]) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .chunk_size(Some(CHUNK))
        .profile("")
        .library("stride-test")
        .create(Cursor::new(Vec::new()))
        .expect("create");
    let mut schemas = vec![0u16];
    for op in ops {
        match op {
            Op::Schema(name, data) => schemas.push(w.add_schema(name, "jsonschema", data).unwrap()),
            Op::Channel(schema, topic) => {
                w.add_channel(
                    schemas[usize::from(*schema)],
                    topic,
                    "json",
                    &BTreeMap::new(),
                )
                .unwrap();
            }
            Op::Message(ch, seq, t, data) => w
                .write_to_known_channel(
                    &mcap::records::MessageHeader {
                        channel_id: *ch,
                        sequence: *seq,
                        log_time: *t,
                        publish_time: *t,
                    },
                    data,
                )
                .unwrap(),
            Op::Attach(name, data) => w
                .attach(&mcap::Attachment {
                    log_time: 0,
                    create_time: 0,
                    name: (*name).into(),
                    media_type: "application/xml".into(),
                    data: Cow::Borrowed(data),
                })
                .unwrap(),
            Op::Metadata(name, entries) => w
                .write_metadata(&mcap::records::Metadata {
                    name: (*name).into(),
                    metadata: entries.clone(),
                })
                .unwrap(),
        }
    }
    w.finish().expect("finish");
    w.into_inner().into_inner()
}

#[test]
fn uncompressed_it_is_the_mcap_crates_file_byte_for_byte() {
    for ops in [operations(), Vec::new()] {
        let a = ours(&ops, Compression::None);
        let b = the_mcap_crates(&ops);
        assert!(a.len() > 8, "a file");
        assert_eq!(a.len(), b.len());
        assert!(a == b, "the files differ");
    }
}

/// Every record of a file, chunks decompressed, as (opcode-like tag, bytes or debug text).
fn records(file: &[u8], compression: Compression) -> Vec<String> {
    let mut out = Vec::new();
    for r in mcap::read::LinearReader::new(file).expect("reader") {
        let r = r.expect("record");
        match r {
            Record::Chunk { mut header, data } => {
                let raw = match compression {
                    Compression::Zstd => zstd::decode_all(&data[..]).expect("zstd"),
                    Compression::Lz4 => {
                        let mut d = lz4::Decoder::new(&data[..]).expect("lz4");
                        let mut raw = Vec::new();
                        std::io::copy(&mut d, &mut raw).expect("lz4 data");
                        raw
                    }
                    Compression::None => data.into_owned(),
                };
                assert_eq!(raw.len() as u64, header.uncompressed_size);
                assert_eq!(crc32fast::hash(&raw), header.uncompressed_crc);
                header.compression.clear();
                header.compressed_size = 0;
                out.push(format!("chunk {header:?} {raw:?}"));
            }
            Record::ChunkIndex(mut c) => {
                c.compression.clear();
                c.compressed_size = 0;
                c.chunk_start_offset = 0;
                c.chunk_length = 0;
                c.message_index_offsets.values_mut().for_each(|v| *v = 0);
                out.push(format!("{c:?}"));
            }
            Record::DataEnd(_) | Record::Footer(_) => {}
            Record::AttachmentIndex(mut a) => {
                a.offset = 0;
                out.push(format!("{a:?}"));
            }
            Record::MetadataIndex(mut m) => {
                m.offset = 0;
                out.push(format!("{m:?}"));
            }
            Record::SummaryOffset(mut s) => {
                s.group_start = 0;
                if s.group_opcode == 0x08 {
                    // chunk indexes name their compression
                    s.group_length = 0;
                }
                out.push(format!("{s:?}"));
            }
            other => out.push(format!("{other:?}")),
        }
    }
    out
}

/// (topic, sequence, log time, payload) of every message, in file order.
fn messages(file: &[u8]) -> Vec<(String, u32, u64, Vec<u8>)> {
    mcap::MessageStream::new(file)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (
                m.channel.topic.clone(),
                m.sequence,
                m.log_time,
                m.data.into_owned(),
            )
        })
        .collect()
}

#[test]
fn compressed_chunks_hold_the_uncompressed_files_records() {
    let ops = operations();
    let plain = ours(&ops, Compression::None);
    let expected = records(&plain, Compression::None);
    assert!(expected.iter().filter(|r| r.starts_with("chunk")).count() > 10);
    for compression in [Compression::Zstd, Compression::Lz4] {
        let file = ours(&ops, compression);
        assert!(file.len() < plain.len(), "{compression:?} compresses");
        let got = records(&file, compression);
        assert_eq!(got.len(), expected.len(), "{compression:?}");
        for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
            assert!(
                a == b,
                "{compression:?}, record {i}: {a:.300} against {b:.300}"
            );
        }
        // The indexed reader (summary, chunk indexes) and the message stream read the same messages.
        let summary = mcap::Summary::read(&file).unwrap().expect("a summary");
        let plain_summary = mcap::Summary::read(&plain).unwrap().expect("a summary");
        assert_eq!(summary.stats, plain_summary.stats);
        let stream = messages(&file);
        let plain_stream = messages(&plain);
        assert_eq!(stream.len(), 400 + 2 * 83);
        assert!(stream == plain_stream, "{compression:?}: the messages");
        let mut indexed = 0;
        for chunk in &summary.chunk_indexes {
            for m in summary.stream_chunk(&file, chunk).unwrap() {
                m.unwrap();
                indexed += 1;
            }
        }
        assert_eq!(indexed, stream.len());
    }
}

#[test]
fn a_message_on_an_unknown_channel_is_an_error() {
    let mut f = McapFile::create(
        Vec::new(),
        Compression::Zstd,
        &ZstdParameters::default(),
        CHUNK,
        "t",
    )
    .unwrap();
    assert!(f.write_message(0, 1, 0, 0, b"{}").is_err());
    assert!(f.write_message(1, 1, 0, 0, b"{}").is_err());
    assert!(f.add_channel(3, "/x", "json").is_err());
}
