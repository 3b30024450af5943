//! How the fixed joint of each force/torque sensor splits the lumped model.
//!
//! An FT sensor is a fixed joint that cuts the robot into a parent side and a child side [Traversaro 2017,
//! §4.3.1, §4.5]. Lumping merged the two links of that joint into one body, so the inertia of the child-side
//! links of the host body is kept here, with the bodies hanging from the child side and, per frame, the side
//! it lies on; [`KinDyn::ft_sensor_wrenches`](crate::KinDyn::ft_sensor_wrenches) needs nothing else.

use super::frames::Frames;
use super::graph::Graph;
use super::links::Links;
use super::tree::Tree;
use crate::model::{FtSensor, FtSensorSide};
use crate::spatial::Inertia;

/// One [`FtSensorSide`] per sensor, same order.
pub(super) fn sensor_sides(
    robot: &urdf_rs::Robot,
    links: &Links,
    graph: &Graph,
    tree: &Tree,
    frames: &Frames,
    sensors: &[FtSensor],
) -> Vec<FtSensorSide> {
    sensors
        .iter()
        .map(|s| sensor_side(robot, links, graph, tree, frames, s))
        .collect()
}

fn sensor_side(
    robot: &urdf_rs::Robot,
    links: &Links,
    graph: &Graph,
    tree: &Tree,
    frames: &Frames,
    sensor: &FtSensor,
) -> FtSensorSide {
    let child = links.index[&sensor.child_link];
    let child_side = descendants(robot, links, graph, child);
    // `tree::build` reaches every link (or fails with `ModelError::Loop`), so every link has a body.
    let body_of = |l: usize| tree.link_frame[l].map_or(0, |(b, _)| b);
    let host = body_of(child);
    let mut inertia = Inertia::zero();
    for (l, _) in child_side.iter().enumerate().filter(|(_, &c)| c) {
        if let Some((b, placement)) = tree.link_frame[l] {
            if b == host {
                let r = placement.rotation.to_rotation_matrix().into_inner();
                inertia.add(&links.inertia[l].transformed(&r, &placement.translation.vector));
            }
        }
    }
    let child_bodies = (1..tree.bodies.len())
        .filter(|&k| tree.parent[k] == host && child_side[links.index[&tree.bodies[k].name]])
        .collect();
    FtSensorSide {
        host,
        mass: inertia.m,
        com: inertia.com(),
        inertia_at_com: inertia.inertia_at_com(),
        child_bodies,
        child_side_frame: frames.links.iter().map(|&l| child_side[l]).collect(),
        child_to_parent: sensor.measure_direction != "parent_to_child",
    }
}

/// Per URDF link: whether it is `link` or below it.
fn descendants(robot: &urdf_rs::Robot, links: &Links, graph: &Graph, link: usize) -> Vec<bool> {
    let mut marked = vec![false; robot.links.len()];
    let mut stack = vec![link];
    while let Some(l) = stack.pop() {
        marked[l] = true;
        for &jk in &graph.children[l] {
            stack.push(links.index[&robot.joints[jk].child.link]);
        }
    }
    marked
}
