//! `stride model feet <URDF>`: each foot's sole frame and rectangle proposed from the lowest flat patch
//! of its collision geometry at the zero posture, compared with its visual geometry.
//!
//! Supported geometry: boxes, cylinders, spheres (their lowest points, e.g. corner spheres), STL (binary
//! and ASCII) and OBJ meshes; COLLADA (`.dae`) meshes and capsules are not read (reported).

pub mod mesh;
pub mod patch;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use stride_model::{KinDyn, Model, RobotState};

use mesh::{box_triangles, cylinder_triangles, read_mesh, resolve_mesh_path, transformed};
use patch::{lowest_patch, Patch, Shapes};

/// A link is a foot candidate when its lowest point is within this of the robot's lowest point \[m\].
pub const FOOT_HEIGHT_TOLERANCE: f64 = 0.01;
/// Without left/right link names, soles whose centres are closer than this to the ankles (along x) leave
/// the forward direction open \[m\].
pub const FORWARD_TOLERANCE: f64 = 0.01;
/// Visual and collision patches disagree beyond this (centre, size, height) \[m\].
pub const VISUAL_TOLERANCE: f64 = 0.01;

/// Why feet could not be proposed.
#[derive(Debug, thiserror::Error)]
pub enum FeetError {
    /// The URDF could not be read or loaded.
    #[error("cannot load {}: {message}", path.display())]
    Load {
        /// The URDF.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// No link with a flat patch of readable collision geometry on one side.
    #[error("no foot found at {side} (a link with a flat collision patch within {FOOT_HEIGHT_TOLERANCE} m of the lowest point){notes}")]
    NoFoot {
        /// `y > 0` or `y < 0` (model frame at the zero posture).
        side: &'static str,
        /// Geometry that could not be read.
        notes: String,
    },
}

/// One foot's proposal.
#[derive(Debug, Clone)]
pub struct FootProposal {
    /// `left` or `right`.
    pub side: &'static str,
    /// The foot link.
    pub link: String,
    /// The sole patch of the collision geometry (world, zero posture).
    pub patch: Patch,
    /// `link_H_sole`: the proposed sole frame (patch centre, z up, x forward) in the link.
    pub sole_in_link: Isometry3<f64>,
    /// What the collision geometry is made of.
    pub source: String,
    /// Disagreements with the visual geometry, or why it was not compared.
    pub warnings: Vec<String>,
    /// When the foot touches the ground only through spheres (point contacts, e.g. the G1's four corner
    /// spheres): the spheres' lowest points on the patch (world, zero posture); empty for a flat sole.
    pub point_contacts: Vec<nalgebra::Point3<f64>>,
}

impl FootProposal {
    /// The contact grid (`sim.contact.surfaces[].grid`, points along x and y, corners included) that puts
    /// one simulated contact point on each of [`FootProposal::point_contacts`] when they form a grid
    /// (distinct x's times distinct y's, each within 10 % of the patch's size: the G1's toe spheres are
    /// 5 mm wider apart than its heel spheres); `None` for a flat sole or another arrangement.
    pub fn point_contact_grid(&self) -> Option<[usize; 2]> {
        let distinct = |v: Vec<f64>, size: f64| {
            let mut v = v;
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| (*a - *b).abs() < 0.1 * size);
            v.len()
        };
        let p = &self.point_contacts;
        let nx = distinct(p.iter().map(|c| c.x).collect(), self.patch.length);
        let ny = distinct(p.iter().map(|c| c.y).collect(), self.patch.width);
        (nx >= 2 && ny >= 2 && nx * ny == p.len()).then_some([nx, ny])
    }
}

/// The geometry of one link, world coordinates, with notes on what could not be read.
struct LinkShapes {
    shapes: Shapes,
    kinds: Vec<String>,
    notes: Vec<String>,
}

/// Proposes both feet of the URDF at `path`.
pub fn propose_feet(path: &Path) -> Result<[FootProposal; 2], FeetError> {
    let load = |message: String| FeetError::Load {
        path: path.to_path_buf(),
        message,
    };
    let robot = urdf_rs::read_file(path).map_err(|e| load(e.to_string()))?;
    let model = Arc::new(Model::from_urdf_file(path).map_err(|e| load(e.to_string()))?);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&RobotState::zero(&model))
        .map_err(|e| load(e.to_string()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut links = Vec::new();
    for link in &robot.links {
        let Some(frame) = model.frame_id(&link.name) else {
            continue;
        };
        let pose = kd.frame_pose(frame);
        let collision = link.collision.iter().map(|c| (&c.origin, &c.geometry));
        let shapes = link_shapes(collision, &pose, dir);
        if !shapes.shapes.is_empty() || !shapes.notes.is_empty() {
            links.push((link, pose, shapes));
        }
    }
    let notes: Vec<String> = links.iter().flat_map(|l| l.2.notes.clone()).collect();
    let lowest = links
        .iter()
        .filter_map(|l| l.2.shapes.lowest())
        .min_by(f64::total_cmp);
    let candidates: Vec<Candidate> = links
        .iter()
        .filter(|(_, _, s)| {
            s.shapes
                .lowest()
                .zip(lowest)
                .is_some_and(|(z, z0)| z - z0 <= FOOT_HEIGHT_TOLERANCE)
        })
        .filter_map(|(link, pose, s)| {
            lowest_patch(&s.shapes).map(|patch| Candidate {
                link,
                pose: *pose,
                source: s.kinds.join(", "),
                patch,
                point_contacts: sphere_contacts(&s.shapes, patch.centre.z),
            })
        })
        .collect();
    let no_foot = |side: &'static str| FeetError::NoFoot {
        side,
        notes: if notes.is_empty() {
            String::new()
        } else {
            format!(" (not read: {})", notes.join("; "))
        },
    };
    let widest = |sign: f64| {
        candidates
            .iter()
            .filter(|c| c.patch.centre.y * sign > 0.0)
            .max_by(|a, b| a.patch.area().total_cmp(&b.patch.area()))
    };
    let (plus, minus) = (widest(1.0), widest(-1.0));
    let (Some(plus), Some(minus)) = (plus, minus) else {
        return Err(no_foot(if plus.is_none() { "y > 0" } else { "y < 0" }));
    };
    let (forward, general) = forward_direction(plus, minus);
    let (left, right) = if forward > 0.0 {
        (plus, minus)
    } else {
        (minus, plus)
    };
    let yaw = if forward > 0.0 {
        0.0
    } else {
        std::f64::consts::PI
    };
    let propose = |side: &'static str, c: &Candidate| {
        let world_sole = Isometry3::from_parts(
            Translation3::from(c.patch.centre.coords),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        );
        let visual = c.link.visual.iter().map(|v| (&v.origin, &v.geometry));
        let visual = link_shapes(visual, &c.pose, dir);
        let mut warnings = general.clone();
        warnings.extend(compare_visual(&c.patch, &visual));
        FootProposal {
            side,
            link: c.link.name.clone(),
            patch: c.patch,
            sole_in_link: c.pose.inverse() * world_sole,
            source: c.source.clone(),
            warnings,
            point_contacts: c.point_contacts.clone(),
        }
    };
    Ok([propose("left", left), propose("right", right)])
}

/// The model's forward direction along x (+1 or −1) and a note when it is a guess: from the link names
/// (`left`/`l_` at y > 0 means forward is +x), else from the toes (soles reaching farther in front of
/// the ankles than behind), else +x.
fn forward_direction(plus: &Candidate, minus: &Candidate) -> (f64, Vec<String>) {
    match (
        side_of_name(&plus.link.name),
        side_of_name(&minus.link.name),
    ) {
        (Some(true), Some(false)) => return (1.0, Vec::new()),
        (Some(false), Some(true)) => return (-1.0, Vec::new()),
        _ => {}
    }
    let ahead = [plus, minus]
        .iter()
        .map(|c| c.patch.centre.x - c.pose.translation.x)
        .sum::<f64>()
        * 0.5;
    if ahead.abs() < FORWARD_TOLERANCE {
        let note = format!(
            "the link names do not say left and right, and the soles are centred under the ankles \
             ({:.1} mm): forward taken as the model's +x",
            ahead * 1e3
        );
        return (1.0, vec![note]);
    }
    let note =
        "the link names do not say left and right: forward taken as where the toes point".into();
    (ahead.signum(), vec![note])
}

/// `Some(true)` for a left link name (`left`, `l_`, `_l_`, `_l`), `Some(false)` for a right one,
/// `None` when the name says neither or both.
fn side_of_name(name: &str) -> Option<bool> {
    let n = name.to_ascii_lowercase();
    let says = |word: &str, c: char| {
        n.contains(word)
            || n.starts_with(&format!("{c}_"))
            || n.contains(&format!("_{c}_"))
            || n.ends_with(&format!("_{c}"))
    };
    match (says("left", 'l'), says("right", 'r')) {
        (true, false) => Some(true),
        (false, true) => Some(false),
        _ => None,
    }
}

/// A link that reaches the ground with a flat patch.
struct Candidate<'a> {
    link: &'a urdf_rs::Link,
    pose: Isometry3<f64>,
    source: String,
    patch: Patch,
    point_contacts: Vec<nalgebra::Point3<f64>>,
}

/// The lowest points of the spheres on a patch at height `z` when the shapes are spheres only (point
/// contacts); empty otherwise.
fn sphere_contacts(shapes: &Shapes, z: f64) -> Vec<nalgebra::Point3<f64>> {
    if !shapes.triangles.is_empty() {
        return Vec::new();
    }
    shapes
        .spheres
        .iter()
        .map(|(c, r)| c - Vector3::z() * *r)
        .filter(|p| (p.z - z).abs() <= patch::PATCH_HEIGHT_TOLERANCE)
        .collect()
}

/// The shapes of one link's collision or visual elements, placed at `pose`.
fn link_shapes<'a>(
    elements: impl Iterator<Item = (&'a urdf_rs::Pose, &'a urdf_rs::Geometry)>,
    pose: &Isometry3<f64>,
    dir: &Path,
) -> LinkShapes {
    let mut out = LinkShapes {
        shapes: Shapes::default(),
        kinds: Vec::new(),
        notes: Vec::new(),
    };
    for (origin, geometry) in elements {
        let [r, p, y] = *origin.rpy;
        let local = Isometry3::from_parts(
            Translation3::from(Vector3::from(*origin.xyz)),
            UnitQuaternion::from_euler_angles(r, p, y),
        );
        let at = pose * local;
        match geometry {
            urdf_rs::Geometry::Box { size } => {
                out.shapes
                    .triangles
                    .extend(transformed(&box_triangles(**size), &at));
                out.kinds.push("box".into());
            }
            urdf_rs::Geometry::Cylinder { radius, length } => {
                let tris = cylinder_triangles(*radius, *length, 32);
                out.shapes.triangles.extend(transformed(&tris, &at));
                out.kinds.push("cylinder".into());
            }
            urdf_rs::Geometry::Sphere { radius } => {
                out.shapes
                    .spheres
                    .push((at * nalgebra::Point3::origin(), *radius));
                out.kinds.push("sphere".into());
            }
            urdf_rs::Geometry::Capsule { .. } => out.notes.push("capsule (not supported)".into()),
            urdf_rs::Geometry::Mesh { filename, scale } => {
                let scale = scale.as_ref().map_or([1.0; 3], |s| **s);
                match resolve_mesh_path(filename, dir).and_then(|p| read_mesh(&p, scale)) {
                    Ok(tris) => {
                        out.shapes.triangles.extend(transformed(&tris, &at));
                        let name = Path::new(filename)
                            .file_name()
                            .map(|n| n.to_string_lossy().into_owned());
                        out.kinds.push(format!("mesh {}", name.unwrap_or_default()));
                    }
                    Err(e) => out.notes.push(e.to_string()),
                }
            }
        }
    }
    out
}

/// Disagreements of the visual geometry's lowest patch with the collision one.
fn compare_visual(collision: &Patch, visual: &LinkShapes) -> Vec<String> {
    if visual.shapes.is_empty() {
        let why = if visual.notes.is_empty() {
            "the link has no visual geometry".to_string()
        } else {
            visual.notes.join("; ")
        };
        return vec![format!("visual geometry not compared: {why}")];
    }
    let Some(v) = lowest_patch(&visual.shapes) else {
        return vec!["the visual geometry has no flat bottom patch".into()];
    };
    let mut out = Vec::new();
    let d = v.centre - collision.centre;
    if d.z.abs() > VISUAL_TOLERANCE * 0.5 {
        out.push(format!(
            "the visual sole is {:.1} mm {} the collision sole",
            d.z.abs() * 1e3,
            if d.z < 0.0 { "below" } else { "above" }
        ));
    }
    if d.xy().norm() > VISUAL_TOLERANCE {
        out.push(format!(
            "the visual sole's centre is {:.1} mm from the collision sole's (dx {:+.1} mm, dy {:+.1} mm)",
            d.xy().norm() * 1e3,
            d.x * 1e3,
            d.y * 1e3
        ));
    }
    if (v.length - collision.length).abs() > VISUAL_TOLERANCE
        || (v.width - collision.width).abs() > VISUAL_TOLERANCE
    {
        out.push(format!(
            "the visual sole is {:.3} m × {:.3} m, the collision sole {:.3} m × {:.3} m",
            v.length, v.width, collision.length, collision.width
        ));
    }
    out
}

/// How far the collision geometry of the body that carries `frame` reaches below the frame's x-y plane
/// \[m\] (positive: below; every URDF link merged into that body counts), or `None` when that body has no
/// readable collision geometry. A sole frame should sit on the lowest flat patch (0 here).
pub fn collision_depth_below(
    urdf: &Path,
    model: &Arc<Model>,
    frame: stride_model::FrameId,
) -> Result<Option<f64>, FeetError> {
    let load = |message: String| FeetError::Load {
        path: urdf.to_path_buf(),
        message,
    };
    let robot = urdf_rs::read_file(urdf).map_err(|e| load(e.to_string()))?;
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&RobotState::zero(model))
        .map_err(|e| load(e.to_string()))?;
    let body = model.frames()[frame.index()].link;
    let frame_inv = kd.frame_pose(frame).inverse();
    let dir = urdf.parent().unwrap_or(Path::new("."));
    let mut shapes = Shapes::default();
    for link in &robot.links {
        let Some(id) = model.frame_id(&link.name) else {
            continue;
        };
        if model.frames()[id.index()].link != body {
            continue;
        }
        let in_frame = frame_inv * kd.frame_pose(id);
        let collision = link.collision.iter().map(|c| (&c.origin, &c.geometry));
        let s = link_shapes(collision, &in_frame, dir).shapes;
        shapes.triangles.extend(s.triangles);
        shapes.spheres.extend(s.spheres);
    }
    Ok(shapes.lowest().map(|z| -z))
}
