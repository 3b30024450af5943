//! Inertial edits applied to the URDF links before lumping: a plant model that differs from the model the
//! controllers use (model mismatch).

use nalgebra::{Matrix3, Vector3};

use crate::error::ModelError;

/// Edits of the inertial parameters of a URDF, applied link by link before fixed joints are merged (see
/// [`Model::from_urdf_str_edited`](crate::Model::from_urdf_str_edited)).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `mass_scale` | – | 1 | scales the mass and the rotational inertia (about the CoM) of every link |
/// | `links` | – | none | per-link edits, applied after `mass_scale`, in order |
///
/// With `mass_scale` = s every link keeps its CoM, so the total mass and every inertia scale by s and the
/// robot's CoM does not move.
#[derive(Clone, Debug, PartialEq)]
pub struct InertiaEdits {
    /// Factor (> 0) on the mass and rotational inertia of every link.
    pub mass_scale: f64,
    /// Edits of single links.
    pub links: Vec<LinkInertiaEdit>,
}

impl Default for InertiaEdits {
    fn default() -> Self {
        Self {
            mass_scale: 1.0,
            links: Vec::new(),
        }
    }
}

/// The edit of one URDF link's inertial parameters.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `link` | – | URDF link name |
/// | `mass_scale` | – | factor (> 0) on the link's mass and rotational inertia about its CoM |
/// | `com_offset` | m | added to the link's CoM, link frame (the inertia about the CoM moves with it) |
#[derive(Clone, Debug, PartialEq)]
pub struct LinkInertiaEdit {
    /// URDF link name.
    pub link: String,
    /// Factor (> 0, finite) on the link's mass and rotational inertia about its CoM.
    pub mass_scale: f64,
    /// CoM displacement in the link frame (m).
    pub com_offset: Vector3<f64>,
}

impl Default for LinkInertiaEdit {
    fn default() -> Self {
        Self {
            link: String::new(),
            mass_scale: 1.0,
            com_offset: Vector3::zeros(),
        }
    }
}

impl InertiaEdits {
    /// Checks every number and that every edited link exists (`link_exists`).
    ///
    /// # Errors
    /// [`ModelError::InvalidInertiaEdit`] naming the link and the field.
    pub(crate) fn validate(
        &self,
        mut link_exists: impl FnMut(&str) -> bool,
    ) -> Result<(), ModelError> {
        check_scale("inertia edits", "mass_scale", self.mass_scale)?;
        for e in &self.links {
            let element = format!("inertia edit of link `{}`", e.link);
            if !link_exists(&e.link) {
                return Err(ModelError::InvalidInertiaEdit {
                    element,
                    field: "link",
                    reason: "the URDF has no such link".to_string(),
                });
            }
            check_scale(&element, "mass_scale", e.mass_scale)?;
            if !e.com_offset.iter().all(|v| v.is_finite()) {
                return Err(ModelError::InvalidInertiaEdit {
                    element,
                    field: "com_offset",
                    reason: format!("{:?} is not finite", e.com_offset.as_slice()),
                });
            }
        }
        Ok(())
    }

    /// The edited `(mass (kg), CoM (m, link frame), rotational inertia about the CoM (kg·m²))` of link `name`.
    pub(crate) fn apply(
        &self,
        name: &str,
        mass: f64,
        com: Vector3<f64>,
        inertia_at_com: Matrix3<f64>,
    ) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let (mut m, mut c, mut i) = (
            mass * self.mass_scale,
            com,
            inertia_at_com * self.mass_scale,
        );
        for e in self.links.iter().filter(|e| e.link == name) {
            m *= e.mass_scale;
            i *= e.mass_scale;
            c += e.com_offset;
        }
        (m, c, i)
    }

    /// Whether the edits change nothing.
    pub(crate) fn is_identity(&self) -> bool {
        self.mass_scale == 1.0 && self.links.is_empty()
    }
}

fn check_scale(element: &str, field: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ModelError::InvalidInertiaEdit {
            element: element.to_string(),
            field,
            reason: format!("{value} is not a positive finite number"),
        })
    }
}

impl crate::Model {
    /// Adds the frame `name` rigidly attached to the existing frame `parent`, at `parent_H_frame` =
    /// `placement` (e.g. a sole frame the URDF lacks, placed on the foot link). The new frame moves with
    /// `parent`'s body; a force/torque sensor sees it on the side `parent` is on.
    ///
    /// # Errors
    /// [`ModelError::InvalidFrame`] when `name` is empty or already a frame, `parent` is not a frame, or
    /// `placement` is not finite.
    pub fn add_frame(
        &mut self,
        name: &str,
        parent: &str,
        placement: nalgebra::Isometry3<f64>,
    ) -> Result<crate::FrameId, ModelError> {
        let invalid = |reason: String| ModelError::InvalidFrame {
            name: name.to_string(),
            reason,
        };
        if name.is_empty() {
            return Err(invalid("the name is empty".into()));
        }
        if self.frame_index.contains_key(name) {
            return Err(invalid("the model already has a frame of that name".into()));
        }
        let p = *self
            .frame_index
            .get(parent)
            .ok_or_else(|| invalid(format!("the model has no frame `{parent}`")))?;
        let finite = placement.translation.vector.iter().all(|v| v.is_finite())
            && placement.rotation.coords.iter().all(|v| v.is_finite());
        if !finite {
            return Err(invalid("the placement is not finite".into()));
        }
        let parent_frame = self.frames[p].clone();
        let body_h_frame = parent_frame.placement * placement;
        let index = self.frames.len();
        self.frames.push(crate::model::Frame {
            name: name.to_string(),
            link: parent_frame.link,
            placement: body_h_frame,
            kind: crate::model::FrameKind::Added,
            attached_to: Some(p),
        });
        self.frame_index.insert(name.to_string(), index);
        self.frame_rot
            .push(body_h_frame.rotation.to_rotation_matrix().into_inner());
        self.frame_pos.push(body_h_frame.translation.vector);
        for side in &mut self.ft_sides {
            let child = side.child_side_frame[p];
            side.child_side_frame.push(child);
        }
        Ok(crate::FrameId(index))
    }
}
