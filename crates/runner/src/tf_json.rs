//! `/tf` and `/tf_static` (`foxglove.FrameTransforms`) written as JSON straight into the message buffer: the
//! bytes `serde_json::to_writer` writes for the same value (numbers and names through `crate::log_json`:
//! serde_json's own formatting and escaping), without its field-by-field dispatch and key escaping.
//! `/tf` is the log's largest message (one transform per body at every state tick).

use crate::log::{FoxgloveQuaternion, FoxgloveVector3, FrameTransforms};
use crate::log_json::Json;

/// Appends the JSON of `tf` to `out`, byte for byte `serde_json::to_writer(out, tf)`.
pub(crate) fn write_frame_transforms(
    out: &mut Vec<u8>,
    tf: &FrameTransforms,
) -> Result<(), serde_json::Error> {
    out.extend_from_slice(b"{\"transforms\":[");
    for (i, t) in tf.transforms.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        out.extend_from_slice(b"{\"timestamp\":{\"sec\":");
        t.timestamp.sec.json(out)?;
        out.extend_from_slice(b",\"nsec\":");
        t.timestamp.nsec.json(out)?;
        out.extend_from_slice(b"},\"parent_frame_id\":");
        t.parent_frame_id.json(out)?;
        out.extend_from_slice(b",\"child_frame_id\":");
        t.child_frame_id.json(out)?;
        out.extend_from_slice(b",\"translation\":");
        vector3(out, &t.translation)?;
        out.extend_from_slice(b",\"rotation\":");
        quaternion(out, &t.rotation)?;
        out.push(b'}');
    }
    out.extend_from_slice(b"]}");
    Ok(())
}

fn vector3(out: &mut Vec<u8>, v: &FoxgloveVector3) -> Result<(), serde_json::Error> {
    let fields: [(&[u8], f64); 3] = [(b"{\"x\":", v.x), (b",\"y\":", v.y), (b",\"z\":", v.z)];
    numbers_object(out, &fields)
}

fn quaternion(out: &mut Vec<u8>, q: &FoxgloveQuaternion) -> Result<(), serde_json::Error> {
    let fields: [(&[u8], f64); 4] = [
        (b"{\"x\":", q.x),
        (b",\"y\":", q.y),
        (b",\"z\":", q.z),
        (b",\"w\":", q.w),
    ];
    numbers_object(out, &fields)
}

/// An object of numbers: each field's bytes up to its value (`{"x":`, then `,"y":`, …), its value, then `}`.
fn numbers_object(out: &mut Vec<u8>, fields: &[(&[u8], f64)]) -> Result<(), serde_json::Error> {
    for (key, v) in fields {
        out.extend_from_slice(key);
        v.json(out)?;
    }
    out.push(b'}');
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::{FoxgloveTime, FrameTransform};

    fn transform(k: usize) -> FrameTransform {
        let special = [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            5e-324,
            1.0e300,
            -123.456_789,
        ];
        let v =
            |j: usize| special[(k + j) % special.len()] + (k as f64 * 0.1 + j as f64).sin() * 1e-3;
        let names = [
            "world",
            "l_\"foot\"",
            "back\\slash",
            "tab\tnewline\n",
            "ünïcode",
            "",
        ];
        FrameTransform {
            timestamp: FoxgloveTime::from_ns(1_234_567_890_123 + k as u64),
            parent_frame_id: names[k % names.len()].into(),
            child_frame_id: names[(k + 1) % names.len()].into(),
            translation: FoxgloveVector3 {
                x: v(0),
                y: v(1),
                z: special[k % special.len()],
            },
            rotation: FoxgloveQuaternion {
                x: v(3),
                y: v(4),
                z: v(5),
                w: special[(k + 3) % special.len()],
            },
        }
    }

    #[test]
    fn the_bytes_are_serde_json_s() {
        for n in [0, 1, 2, 17] {
            let tf = FrameTransforms {
                transforms: (0..n).map(transform).collect(),
            };
            let mut ours = Vec::new();
            write_frame_transforms(&mut ours, &tf).expect("write");
            let reference = serde_json::to_vec(&tf).expect("serde_json");
            assert_eq!(
                String::from_utf8_lossy(&ours),
                String::from_utf8_lossy(&reference),
                "{n} transforms"
            );
            assert_eq!(ours, reference);
        }
    }
}
