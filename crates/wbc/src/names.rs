//! Resolution of a controller's reference and contact names to the slots of a [`WbcInput`]'s tables.
//! Done once per input layout (a pointer comparison per tick afterwards): the per-tick path has no
//! string lookup and no allocation.

use std::sync::Arc;

use crate::config::TaskConfig;
use crate::error::WbcError;
use crate::io::{ContactInput, FrameReference, InputLayout, WbcInput};

/// A controller's names and, for the last input layout seen, where each sits in the input.
#[derive(Debug, Clone)]
pub(crate) struct Resolver {
    /// The controller's own layout (what [`crate::Tsid::input`] builds).
    own: Arc<InputLayout>,
    /// The layout `frame_slots` / `contact_slots` were resolved for.
    seen: Option<Arc<InputLayout>>,
    frame_slots: Vec<usize>,
    contact_slots: Vec<usize>,
}

impl Resolver {
    pub fn new(own: InputLayout) -> Self {
        Resolver {
            frame_slots: vec![0; own.frames().len()],
            contact_slots: vec![0; own.contacts().len()],
            own: Arc::new(own),
            seen: None,
        }
    }

    pub fn layout(&self) -> &Arc<InputLayout> {
        &self.own
    }

    /// Index of a frame reference name in the controller's layout (`None` for `"initial"`).
    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.own.frames().iter().position(|n| n == name)
    }

    /// Index of a contact name in the controller's layout.
    pub fn contact_index(&self, name: &str) -> Option<usize> {
        self.own.contacts().iter().position(|n| n == name)
    }

    /// Maps the controller's names onto `input`'s layout (a superset is fine). Allocation-free; string
    /// comparisons only when the input's layout is not the one of the previous tick.
    pub fn resolve(&mut self, input: &WbcInput) -> Result<(), WbcError> {
        let layout = input.layout();
        if self.seen.as_ref().is_some_and(|s| Arc::ptr_eq(s, layout)) {
            return Ok(());
        }
        for (slot, name) in self.frame_slots.iter_mut().zip(self.own.frames()) {
            *slot = input.frame_id(name).map(|id| id.index())?;
        }
        for (slot, name) in self.contact_slots.iter_mut().zip(self.own.contacts()) {
            *slot = input.contact_id(name).map(|id| id.index())?;
        }
        self.seen = Some(Arc::clone(layout));
        Ok(())
    }

    /// The input's reference for the controller's frame name `k` (after [`Resolver::resolve`]).
    pub fn frame<'a>(&self, input: &'a WbcInput, k: usize) -> &'a FrameReference {
        &input.frames()[self.frame_slots[k]]
    }

    /// The input's contact for the controller's contact name `k` (after [`Resolver::resolve`]).
    pub fn contact<'a>(&self, input: &'a WbcInput, k: usize) -> &'a ContactInput {
        &input.contacts()[self.contact_slots[k]]
    }
}

/// The frame reference names (of the `se3`, `so3`, `r3` tasks, `"initial"` aside, and the angular
/// momentum tasks' `reference_frames`) and contact names (of
/// the `contact` tasks) of a task list, in task order. Errors: a contact task without a valid name.
pub(crate) fn input_layout(tasks: &[TaskConfig]) -> Result<InputLayout, WbcError> {
    let mut layout = InputLayout::default();
    for task in tasks {
        match task {
            TaskConfig::Se3(c) => layout.add_frame(&c.reference),
            TaskConfig::So3(c) | TaskConfig::R3(c) => layout.add_frame(&c.reference),
            TaskConfig::Contact(c) => layout.add_contact(c.contact_name()?),
            TaskConfig::AngularMomentum(c) => {
                for f in &c.reference_frames {
                    layout.add_frame(&f.reference);
                }
            }
            _ => {}
        }
    }
    Ok(layout)
}
