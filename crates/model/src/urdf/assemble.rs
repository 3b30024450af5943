//! The last step: lumped body inertias, the massless-body warnings and the flat data of the algorithms.

use std::collections::HashMap;

use nalgebra::Vector3;

use super::frames::Frames;
use super::graph::Graph;
use super::tree::Tree;
use crate::model::{FtSensor, FtSensorSide, Model, STANDARD_GRAVITY};
use crate::spatial::skew;

/// Writes each body's lumped mass (kg), CoM (m, body frame) and rotational inertia about the CoM (kg·m²)
/// and warns about massless bodies; returns the total mass (kg).
pub(super) fn lump_inertias(tree: &mut Tree, warnings: &mut Vec<String>) -> f64 {
    let mut total_mass = 0.0;
    for (k, b) in tree.bodies.iter_mut().enumerate() {
        let inertia = &tree.body_inertia[k];
        b.mass = inertia.m;
        b.com = inertia.com();
        b.inertia_at_com = inertia.inertia_at_com();
        total_mass += inertia.m;
    }
    massless_warnings(tree, warnings);
    total_mass
}

/// Massless bodies: the joint moving them must move some inertia further down (the subtree's `m + tr I`
/// is not zero), otherwise the mass matrix is singular and forward dynamics fails.
fn massless_warnings(tree: &Tree, warnings: &mut Vec<String>) {
    let mut subtree_mass = tree
        .body_inertia
        .iter()
        .map(|i| i.m + i.i.trace())
        .collect::<Vec<_>>();
    for k in (1..tree.bodies.len()).rev() {
        let p = tree.parent[k];
        subtree_mass[p] += subtree_mass[k];
    }
    for (k, inertia) in tree.body_inertia.iter().enumerate().skip(1) {
        if inertia.m == 0.0 {
            let joint = &tree.joints[k - 1].name;
            if subtree_mass[k] == 0.0 {
                warnings.push(format!(
                    "link `{}` (moved by joint `{joint}`) and everything below it are massless: the mass matrix is singular and forward dynamics will fail",
                    tree.bodies[k].name
                ));
            } else {
                warnings.push(format!(
                    "link `{}` (moved by joint `{joint}`) is massless",
                    tree.bodies[k].name
                ));
            }
        }
    }
}

/// What the model names: frames, joints by name, sensors and the loading warnings.
pub(super) struct Named {
    pub(super) frames: Frames,
    pub(super) joint_index: HashMap<String, usize>,
    pub(super) ft_sensors: Vec<FtSensor>,
    pub(super) ft_sides: Vec<FtSensorSide>,
    pub(super) warnings: Vec<String>,
}

/// The model, with the flat per-body data of the algorithms: the joint axis in the parent frame
/// `R_p a`, and `R_p K`, `R_p K²` with `K = skew(a)` for Rodrigues' formula
/// `R(q) = R_p (1 + sin q K + (1 − cos q) K²)`.
pub(super) fn model(
    robot: &urdf_rs::Robot,
    graph: &Graph,
    tree: Tree,
    total_mass: f64,
    named: Named,
) -> Model {
    let frames = named.frames.list;
    let frame_rot = frames
        .iter()
        .map(|f| f.placement.rotation.to_rotation_matrix().into_inner())
        .collect();
    let frame_pos = frames
        .iter()
        .map(|f| f.placement.translation.vector)
        .collect();
    let rot_axes = || tree.placement_rot.iter().zip(&tree.axes);
    let axis_in_parent = rot_axes().map(|(r, a)| r * a).collect();
    let placement_k = rot_axes().map(|(r, a)| r * skew(a)).collect();
    let placement_k2 = rot_axes()
        .map(|(r, a)| {
            let k = skew(a);
            r * k * k
        })
        .collect();
    let body_inertia = tree.body_inertia;
    Model {
        name: robot.name.clone(),
        root_link: robot.links[graph.root].name.clone(),
        joints: tree.joints,
        bodies: tree.bodies,
        frames,
        frame_index: named.frames.index,
        joint_index: named.joint_index,
        ft_sensors: named.ft_sensors,
        ft_sides: named.ft_sides,
        warnings: named.warnings,
        total_mass,
        gravity: Vector3::new(0.0, 0.0, -STANDARD_GRAVITY),
        parent: tree.parent,
        placement_rot: tree.placement_rot,
        placement_pos: tree.placement_pos,
        axis_in_parent,
        placement_k,
        placement_k2,
        prismatic: tree.prismatic,
        body_com: body_inertia.iter().map(|i| i.com()).collect(),
        body_inertia_com: body_inertia.iter().map(|i| i.inertia_at_com()).collect(),
        inertia: body_inertia,
        frame_rot,
        frame_pos,
    }
}
