//! What urdf-rs drops, read with a small XML pass: which joints declare `<limit>`, and the six-axis
//! force/torque `<sensor>` elements (iDynTree-style top-level sensors and Gazebo-style sensors on a joint).

use std::collections::HashMap;

use nalgebra::Isometry3;

use super::{check_finite, pose};
use crate::error::ModelError;

/// A force/torque sensor as declared, before it is attached to a frame of the model.
pub(super) struct RawSensor {
    pub(super) name: String,
    pub(super) joint: String,
    /// `<frame>`: `child` (default), `parent` or `sensor`.
    pub(super) frame: String,
    /// `<measure_direction>`: `child_to_parent` (default) or `parent_to_child`.
    pub(super) direction: String,
    /// `joint_H_sensor` as declared (`<origin>` or `<pose>`; identity if absent).
    pub(super) origin: Isometry3<f64>,
}

/// The XML pass's findings.
pub(super) struct RawInfo {
    /// Joint name → whether the joint has a `<limit>` element.
    joints_with_limit: HashMap<String, bool>,
    /// Force/torque sensors in declaration order: top-level ones first, then the Gazebo ones that name
    /// neither a declared sensor nor a joint that already has one.
    pub(super) sensors: Vec<RawSensor>,
}

/// Reads the presence of `<limit>` per joint and the force/torque sensors from the parsed `<robot>`.
pub(super) fn read_raw(root: &xml::Element) -> Result<RawInfo, ModelError> {
    let mut joints_with_limit = HashMap::new();
    for joint in root.get_children("joint", None) {
        if let Some(name) = joint.get_attribute("name", None) {
            joints_with_limit.insert(name.to_string(), joint.get_child("limit", None).is_some());
        }
    }
    let mut sensors: Vec<RawSensor> = Vec::new();
    for sensor in root.get_children("sensor", None) {
        if let Some(sensor) = top_level_sensor(sensor)? {
            sensors.push(sensor);
        }
    }
    for gazebo in root.get_children("gazebo", None) {
        gazebo_sensors(gazebo, &mut sensors)?;
    }
    Ok(RawInfo {
        joints_with_limit,
        sensors,
    })
}

impl RawInfo {
    /// Whether the joint `name` declares a `<limit>` element (`false` for an unknown joint).
    pub(super) fn has_limit(&self, name: &str) -> bool {
        self.joints_with_limit.get(name).copied().unwrap_or(false)
    }
}

fn is_force_torque(sensor: &xml::Element) -> bool {
    sensor.get_attribute("type", None) == Some("force_torque")
}

fn element_text(e: &xml::Element) -> String {
    e.content_str().trim().to_string()
}

/// An iDynTree-style top-level `<sensor type="force_torque">` with `<parent joint>`; `None` for other sensor
/// types and sensors without a parent joint.
fn top_level_sensor(sensor: &xml::Element) -> Result<Option<RawSensor>, ModelError> {
    if !is_force_torque(sensor) {
        return Ok(None);
    }
    let name = sensor
        .get_attribute("name", None)
        .unwrap_or_default()
        .to_string();
    let Some(joint) = sensor
        .get_child("parent", None)
        .and_then(|p| p.get_attribute("joint", None))
    else {
        return Ok(None);
    };
    let element = format!("sensor `{name}`");
    let origin = match sensor.get_child("origin", None) {
        Some(o) => {
            let xyz = parse_triplet(o.get_attribute("xyz", None), &element, "origin xyz")?;
            let rpy = parse_triplet(o.get_attribute("rpy", None), &element, "origin rpy")?;
            check_finite(&xyz, &element, "origin xyz")?;
            check_finite(&rpy, &element, "origin rpy")?;
            pose(xyz, rpy)
        }
        None => Isometry3::identity(),
    };
    let (frame, direction) = ft_details(sensor);
    Ok(Some(RawSensor {
        name,
        joint: joint.to_string(),
        frame,
        direction,
        origin,
    }))
}

/// Gazebo-style sensors on a joint (`<gazebo reference="joint"><sensor type="force_torque">`), appended to
/// `sensors`. One sensor per joint: a declaration already in `sensors` wins (iCub files declare both,
/// sometimes with different names).
fn gazebo_sensors(gazebo: &xml::Element, sensors: &mut Vec<RawSensor>) -> Result<(), ModelError> {
    let Some(reference) = gazebo.get_attribute("reference", None) else {
        return Ok(());
    };
    for sensor in gazebo.get_children("sensor", None) {
        if !is_force_torque(sensor) {
            continue;
        }
        let name = sensor
            .get_attribute("name", None)
            .unwrap_or(reference)
            .to_string();
        if sensors
            .iter()
            .any(|s| s.name == name || s.joint == reference)
        {
            continue;
        }
        let element = format!("sensor `{name}`");
        let origin = match sensor.get_child("pose", None) {
            Some(p) => gazebo_pose(p, &element)?,
            None => Isometry3::identity(),
        };
        let (frame, direction) = ft_details(sensor);
        sensors.push(RawSensor {
            name,
            joint: reference.to_string(),
            frame,
            direction,
            origin,
        });
    }
    Ok(())
}

/// A Gazebo `<pose>x y z roll pitch yaw</pose>` (m, rad).
fn gazebo_pose(p: &xml::Element, element: &str) -> Result<Isometry3<f64>, ModelError> {
    let values: Vec<f64> = element_text(p)
        .split_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| ModelError::Urdf(format!("{element}: cannot parse <pose>")))?;
    if values.len() != 6 {
        return Err(ModelError::Urdf(format!(
            "{element}: <pose> needs six numbers"
        )));
    }
    check_finite(&values, element, "pose")?;
    Ok(pose(
        [values[0], values[1], values[2]],
        [values[3], values[4], values[5]],
    ))
}

/// `<force_torque><frame>` and `<measure_direction>`, defaulting to `child` and `child_to_parent`.
fn ft_details(sensor: &xml::Element) -> (String, String) {
    let mut frame = "child".to_string();
    let mut direction = "child_to_parent".to_string();
    if let Some(ft) = sensor.get_child("force_torque", None) {
        if let Some(f) = ft.get_child("frame", None) {
            frame = element_text(f);
        }
        if let Some(d) = ft.get_child("measure_direction", None) {
            direction = element_text(d);
        }
    }
    (frame, direction)
}

/// Three numbers of an attribute such as `xyz="0 0 0.1"`; `[0, 0, 0]` when the attribute is absent.
fn parse_triplet(text: Option<&str>, element: &str, field: &str) -> Result<[f64; 3], ModelError> {
    let mut out = [0.0; 3];
    if let Some(text) = text {
        let mut count = 0;
        for (k, token) in text.split_whitespace().enumerate() {
            if k >= 3 {
                return Err(ModelError::Urdf(format!(
                    "{element}: `{field}` has more than three numbers"
                )));
            }
            out[k] = token.parse::<f64>().map_err(|_| {
                ModelError::Urdf(format!("{element}: cannot parse `{field}` = `{text}`"))
            })?;
            count += 1;
        }
        if count != 3 {
            return Err(ModelError::Urdf(format!(
                "{element}: `{field}` needs three numbers"
            )));
        }
    }
    Ok(out)
}
