//! `robot.left_sole` / `robot.right_sole`: a frame of the model by name, or a frame the model lacks,
//! attached to a link by the configuration (`{ parent = "<link>", xyz = [..], rpy = [..] }`) and added to
//! the model when it is loaded.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// A sole frame: its name in the model, or where to attach it.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum SoleFrame {
    /// A frame (link, merged link or sensor frame) of the model.
    Name(String),
    /// A frame added to the model on a parent frame.
    Attached(AttachedFrame),
}

/// A frame the configuration adds to the model, URDF-`<origin>` style.
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `parent` | – | required | frame (usually the foot link) the new frame is rigidly attached to |
/// | `xyz` | m | `[0, 0, 0]` | origin of the new frame in `parent` |
/// | `rpy` | rad | `[0, 0, 0]` | roll, pitch, yaw of the new frame in `parent` (URDF convention: `R = Rz(y) Ry(p) Rx(r)`) |
/// | `name` | – | `left_sole` / `right_sole` | name of the new frame in the model |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttachedFrame {
    /// Name of the added frame (empty: `left_sole` / `right_sole`, filled in when the scenario loads).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub name: String,
    /// Frame it is attached to.
    pub parent: String,
    /// Origin in the parent frame \[m\].
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw in the parent frame \[rad\] (URDF convention).
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl AttachedFrame {
    /// `parent_H_frame`.
    pub fn placement(&self) -> Isometry3<f64> {
        let [x, y, z] = self.xyz;
        let [r, p, yaw] = self.rpy;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(r, p, yaw),
        )
    }
}

impl SoleFrame {
    /// The frame's name in the model (an attached frame's own name).
    pub fn name(&self) -> &str {
        match self {
            SoleFrame::Name(n) => n,
            SoleFrame::Attached(a) => &a.name,
        }
    }

    /// The attached frame, if the configuration adds one.
    pub fn attached(&self) -> Option<&AttachedFrame> {
        match self {
            SoleFrame::Name(_) => None,
            SoleFrame::Attached(a) => Some(a),
        }
    }
}

impl std::ops::Deref for SoleFrame {
    type Target = str;
    fn deref(&self) -> &str {
        self.name()
    }
}

impl PartialEq<&str> for SoleFrame {
    fn eq(&self, other: &&str) -> bool {
        self.name() == *other
    }
}

impl From<&str> for SoleFrame {
    fn from(name: &str) -> Self {
        SoleFrame::Name(name.to_string())
    }
}

/// A string, or a table deserialized as [`AttachedFrame`] (so its errors keep their keys and spans).
impl<'de> Deserialize<'de> for SoleFrame {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SoleFrame;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a frame name, or a table `{ parent = \"<link>\", xyz = [x, y, z], rpy = [r, p, y] }`",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<SoleFrame, E> {
                Ok(SoleFrame::Name(v.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<SoleFrame, A::Error> {
                AttachedFrame::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(SoleFrame::Attached)
            }
        }
        d.deserialize_any(V)
    }
}
