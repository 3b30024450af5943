//! The depth-first traversal from the root: one body per movable joint, fixed joints merged into the body
//! above them (inertias lumped, merged links kept as frames).

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Matrix3, Vector3};

use super::graph::Graph;
use super::links::Links;
use super::raw::RawInfo;
use super::{check_finite, pose};
use crate::error::ModelError;
use crate::model::{Body, Frame, FrameKind, Joint, JointKind, Mimic};
use crate::spatial::Inertia;

/// Bodies and movable joints in model order (depth-first from the root, children in file order), with the
/// per-body data the algorithms need (index = body; body `i > 0` is moved by joint `i − 1`).
pub(super) struct Tree {
    pub(super) bodies: Vec<Body>,
    /// Lumped spatial inertia of each body about its frame.
    pub(super) body_inertia: Vec<Inertia>,
    pub(super) joints: Vec<Joint>,
    /// Parent body (`usize::MAX` for the root).
    pub(super) parent: Vec<usize>,
    /// Rotation and translation of `parent_body_H_body` at zero joint position.
    pub(super) placement_rot: Vec<Matrix3<f64>>,
    pub(super) placement_pos: Vec<Vector3<f64>>,
    /// Unit joint axis in the body frame (zero for the root).
    pub(super) axes: Vec<Vector3<f64>>,
    pub(super) prismatic: Vec<bool>,
    /// Frames of the links merged through fixed joints, in traversal order.
    pub(super) merged_frames: Vec<Frame>,
    /// Per URDF link: the body it belongs to and `body_H_link`.
    pub(super) link_frame: Vec<Option<(usize, Isometry3<f64>)>>,
}

/// A link waiting to be visited.
struct Pending {
    link: usize,
    parent_body: usize,
    /// `parent_body_H_link` (at zero position of the joint, if movable).
    placement: Isometry3<f64>,
    /// URDF index of the movable joint that connects the link, if any.
    joint: Option<usize>,
}

/// How [`build`] treats the joints.
pub(super) struct Options<'a> {
    /// `<robot version>` ≥ 1.2: revolute and prismatic joints without `<limit>` are unbounded silently.
    pub(super) version_ge_1_2: bool,
    /// Locked joints (URDF index → position): merged like fixed joints at `origin · motion(q)`.
    pub(super) locked: &'a BTreeMap<usize, f64>,
}

/// Walks the tree depth-first from the root, children in file order.
///
/// # Errors
/// [`ModelError::ZeroAxis`], [`ModelError::NonFinite`] (mimic), and [`ModelError::Loop`] when some links
/// are not reached from the root (they form a closed chain).
pub(super) fn build(
    robot: &urdf_rs::Robot,
    raw: &RawInfo,
    links: &Links,
    graph: &Graph,
    options: Options<'_>,
    warnings: &mut Vec<String>,
) -> Result<Tree, ModelError> {
    let version_ge_1_2 = options.version_ge_1_2;
    let root = graph.root;
    let mut tree = Tree::with_root(robot.links[root].name.clone(), robot.links.len());
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
                let has_limit = raw.has_limit(&joint.name);
                let (joint, axis) = movable_joint(joint, has_limit, version_ge_1_2, warnings)?;
                (
                    tree.push_body(p.parent_body, p.placement, joint, axis),
                    Isometry3::identity(),
                )
            }
        };
        tree.add_link(p.link, body, placement, &links.inertia[p.link]);
        if p.joint.is_none() && p.link != root {
            tree.merged_frames.push(Frame {
                name: robot.links[p.link].name.clone(),
                link: body,
                placement,
                kind: FrameKind::MergedLink,
                attached_to: None,
            });
        }
        // Push children in reverse so that they are visited in file order.
        for &jk in graph.children[p.link].iter().rev() {
            let joint = &robot.joints[jk];
            let child = links.index[&joint.child.link];
            let mut origin = placement * pose(joint.origin.xyz.0, joint.origin.rpy.0);
            if let Some(&q) = options.locked.get(&jk) {
                origin *= crate::locks::joint_motion(joint, q)?;
            }
            let movable =
                joint.joint_type != urdf_rs::JointType::Fixed && !options.locked.contains_key(&jk);
            stack.push(Pending {
                link: child,
                parent_body: body,
                placement: origin,
                joint: movable.then_some(jk),
            });
        }
    }
    if visited != robot.links.len() {
        return Err(ModelError::Loop {
            link: tree.first_unreached_link(robot),
        });
    }
    Ok(tree)
}

impl Tree {
    /// The tree with only the root body (massless until its links are added).
    fn with_root(name: String, n_links: usize) -> Tree {
        Tree {
            bodies: vec![Body {
                name,
                parent: None,
                joint: None,
                placement_in_parent: Isometry3::identity(),
                mass: 0.0,
                com: Vector3::zeros(),
                inertia_at_com: Matrix3::zeros(),
            }],
            body_inertia: vec![Inertia::zero()],
            joints: Vec::new(),
            parent: vec![usize::MAX],
            placement_rot: vec![Matrix3::identity()],
            placement_pos: vec![Vector3::zeros()],
            axes: vec![Vector3::zeros()],
            prismatic: vec![false],
            merged_frames: Vec::new(),
            link_frame: vec![None; n_links],
        }
    }

    /// Appends the body moved by `joint` (unit `axis` in the body frame), placed at `parent_body_H_body` =
    /// `placement`; returns its index. Its inertia is zero until its links are added.
    fn push_body(
        &mut self,
        parent_body: usize,
        placement: Isometry3<f64>,
        joint: Joint,
        axis: Vector3<f64>,
    ) -> usize {
        let body = self.bodies.len();
        self.bodies.push(Body {
            name: joint.child_link.clone(),
            parent: Some(parent_body),
            joint: Some(self.joints.len()),
            placement_in_parent: placement,
            mass: 0.0,
            com: Vector3::zeros(),
            inertia_at_com: Matrix3::zeros(),
        });
        self.body_inertia.push(Inertia::zero());
        self.parent.push(parent_body);
        self.placement_rot
            .push(placement.rotation.to_rotation_matrix().into_inner());
        self.placement_pos.push(placement.translation.vector);
        self.axes.push(axis);
        self.prismatic.push(joint.kind == JointKind::Prismatic);
        self.joints.push(joint);
        body
    }

    /// Records that URDF link `link` belongs to `body` at `body_H_link` = `placement` and lumps its inertia
    /// into the body's: `I_body += X* I_link` (the inertia expressed in the body frame).
    fn add_link(&mut self, link: usize, body: usize, placement: Isometry3<f64>, inertia: &Inertia) {
        self.link_frame[link] = Some((body, placement));
        let lumped = inertia.transformed(
            &placement.rotation.to_rotation_matrix().into_inner(),
            &placement.translation.vector,
        );
        self.body_inertia[body].add(&lumped);
    }

    /// Name of the first URDF link (file order) not reached from the root: a link of a closed chain.
    fn first_unreached_link(&self, robot: &urdf_rs::Robot) -> String {
        (0..robot.links.len())
            .find(|&l| self.link_frame[l].is_none())
            .map(|l| robot.links[l].name.clone())
            .unwrap_or_default()
    }
}

/// The model joint for a movable URDF joint, and its unit axis. A non-unit axis is normalised (warning);
/// continuous joints are unbounded; a joint without `<limit>` is unbounded in position, velocity and effort
/// (with a warning for revolute and prismatic joints before URDF 1.2, where urdf-rs reports zero limits).
fn movable_joint(
    joint: &urdf_rs::Joint,
    has_limit: bool,
    version_ge_1_2: bool,
    warnings: &mut Vec<String>,
) -> Result<(Joint, Vector3<f64>), ModelError> {
    let element = format!("joint `{}`", joint.name);
    let axis_raw = Vector3::new(joint.axis.xyz[0], joint.axis.xyz[1], joint.axis.xyz[2]);
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
    let kind = match joint.joint_type {
        urdf_rs::JointType::Revolute => JointKind::Revolute,
        urdf_rs::JointType::Continuous => JointKind::Continuous,
        _ => JointKind::Prismatic,
    };
    let [lower, upper, velocity, effort] =
        limits(joint, kind, has_limit, version_ge_1_2, &element, warnings);
    let mimic = joint.mimic.as_ref().map(|m| Mimic {
        joint: m.joint.clone(),
        multiplier: m.multiplier.unwrap_or(1.0),
        offset: m.offset.unwrap_or(0.0),
    });
    if let Some(m) = &mimic {
        check_finite(&[m.multiplier, m.offset], &element, "mimic")?;
    }
    let joint = Joint {
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
    };
    Ok((joint, axis))
}

/// `[lower, upper, velocity, effort]` limits (rad or m, rad/s or m/s, N·m or N) of a movable joint: as
/// declared, position unbounded for continuous joints, everything unbounded without `<limit>`.
fn limits(
    joint: &urdf_rs::Joint,
    kind: JointKind,
    has_limit: bool,
    version_ge_1_2: bool,
    element: &str,
    warnings: &mut Vec<String>,
) -> [f64; 4] {
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
    [lower, upper, velocity, effort]
}
