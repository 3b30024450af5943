//! Frames (bodies, merged links, sensors), the mimic targets and the force/torque sensors.

use std::collections::HashMap;

use super::graph::Graph;
use super::links::Links;
use super::raw::{RawInfo, RawSensor};
use super::tree::Tree;
use crate::error::ModelError;
use crate::model::{Body, Frame, FrameId, FrameKind, FtSensor, Joint};

/// The frames of the model and their index by name.
pub(super) struct Frames {
    pub(super) list: Vec<Frame>,
    pub(super) index: HashMap<String, usize>,
    /// Per frame, the URDF link (file-order index) it is attached to.
    pub(super) links: Vec<usize>,
}

/// Body frames first (frame `k` is body `k`), then the merged links in traversal order.
pub(super) fn body_and_merged_frames(bodies: &[Body], merged: Vec<Frame>, links: &Links) -> Frames {
    let mut list: Vec<Frame> = Vec::new();
    for b in bodies {
        list.push(Frame {
            name: b.name.clone(),
            link: list.len(),
            placement: nalgebra::Isometry3::identity(),
            kind: FrameKind::Body,
            attached_to: None,
        });
    }
    list.extend(merged);
    let mut index: HashMap<String, usize> = HashMap::new();
    for (k, f) in list.iter().enumerate() {
        index.insert(f.name.clone(), k);
    }
    // Body and merged frames are named after their URDF link.
    let links = list.iter().map(|f| links.index[&f.name]).collect();
    Frames { list, index, links }
}

/// The movable joints by name; every mimic joint must copy one of them ([`ModelError::MimicTarget`]).
pub(super) fn check_mimic_targets(joints: &[Joint]) -> Result<HashMap<String, usize>, ModelError> {
    let joint_index: HashMap<String, usize> = joints
        .iter()
        .enumerate()
        .map(|(k, j)| (j.name.clone(), k))
        .collect();
    for j in joints {
        if let Some(m) = &j.mimic {
            if !joint_index.contains_key(&m.joint) {
                return Err(ModelError::MimicTarget {
                    joint: j.name.clone(),
                    target: m.joint.clone(),
                });
            }
        }
    }
    Ok(joint_index)
}

/// The force/torque sensors on fixed joints, in declaration order. A sensor whose name is not yet a frame
/// gets a [`FrameKind::Sensor`] frame: the `<frame>` link (`parent`, else the child), composed with the
/// declared origin when `<frame>` is `sensor`. Sensors on missing or movable joints are ignored with a
/// warning.
pub(super) fn ft_sensors(
    robot: &urdf_rs::Robot,
    raw: &RawInfo,
    links: &Links,
    graph: &Graph,
    tree: &Tree,
    frames: &mut Frames,
    warnings: &mut Vec<String>,
) -> Vec<FtSensor> {
    let mut ft_sensors = Vec::new();
    for s in &raw.sensors {
        let Some(&jk) = graph.joint_names.get(s.joint.as_str()) else {
            warnings.push(format!(
                "force/torque sensor `{}` refers to the missing joint `{}`; ignored",
                s.name, s.joint
            ));
            continue;
        };
        let joint = &robot.joints[jk];
        if joint.joint_type != urdf_rs::JointType::Fixed {
            warnings.push(format!(
                "force/torque sensor `{}` is on the non-fixed joint `{}`; ignored",
                s.name, s.joint
            ));
            continue;
        }
        let Some(frame) = sensor_frame(s, joint, links, tree, frames) else {
            continue;
        };
        ft_sensors.push(FtSensor {
            name: s.name.clone(),
            joint: s.joint.clone(),
            frame: FrameId(frame),
            parent_link: joint.parent.link.clone(),
            child_link: joint.child.link.clone(),
            measure_direction: s.direction.clone(),
        });
    }
    ft_sensors
}

/// The frame named like the sensor, or a new sensor frame (`None` if its link was not reached).
fn sensor_frame(
    s: &RawSensor,
    joint: &urdf_rs::Joint,
    links: &Links,
    tree: &Tree,
    frames: &mut Frames,
) -> Option<usize> {
    if let Some(&f) = frames.index.get(&s.name) {
        return Some(f);
    }
    let link = match s.frame.as_str() {
        "parent" => &joint.parent.link,
        _ => &joint.child.link,
    };
    let link = links.index[link];
    let (body, placement) = tree.link_frame[link]?;
    let placement = if s.frame == "sensor" {
        placement * s.origin
    } else {
        placement
    };
    frames.list.push(Frame {
        name: s.name.clone(),
        link: body,
        placement,
        kind: FrameKind::Sensor,
        attached_to: None,
    });
    frames.links.push(link);
    frames.index.insert(s.name.clone(), frames.list.len() - 1);
    Some(frames.list.len() - 1)
}
