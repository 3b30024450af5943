//! URDF → [`Model`]: urdf-rs for the standard elements, a small XML pass for what urdf-rs ignores (presence of
//! `<limit>`, force/torque `<sensor>` elements).

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Isometry3, Matrix3, SymmetricEigen, Translation3, UnitQuaternion, Vector3};

use crate::error::ModelError;
use crate::model::{Body, Frame, FrameKind, FtSensor, Joint, JointKind, Mimic, Model};
use crate::spatial::Inertia;

/// Removes `<texture .../>` elements that have no `filename` attribute (allowed by the URDF XSD, rejected by
/// urdf-rs 0.10). Textures are visual-only and irrelevant to dynamics.
pub(crate) fn strip_textures_without_filename(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("<texture") {
        let after = &rest[start + "<texture".len()..];
        let is_tag = after
            .chars()
            .next()
            .is_some_and(|c| c.is_whitespace() || c == '/' || c == '>');
        let end = after.find('>');
        match (is_tag, end) {
            (true, Some(end)) => {
                let tag = &after[..end];
                let self_closing = tag.trim_end().ends_with('/');
                if self_closing && !tag.contains("filename") {
                    out.push_str(&rest[..start]);
                } else {
                    out.push_str(&rest[..start + "<texture".len() + end + 1]);
                }
                rest = &after[end + 1..];
            }
            _ => {
                out.push_str(&rest[..start + "<texture".len()]);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

struct RawSensor {
    name: String,
    joint: String,
    frame: String,
    direction: String,
    origin: Isometry3<f64>,
}

struct RawInfo {
    joints_with_limit: HashMap<String, bool>,
    sensors: Vec<RawSensor>,
}

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

fn check_finite(values: &[f64], element: &str, field: &str) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NonFinite {
            element: element.to_string(),
            field: field.to_string(),
        })
    }
}

fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    // URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z), which is nalgebra's from_euler_angles.
    let rot = UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    Isometry3::from_parts(Translation3::new(xyz[0], xyz[1], xyz[2]), rot)
}

fn element_text(e: &xml::Element) -> String {
    e.content_str().trim().to_string()
}

fn read_raw(text: &str) -> Result<RawInfo, ModelError> {
    let root: xml::Element = text
        .parse()
        .map_err(|e| ModelError::Urdf(format!("XML error: {e:?}")))?;
    let mut joints_with_limit = HashMap::new();
    let mut sensors: Vec<RawSensor> = Vec::new();
    for joint in root.get_children("joint", None) {
        if let Some(name) = joint.get_attribute("name", None) {
            joints_with_limit.insert(name.to_string(), joint.get_child("limit", None).is_some());
        }
    }
    let ft_details = |sensor: &xml::Element| -> (String, String) {
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
    };
    // iDynTree-style top-level sensors.
    for sensor in root.get_children("sensor", None) {
        if sensor.get_attribute("type", None) != Some("force_torque") {
            continue;
        }
        let name = sensor
            .get_attribute("name", None)
            .unwrap_or_default()
            .to_string();
        let Some(joint) = sensor
            .get_child("parent", None)
            .and_then(|p| p.get_attribute("joint", None))
        else {
            continue;
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
        sensors.push(RawSensor {
            name,
            joint: joint.to_string(),
            frame,
            direction,
            origin,
        });
    }
    // Gazebo-style sensors on a joint (`<gazebo reference="joint"><sensor type="force_torque">`).
    for gazebo in root.get_children("gazebo", None) {
        let Some(reference) = gazebo.get_attribute("reference", None) else {
            continue;
        };
        for sensor in gazebo.get_children("sensor", None) {
            if sensor.get_attribute("type", None) != Some("force_torque") {
                continue;
            }
            let name = sensor
                .get_attribute("name", None)
                .unwrap_or(reference)
                .to_string();
            // One sensor per joint: the iDynTree-style declaration wins (iCub files declare both, sometimes
            // with different names).
            if sensors
                .iter()
                .any(|s| s.name == name || s.joint == reference)
            {
                continue;
            }
            let element = format!("sensor `{name}`");
            let origin = match sensor.get_child("pose", None) {
                Some(p) => {
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
                    check_finite(&values, &element, "pose")?;
                    pose(
                        [values[0], values[1], values[2]],
                        [values[3], values[4], values[5]],
                    )
                }
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
    }
    Ok(RawInfo {
        joints_with_limit,
        sensors,
    })
}

struct LinkData {
    inertia: Inertia,
}

/// Loads a model from a URDF file.
pub(crate) fn load_file(path: &Path) -> Result<Model, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|e| ModelError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    load_str(&text)
}

/// Loads a model from URDF text.
pub(crate) fn load_str(text: &str) -> Result<Model, ModelError> {
    let text = strip_textures_without_filename(text);
    let robot = urdf_rs::read_from_string(&text).map_err(|e| ModelError::Urdf(e.to_string()))?;
    let raw = read_raw(&text)?;
    let version_ge_1_2 = robot
        .version
        .as_deref()
        .and_then(|v| {
            let mut it = v.split('.');
            let major = it.next()?.trim().parse::<u32>().ok()?;
            let minor = it.next().unwrap_or("0").trim().parse::<u32>().ok()?;
            Some((major, minor) >= (1, 2))
        })
        .unwrap_or(false);
    let mut warnings: Vec<String> = Vec::new();

    if robot.links.is_empty() {
        return Err(ModelError::Empty);
    }
    // ---- links ----
    let mut link_index: HashMap<String, usize> = HashMap::new();
    let mut links: Vec<LinkData> = Vec::with_capacity(robot.links.len());
    for (k, link) in robot.links.iter().enumerate() {
        if link_index.insert(link.name.clone(), k).is_some() {
            return Err(ModelError::DuplicateLink {
                link: link.name.clone(),
            });
        }
        let element = format!("link `{}`", link.name);
        let inertial = &link.inertial;
        let m = inertial.mass.value;
        check_finite(&[m], &element, "mass")?;
        check_finite(&inertial.origin.xyz.0, &element, "inertial origin xyz")?;
        check_finite(&inertial.origin.rpy.0, &element, "inertial origin rpy")?;
        let i = &inertial.inertia;
        let iv = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
        check_finite(&iv, &element, "inertia")?;
        if m < 0.0 {
            return Err(ModelError::NegativeMass {
                link: link.name.clone(),
                mass: m,
            });
        }
        let i_frame = Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        );
        let eig = SymmetricEigen::new(i_frame).eigenvalues;
        let (mut lo, mut hi) = (eig[0], eig[0]);
        for e in eig.iter() {
            lo = lo.min(*e);
            hi = hi.max(*e);
        }
        let tol = 1e-9 * hi.abs() + 1e-12;
        if lo < -tol {
            return Err(ModelError::NegativeInertia {
                link: link.name.clone(),
                eigenvalue: lo,
            });
        }
        if hi > 0.0 {
            // Triangle inequalities on the principal moments.
            let mut sorted = [eig[0], eig[1], eig[2]];
            sorted.sort_by(f64::total_cmp);
            if sorted[0] + sorted[1] < sorted[2] - tol {
                warnings.push(format!(
                    "link `{}`: inertia is not physically consistent (principal moments {:.6e}, {:.6e}, {:.6e} violate the triangle inequality)",
                    link.name, sorted[0], sorted[1], sorted[2]
                ));
            }
            if m == 0.0 {
                warnings.push(format!(
                    "link `{}`: zero mass but non-zero rotational inertia",
                    link.name
                ));
            }
        } else if m > 0.0 {
            warnings.push(format!(
                "link `{}`: point mass ({m} kg with zero rotational inertia)",
                link.name
            ));
        }
        let origin = pose(inertial.origin.xyz.0, inertial.origin.rpy.0);
        let r = origin.rotation.to_rotation_matrix().into_inner();
        let i_com = r * i_frame * r.transpose();
        links.push(LinkData {
            inertia: Inertia::from_com(m, &origin.translation.vector, &i_com),
        });
    }

    // ---- joints ----
    let mut joint_names: HashMap<&str, usize> = HashMap::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
    for (k, joint) in robot.joints.iter().enumerate() {
        if joint_names.insert(joint.name.as_str(), k).is_some() {
            return Err(ModelError::DuplicateJoint {
                joint: joint.name.clone(),
            });
        }
        let element = format!("joint `{}`", joint.name);
        match joint.joint_type {
            urdf_rs::JointType::Revolute
            | urdf_rs::JointType::Continuous
            | urdf_rs::JointType::Prismatic
            | urdf_rs::JointType::Fixed => {}
            ref other => {
                return Err(ModelError::UnsupportedJoint {
                    joint: joint.name.clone(),
                    kind: format!("{other:?}").to_lowercase(),
                })
            }
        }
        check_finite(&joint.origin.xyz.0, &element, "origin xyz")?;
        check_finite(&joint.origin.rpy.0, &element, "origin rpy")?;
        check_finite(&joint.axis.xyz.0, &element, "axis")?;
        let lim = &joint.limit;
        for (v, f) in [
            (lim.lower, "limit lower"),
            (lim.upper, "limit upper"),
            (lim.effort, "limit effort"),
            (lim.velocity, "limit velocity"),
        ] {
            if v.is_nan() {
                return Err(ModelError::NonFinite {
                    element: element.clone(),
                    field: f.to_string(),
                });
            }
        }
        let parent =
            *link_index
                .get(&joint.parent.link)
                .ok_or_else(|| ModelError::MissingLink {
                    joint: joint.name.clone(),
                    link: joint.parent.link.clone(),
                })?;
        let child = *link_index
            .get(&joint.child.link)
            .ok_or_else(|| ModelError::MissingLink {
                joint: joint.name.clone(),
                link: joint.child.link.clone(),
            })?;
        if let Some(previous) = parent_joint[child] {
            return Err(ModelError::MultipleParents {
                link: joint.child.link.clone(),
                first: robot.joints[previous].name.clone(),
                second: joint.name.clone(),
            });
        }
        if parent == child {
            return Err(ModelError::Loop {
                link: joint.child.link.clone(),
            });
        }
        parent_joint[child] = Some(k);
        children[parent].push(k);
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    if roots.is_empty() {
        return Err(ModelError::NoRoot);
    }
    if roots.len() > 1 {
        return Err(ModelError::MultipleRoots {
            links: roots.iter().map(|&l| robot.links[l].name.clone()).collect(),
        });
    }
    let root = roots[0];

    // ---- depth-first traversal: bodies, joints, frames ----
    struct Pending {
        link: usize,
        parent_body: usize,
        /// `parent_body_H_link` (at zero position of the joint, if movable).
        placement: Isometry3<f64>,
        /// URDF index of the movable joint that connects the link, if any.
        joint: Option<usize>,
    }
    let mut bodies: Vec<Body> = Vec::new();
    let mut body_inertia: Vec<Inertia> = Vec::new();
    let mut joints: Vec<Joint> = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut placement_rot = Vec::new();
    let mut placement_pos = Vec::new();
    let mut axes = Vec::new();
    let mut prismatic = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    let mut merged_frames: Vec<Frame> = Vec::new();
    let mut link_frame: Vec<Option<(usize, Isometry3<f64>)>> = vec![None; links.len()];

    bodies.push(Body {
        name: robot.links[root].name.clone(),
        parent: None,
        joint: None,
        placement_in_parent: Isometry3::identity(),
        mass: 0.0,
        com: Vector3::zeros(),
        inertia_at_com: Matrix3::zeros(),
    });
    body_inertia.push(Inertia::zero());
    parent.push(usize::MAX);
    placement_rot.push(Matrix3::identity());
    placement_pos.push(Vector3::zeros());
    axes.push(Vector3::zeros());
    prismatic.push(false);
    let mut stack = vec![Pending {
        link: root,
        parent_body: 0,
        placement: Isometry3::identity(),
        joint: None,
    }];
    let mut visited = 0usize;
    while let Some(p) = stack.pop() {
        visited += 1;
        let (body, placement) = match p.joint {
            None => (p.parent_body, p.placement),
            Some(jk) => {
                let joint = &robot.joints[jk];
                let element = format!("joint `{}`", joint.name);
                let axis_raw =
                    Vector3::new(joint.axis.xyz[0], joint.axis.xyz[1], joint.axis.xyz[2]);
                let norm = axis_raw.norm();
                if norm < 1e-12 {
                    return Err(ModelError::ZeroAxis {
                        joint: joint.name.clone(),
                    });
                }
                if (norm - 1.0).abs() > 1e-6 {
                    warnings.push(format!("{element}: axis of length {norm} normalised"));
                }
                let axis = axis_raw / norm;
                let (kind, is_prismatic) = match joint.joint_type {
                    urdf_rs::JointType::Revolute => (JointKind::Revolute, false),
                    urdf_rs::JointType::Continuous => (JointKind::Continuous, false),
                    _ => (JointKind::Prismatic, true),
                };
                let has_limit = raw
                    .joints_with_limit
                    .get(&joint.name)
                    .copied()
                    .unwrap_or(false);
                let (mut lower, mut upper, mut velocity, mut effort) = (
                    joint.limit.lower,
                    joint.limit.upper,
                    joint.limit.velocity,
                    joint.limit.effort,
                );
                if kind == JointKind::Continuous {
                    lower = f64::NEG_INFINITY;
                    upper = f64::INFINITY;
                }
                if !has_limit {
                    if kind != JointKind::Continuous && !version_ge_1_2 {
                        warnings.push(format!(
                            "{element}: {} joint without <limit>; position, velocity and effort treated as unbounded (urdf-rs would report zero limits)",
                            kind.as_str()
                        ));
                    }
                    lower = f64::NEG_INFINITY;
                    upper = f64::INFINITY;
                    velocity = f64::INFINITY;
                    effort = f64::INFINITY;
                }
                let mimic = joint.mimic.as_ref().map(|m| Mimic {
                    joint: m.joint.clone(),
                    multiplier: m.multiplier.unwrap_or(1.0),
                    offset: m.offset.unwrap_or(0.0),
                });
                if let Some(m) = &mimic {
                    check_finite(&[m.multiplier, m.offset], &element, "mimic")?;
                }
                let body = bodies.len();
                bodies.push(Body {
                    name: joint.child.link.clone(),
                    parent: Some(p.parent_body),
                    joint: Some(joints.len()),
                    placement_in_parent: p.placement,
                    mass: 0.0,
                    com: Vector3::zeros(),
                    inertia_at_com: Matrix3::zeros(),
                });
                body_inertia.push(Inertia::zero());
                parent.push(p.parent_body);
                placement_rot.push(p.placement.rotation.to_rotation_matrix().into_inner());
                placement_pos.push(p.placement.translation.vector);
                axes.push(axis);
                prismatic.push(is_prismatic);
                joints.push(Joint {
                    name: joint.name.clone(),
                    kind,
                    axis,
                    lower,
                    upper,
                    velocity_limit: velocity,
                    effort_limit: effort,
                    mimic,
                    parent_link: joint.parent.link.clone(),
                    child_link: joint.child.link.clone(),
                });
                (body, Isometry3::identity())
            }
        };
        link_frame[p.link] = Some((body, placement));
        let lumped = links[p.link].inertia.transformed(
            &placement.rotation.to_rotation_matrix().into_inner(),
            &placement.translation.vector,
        );
        body_inertia[body].add(&lumped);
        if p.joint.is_none() && p.link != root {
            merged_frames.push(Frame {
                name: robot.links[p.link].name.clone(),
                link: body,
                placement,
                kind: FrameKind::MergedLink,
            });
        }
        // Push children in reverse so that they are visited in file order.
        for &jk in children[p.link].iter().rev() {
            let joint = &robot.joints[jk];
            let child = link_index[&joint.child.link];
            let origin = placement * pose(joint.origin.xyz.0, joint.origin.rpy.0);
            let movable = joint.joint_type != urdf_rs::JointType::Fixed;
            stack.push(Pending {
                link: child,
                parent_body: body,
                placement: origin,
                joint: movable.then_some(jk),
            });
        }
    }
    if visited != links.len() {
        let on_loop = (0..links.len())
            .find(|&l| link_frame[l].is_none())
            .map(|l| robot.links[l].name.clone())
            .unwrap_or_default();
        return Err(ModelError::Loop { link: on_loop });
    }

    // Body frames first, then merged links.
    for b in &bodies {
        frames.push(Frame {
            name: b.name.clone(),
            link: frames.len(),
            placement: Isometry3::identity(),
            kind: FrameKind::Body,
        });
    }
    frames.extend(merged_frames);
    let mut frame_index: HashMap<String, usize> = HashMap::new();
    for (k, f) in frames.iter().enumerate() {
        frame_index.insert(f.name.clone(), k);
    }

    // Mimic targets must be movable joints.
    let joint_index: HashMap<String, usize> = joints
        .iter()
        .enumerate()
        .map(|(k, j)| (j.name.clone(), k))
        .collect();
    for j in &joints {
        if let Some(m) = &j.mimic {
            if !joint_index.contains_key(&m.joint) {
                return Err(ModelError::MimicTarget {
                    joint: j.name.clone(),
                    target: m.joint.clone(),
                });
            }
        }
    }

    // Lumped inertias.
    let mut total_mass = 0.0;
    for (k, b) in bodies.iter_mut().enumerate() {
        let inertia = &body_inertia[k];
        b.mass = inertia.m;
        b.com = inertia.com();
        b.inertia_at_com = inertia.inertia_at_com();
        total_mass += inertia.m;
    }
    // Massless bodies: the joint moving them must move some inertia further down, otherwise forward dynamics
    // is singular.
    let mut subtree_mass = body_inertia
        .iter()
        .map(|i| i.m + i.i.trace())
        .collect::<Vec<_>>();
    for k in (1..bodies.len()).rev() {
        let p = parent[k];
        subtree_mass[p] += subtree_mass[k];
    }
    for k in 1..bodies.len() {
        if body_inertia[k].m == 0.0 {
            let joint = &joints[k - 1].name;
            if subtree_mass[k] == 0.0 {
                warnings.push(format!(
                    "link `{}` (moved by joint `{joint}`) and everything below it are massless: the mass matrix is singular and forward dynamics will fail",
                    bodies[k].name
                ));
            } else {
                warnings.push(format!(
                    "link `{}` (moved by joint `{joint}`) is massless",
                    bodies[k].name
                ));
            }
        }
    }

    // Force/torque sensors.
    let mut ft_sensors = Vec::new();
    for s in &raw.sensors {
        let Some(&jk) = joint_names.get(s.joint.as_str()) else {
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
        let frame = match frame_index.get(&s.name) {
            Some(&f) => f,
            None => {
                let link = match s.frame.as_str() {
                    "parent" => &joint.parent.link,
                    _ => &joint.child.link,
                };
                let Some((body, placement)) = link_frame[link_index[link]] else {
                    continue;
                };
                let placement = if s.frame == "sensor" {
                    placement * s.origin
                } else {
                    placement
                };
                frames.push(Frame {
                    name: s.name.clone(),
                    link: body,
                    placement,
                    kind: FrameKind::Sensor,
                });
                frame_index.insert(s.name.clone(), frames.len() - 1);
                frames.len() - 1
            }
        };
        ft_sensors.push(FtSensor {
            name: s.name.clone(),
            joint: s.joint.clone(),
            frame: crate::model::FrameId(frame),
            parent_link: joint.parent.link.clone(),
            child_link: joint.child.link.clone(),
            measure_direction: s.direction.clone(),
        });
    }

    for w in &warnings {
        tracing::warn!("{w}");
    }
    let frame_rot = frames
        .iter()
        .map(|f| f.placement.rotation.to_rotation_matrix().into_inner())
        .collect();
    let frame_pos = frames
        .iter()
        .map(|f| f.placement.translation.vector)
        .collect();
    let axis_in_parent = placement_rot
        .iter()
        .zip(&axes)
        .map(|(r, a)| r * a)
        .collect();
    let placement_k = placement_rot
        .iter()
        .zip(&axes)
        .map(|(r, a)| r * crate::spatial::skew(a))
        .collect();
    let placement_k2 = placement_rot
        .iter()
        .zip(&axes)
        .map(|(r, a)| {
            let k = crate::spatial::skew(a);
            r * k * k
        })
        .collect();
    Ok(Model {
        name: robot.name.clone(),
        root_link: robot.links[root].name.clone(),
        joints,
        bodies,
        frames,
        frame_index,
        joint_index,
        ft_sensors,
        warnings,
        total_mass,
        gravity: Vector3::new(0.0, 0.0, -crate::model::STANDARD_GRAVITY),
        parent,
        placement_rot,
        placement_pos,
        axis_in_parent,
        placement_k,
        placement_k2,
        prismatic,
        body_com: body_inertia.iter().map(|i| i.com()).collect(),
        body_inertia_com: body_inertia.iter().map(|i| i.inertia_at_com()).collect(),
        inertia: body_inertia,
        frame_rot,
        frame_pos,
    })
}
