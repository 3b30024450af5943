//! The wrench `f_c` TSID-Compliant's rows read (`[wbc.tsid.compliant] wrench_source`,
//! [`crate::WrenchSource`]): the measured one, Lemma 1's at the sole's state [Romualdi 2022, eq. 8.1.7], or
//! the last solve's prediction corrected toward the measured one.

use nalgebra::Vector6;

use super::compliant::CompliantContacts;
use super::Contact;
use crate::config::WrenchSource;

impl CompliantContacts {
    /// `"filtered"`: each contact's measured wrench (in `measured`, read this tick) replaced by
    /// `p + α (measured − p)` with `p` the wrench the last solve predicted for this tick (`predicted`:
    /// [`crate::TsidOutput::contact_wrenches`], `f + ḟ·period`) and `α = period / (τ + period)`. Not on the
    /// first tick (`started = false`), nor for the other sources.
    pub fn filter_wrenches(&mut self, predicted: &[Vector6<f64>], started: bool) {
        if self.wrench_source != WrenchSource::Filtered || !started {
            return;
        }
        let alpha = self.filter_gain;
        for (m, p) in self.measured.iter_mut().zip(predicted) {
            *m = p + (*m - p) * alpha;
        }
    }

    /// `"model"`: the wrench of every contact in the QP (`load > 0`) replaced by Lemma 1's at its state
    /// about its rest pose ([`crate::soft_contact::SoleGeometry::wrench`]), the others' by zero. Call after
    /// the touch-downs of this tick (their rest poses read the measured wrench) and the ground estimate
    /// (which reads the measured wrench too).
    pub fn model_wrenches(&mut self, contacts: &[Contact]) {
        if self.wrench_source != WrenchSource::Model {
            return;
        }
        for (c, contact) in contacts.iter().enumerate() {
            self.measured[c] = match contact.load > 0.0 {
                true => self.sole.wrench(&self.sole_state(c, contact), &self.ground),
                false => Vector6::zeros(),
            };
        }
    }
}
