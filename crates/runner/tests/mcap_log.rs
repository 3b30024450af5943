//! The MCAP writer: read back with the mcap crate's reader, to the last message.
mod common;

use std::collections::BTreeMap;

use common::Scratch;
use stride_runner::log::{
    read_log, read_log_topics, FrameTransforms, LogOptions, LogWriter, FRAME_TRANSFORMS_SCHEMA,
};

#[derive(serde::Serialize)]
struct Sample<'a> {
    time: f64,
    values: &'a [f64],
}

#[test]
fn written_log_reads_back_completely() {
    let s = Scratch::new("mcap");
    let path = s.path("a.mcap");
    let mut w = LogWriter::create(
        &path,
        &LogOptions {
            queue_capacity: 16,
            ..LogOptions::default()
        },
    )
    .unwrap();
    let a = w.topic("/a", "test.A", None).unwrap();
    let tf = w
        .topic(
            "/tf",
            "foxglove.FrameTransforms",
            Some(FRAME_TRANSFORMS_SCHEMA.into()),
        )
        .unwrap();
    w.attach(
        "scenario.toml",
        "application/toml",
        b"[scenario]\n".to_vec(),
    )
    .unwrap();
    let mut meta = BTreeMap::new();
    meta.insert("stride_version".to_string(), "x".to_string());
    w.metadata("stride", meta).unwrap();
    let values = [0.1, 1.0 / 3.0, -2.5e-300, f64::MAX];
    let n = 5000u64;
    for k in 0..n {
        w.write(
            a,
            k * 1000,
            &Sample {
                time: k as f64,
                values: &values,
            },
        )
        .unwrap();
    }
    w.write(tf, n * 1000, &FrameTransforms::default()).unwrap();
    let stats = w.finish().unwrap();
    assert_eq!(stats.messages, n + 1);

    // Independent check with the mcap crate directly: summary present, every message readable.
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a summary section");
    assert_eq!(summary.stats.as_ref().unwrap().message_count, n + 1);
    let mut count = 0;
    let mut last = None;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        count += 1;
        assert_eq!(m.channel.message_encoding, "json");
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "jsonschema");
        last = Some((m.channel.topic.clone(), m.log_time));
    }
    assert_eq!(count, n + 1);
    assert_eq!(last, Some(("/tf".to_string(), n * 1000)));

    let log = read_log(&path).unwrap();
    assert_eq!(log.schemas["/tf"].0, "foxglove.FrameTransforms");
    assert_eq!(log.attachments["scenario.toml"], b"[scenario]\n");
    assert_eq!(log.metadata["stride"]["stride_version"], "x");
    // f64 values round-trip bit-exactly.
    let first: serde_json::Value = serde_json::from_slice(&log.messages[0].data).unwrap();
    let back: Vec<f64> = serde_json::from_value(first["values"].clone()).unwrap();
    assert_eq!(
        back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    // The derived schema describes the message.
    let schema: serde_json::Value = serde_json::from_str(&log.schemas["/a"].2).unwrap();
    assert_eq!(schema["type"], "object");
    assert_eq!(schema["properties"]["values"]["type"], "array");

    // Reading one topic keeps its messages and schema alone, and every attachment and metadata record.
    let tf_only = read_log_topics(&path, |topic| topic == "/tf").unwrap();
    assert_eq!(tf_only.messages.len(), 1);
    assert_eq!(tf_only.messages[0].topic, "/tf");
    assert_eq!(tf_only.messages[0].data, log.messages[n as usize].data);
    assert_eq!(tf_only.schemas.keys().collect::<Vec<_>>(), ["/tf"]);
    assert_eq!(tf_only.attachments, log.attachments);
    assert_eq!(tf_only.metadata, log.metadata);
}

#[test]
fn dropped_writer_still_finishes_the_file() {
    let s = Scratch::new("drop");
    let path = s.path("b.mcap");
    {
        let mut w = LogWriter::create(&path, &LogOptions::default()).unwrap();
        let a = w.topic("/a", "test.A", None).unwrap();
        for k in 0..100u64 {
            w.write(
                a,
                k,
                &Sample {
                    time: k as f64,
                    values: &[],
                },
            )
            .unwrap();
        }
        // No finish(): as when a run unwinds.
    }
    let bytes = std::fs::read(&path).unwrap();
    assert!(mcap::Summary::read(&bytes).unwrap().is_some());
    assert_eq!(mcap::MessageStream::new(&bytes).unwrap().count(), 100);
}
