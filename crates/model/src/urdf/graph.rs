//! Joints: validation of every `<joint>`, the parent joint of each link and the one root link.

use std::collections::HashMap;

use super::check_finite;
use crate::error::ModelError;

/// The kinematic graph of the URDF (indices are file order).
pub(super) struct Graph<'a> {
    /// Joint name → index in file order.
    pub(super) joint_names: HashMap<&'a str, usize>,
    /// Per link, the joints of which it is the parent, in file order.
    pub(super) children: Vec<Vec<usize>>,
    /// The link that is no joint's child.
    pub(super) root: usize,
}

/// Validates every joint in file order (unique name, supported type, finite numbers, existing links, at most
/// one parent joint per link, no joint from a link to itself), then finds the one root link.
pub(super) fn read_joints<'a>(
    robot: &'a urdf_rs::Robot,
    link_index: &HashMap<String, usize>,
) -> Result<Graph<'a>, ModelError> {
    let n_links = robot.links.len();
    let mut joint_names: HashMap<&str, usize> = HashMap::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; n_links];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n_links];
    for (k, joint) in robot.joints.iter().enumerate() {
        if joint_names.insert(joint.name.as_str(), k).is_some() {
            return Err(ModelError::DuplicateJoint {
                joint: joint.name.clone(),
            });
        }
        check_joint(joint)?;
        let parent = link_of(joint, &joint.parent.link, link_index)?;
        let child = link_of(joint, &joint.child.link, link_index)?;
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
    let root = find_root(robot, &parent_joint)?;
    Ok(Graph {
        joint_names,
        children,
        root,
    })
}

/// A supported type (revolute, continuous, prismatic, fixed) and finite origin, axis and limits (limits may
/// be infinite, not NaN).
fn check_joint(joint: &urdf_rs::Joint) -> Result<(), ModelError> {
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
    Ok(())
}

/// Index of the link `link` that `joint` names as parent or child.
fn link_of(
    joint: &urdf_rs::Joint,
    link: &str,
    link_index: &HashMap<String, usize>,
) -> Result<usize, ModelError> {
    link_index
        .get(link)
        .copied()
        .ok_or_else(|| ModelError::MissingLink {
            joint: joint.name.clone(),
            link: link.to_string(),
        })
}

/// The one link without a parent joint.
fn find_root(robot: &urdf_rs::Robot, parent_joint: &[Option<usize>]) -> Result<usize, ModelError> {
    let roots: Vec<usize> = (0..parent_joint.len())
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
    Ok(roots[0])
}
