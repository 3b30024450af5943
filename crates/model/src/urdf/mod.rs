//! URDF → [`Model`]: the file parsed once into an XML tree, read into urdf-rs's types for the standard
//! elements and by a small pass for what urdf-rs ignores (presence of `<limit>`, force/torque `<sensor>`
//! elements).
//!
//! The loading steps, one file each, in the order [`load_str`] runs them (errors and warnings come in this
//! order too):
//! 1. [`texture`]: drop the `<texture/>` elements urdf-rs rejects; the text is parsed into an XML tree;
//!    [`element`]: the standard elements, as urdf-rs reads them;
//! 2. [`raw`]: the pass over the same tree for `<limit>` presence and force/torque sensors;
//! 3. [`links`]: validate every link (and the inertia edits, applied here) and build its spatial inertia;
//! 4. [`graph`]: validate every joint, find each link's parent joint and the one root;
//! 5. [`tree`]: depth-first from the root: one body per movable joint, fixed joints merged (inertias lumped,
//!    merged links kept as frames);
//! 6. [`frames`]: the frame list, the mimic targets and the force/torque sensors;
//!    [`ft`]: how each sensor's fixed joint splits its lumped body;
//! 7. [`assemble`]: lumped body inertias, massless-body warnings and the flat data of the algorithms.

mod assemble;
mod element;
mod frames;
mod ft;
mod graph;
mod links;
mod raw;
mod texture;
mod tree;

use std::path::Path;

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use crate::edits::InertiaEdits;
use crate::error::ModelError;
use crate::locks::JointLock;
use crate::model::Model;

/// Loads a model from a URDF file.
pub(crate) fn load_file(path: &Path) -> Result<Model, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|e| ModelError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    load_str(&text)
}

/// Loads a model from a URDF file with edited inertias.
pub(crate) fn load_file_edited(path: &Path, edits: &InertiaEdits) -> Result<Model, ModelError> {
    load_file_reduced(path, edits, &[])
}

/// Loads a model from a URDF file with edited inertias and locked joints.
pub(crate) fn load_file_reduced(
    path: &Path,
    edits: &InertiaEdits,
    locks: &[JointLock],
) -> Result<Model, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|e| ModelError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    load_str_reduced(&text, edits, locks)
}

/// Loads a model from URDF text.
pub(crate) fn load_str(text: &str) -> Result<Model, ModelError> {
    load_str_edited(text, &InertiaEdits::default())
}

/// Loads a model from URDF text, the link inertias edited by `edits` before lumping.
pub(crate) fn load_str_edited(text: &str, edits: &InertiaEdits) -> Result<Model, ModelError> {
    load_str_reduced(text, edits, &[])
}

/// Loads a model from URDF text, the link inertias edited by `edits` before lumping and the joints
/// matched by `locks` fixed at their positions ([`crate::locks`]).
pub(crate) fn load_str_reduced(
    text: &str,
    edits: &InertiaEdits,
    locks: &[JointLock],
) -> Result<Model, ModelError> {
    let text = texture::strip_textures_without_filename(text);
    let root: xml::Element = text
        .parse()
        .map_err(|e| ModelError::Urdf(format!("XML error: {e:?}")))?;
    let robot = element::read_robot(&root)?;
    let raw = raw::read_raw(&root)?;
    let version_ge_1_2 = version_at_least_1_2(robot.version.as_deref());
    let mut warnings: Vec<String> = Vec::new();
    if robot.links.is_empty() {
        return Err(ModelError::Empty);
    }
    let links = links::read_links(&robot, edits, &mut warnings)?;
    let graph = graph::read_joints(&robot, &links.index)?;
    let locked = crate::locks::resolve(&robot, locks)?;
    let options = tree::Options {
        version_ge_1_2,
        locked: &locked,
    };
    let mut tree = tree::build(&robot, &raw, &links, &graph, options, &mut warnings)?;
    let joint_index = frames::check_mimic_targets(&tree.joints)?;
    let merged = std::mem::take(&mut tree.merged_frames);
    let mut frames = frames::body_and_merged_frames(&tree.bodies, merged, &links);
    let total_mass = assemble::lump_inertias(&mut tree, &mut warnings);
    let ft_sensors = frames::ft_sensors(
        &robot,
        &raw,
        &links,
        &graph,
        &tree,
        &mut frames,
        &mut warnings,
    );
    let ft_sides = ft::sensor_sides(&robot, &links, &graph, &tree, &frames, &ft_sensors);
    for w in &warnings {
        tracing::warn!("{w}");
    }
    let named = assemble::Named {
        frames,
        joint_index,
        ft_sensors,
        ft_sides,
        warnings,
    };
    Ok(assemble::model(&robot, &graph, tree, total_mass, named))
}

/// Whether the `<robot version>` attribute is at least 1.2 (then a revolute or prismatic joint without
/// `<limit>` is unbounded without a warning); `false` when absent or unreadable.
fn version_at_least_1_2(version: Option<&str>) -> bool {
    version
        .and_then(|v| {
            let mut it = v.split('.');
            let major = it.next()?.trim().parse::<u32>().ok()?;
            let minor = it.next().unwrap_or("0").trim().parse::<u32>().ok()?;
            Some((major, minor) >= (1, 2))
        })
        .unwrap_or(false)
}

/// `Ok` when every value is finite, else [`ModelError::NonFinite`] naming `element` and `field`.
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

/// A URDF `<origin xyz rpy>` (m, rad) as `parent_H_child`. URDF rpy: `R = Rz(yaw) Ry(pitch) Rx(roll)`
/// (fixed axes x, y, z), which is nalgebra's `from_euler_angles`.
fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    let rot = UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    Isometry3::from_parts(Translation3::new(xyz[0], xyz[1], xyz[2]), rot)
}
