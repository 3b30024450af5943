//! Estimated state + feet wrenches → the measured quantities the simplified layer reads
//! ([`MeasuredCentroidal`]): the rules the walking stack uses between the estimation and simplified layers.

use std::sync::Arc;

use nalgebra::{Isometry3, Vector2, Vector3, Vector6};
use stride_model::{FrameId, KinDyn, Model, ModelError, RobotState, VelocityRepresentation};
use stride_simplified::{measured_zmp, FootWrench};

use crate::MeasuredCentroidal;

/// Share of the robot's weight the loaded feet must carry together for the ZMP to come from their
/// wrenches; below it the ZMP is the CoM's ground projection.
pub const MIN_ZMP_LOAD: f64 = 0.05;

/// Cut-off \[Hz\] of the first-order low-pass filter ([`stride_block::FirstOrderLowPass`]) the walking
/// stack reads the measured ZMP through before the simplified layer: the default of stride-runner's
/// `estimation.measured_zmp_cutoff`, the middle of the band that walks on both of its plants. The filter
/// keeps force/torque noise and contact chatter out of the ZMP-CoM controller's CoM references.
pub const MEASURED_ZMP_CUTOFF: f64 = 5.0;

/// Measures a [`MeasuredCentroidal`] from an estimated state and the feet wrenches; owns its kinematics
/// workspace (allocation in [`CentroidalMeter::new`] only).
///
/// The rules (the walking stack's choices):
/// - **CoM** position and velocity of `state` through the model (mixed velocities);
/// - **DCM** `ξ = x + ẋ/ω` (xy) with the caller's ω, the plan's [Romualdi 2022, eq. 4.4.2];
/// - **ZMP** from the wrenches of the feet flagged in contact that push on the ground (`f_z > 0`), about
///   their sole origins ([`measured_zmp`], ground at `z = 0`), when they carry at least [`MIN_ZMP_LOAD`] of
///   the weight; otherwise the CoM's ground projection ([`CentroidalMeter::zmp_from_wrenches`] says which);
/// - **soles**: the sole frame poses of `state`.
///
/// ```
/// use std::sync::Arc;
/// use nalgebra::{DVector, Vector6};
/// use stride_model::{bundled, RobotState};
/// use stride_walking::CentroidalMeter;
///
/// let model = Arc::new(bundled::model()?);
/// let soles = [model.frame_id(bundled::LEFT_SOLE).unwrap(), model.frame_id(bundled::RIGHT_SOLE).unwrap()];
/// let state = RobotState::standing(&model, &DVector::zeros(model.dof()), soles[0], soles[1])?;
/// let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
/// let half_weight = Vector6::new(0.0, 0.0, 0.5 * model.total_mass() * 9.81, 0.0, 0.0, 0.0);
/// let m = meter.measure(&state, &[half_weight; 2], [true, true], 4.26)?;
/// // equal vertical forces on both soles: the ZMP is their mid-point, the world origin
/// assert!(meter.zmp_from_wrenches() && m.zmp.norm() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct CentroidalMeter {
    kd: KinDyn,
    soles: [FrameId; 2],
    weight: f64,
    zmp_from_wrenches: bool,
}

impl CentroidalMeter {
    /// A meter for `model` with the sole frames `[left, right]`; the weight is the model's mass times its
    /// gravity's magnitude.
    pub fn new(model: Arc<Model>, soles: [FrameId; 2]) -> Self {
        let weight = model.total_mass() * model.gravity().norm();
        let mut kd = KinDyn::new(model);
        kd.set_representation(VelocityRepresentation::Mixed);
        Self {
            kd,
            soles,
            weight,
            zmp_from_wrenches: false,
        }
    }

    /// The measured quantities of `state` (mixed velocities) with the feet wrenches `[left, right]`
    /// (`[f; τ]` \[N, N·m\] the ground applies on each foot, world orientation, torque about the sole
    /// origin, as the estimation layer's `EstimatorOutput::foot_wrenches`), the feet `contacts` and the plan's
    /// `omega` \[1/s\]. Allocation-free.
    ///
    /// # Errors
    /// [`ModelError`] when `state` does not fit the model or is not finite.
    pub fn measure(
        &mut self,
        state: &RobotState,
        foot_wrenches: &[Vector6<f64>; 2],
        contacts: [bool; 2],
        omega: f64,
    ) -> Result<MeasuredCentroidal, ModelError> {
        self.kd.set_state(state)?;
        let com = self.kd.com_position();
        let com_velocity = self.kd.com_velocity();
        let soles = [
            self.kd.frame_pose(self.soles[0]),
            self.kd.frame_pose(self.soles[1]),
        ];
        let zmp = self.zmp(&soles, foot_wrenches, contacts, &com);
        Ok(MeasuredCentroidal {
            com,
            com_velocity,
            dcm: com.xy() + com_velocity.xy() / omega,
            zmp,
            soles,
        })
    }

    /// Whether the last [`CentroidalMeter::measure`] took the ZMP from the feet wrenches (`false`: the
    /// CoM's ground projection).
    pub fn zmp_from_wrenches(&self) -> bool {
        self.zmp_from_wrenches
    }

    fn zmp(
        &mut self,
        soles: &[Isometry3<f64>; 2],
        foot_wrenches: &[Vector6<f64>; 2],
        contacts: [bool; 2],
        com: &Vector3<f64>,
    ) -> Vector2<f64> {
        let zmp = feet_zmp(soles, foot_wrenches, contacts, self.weight);
        self.zmp_from_wrenches = zmp.is_some();
        zmp.unwrap_or_else(|| com.xy())
    }
}

/// The walking stack's measured ZMP \[m\] (world xy, ground at `z = 0`): from the wrenches of the feet
/// flagged in `contacts` that push on the ground (`f_z > 0`), about their sole origins `soles` ([`measured_zmp`],
/// [Romualdi 2022, eq. 2.4.10]), when together they carry at least [`MIN_ZMP_LOAD`] of `weight` \[N\];
/// `None` otherwise (the caller's fallback, [`CentroidalMeter`]'s the CoM's ground projection). Wrenches
/// `[f; τ]` \[N, N·m\] the ground applies on each foot, world orientation, torque about the sole origin.
/// Allocation-free.
pub fn feet_zmp(
    soles: &[Isometry3<f64>; 2],
    foot_wrenches: &[Vector6<f64>; 2],
    contacts: [bool; 2],
    weight: f64,
) -> Option<Vector2<f64>> {
    let mut loaded = [FootWrench {
        wrench: Vector6::zeros(),
        point: Vector3::zeros(),
    }; 2];
    let mut n = 0;
    for k in 0..2 {
        if contacts[k] && foot_wrenches[k][2] > 0.0 {
            loaded[n] = FootWrench {
                wrench: foot_wrenches[k],
                point: soles[k].translation.vector,
            };
            n += 1;
        }
    }
    measured_zmp(&loaded[..n], 0.0, MIN_ZMP_LOAD * weight).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use stride_model::bundled;

    fn standing() -> (Arc<Model>, [FrameId; 2], RobotState) {
        let model = Arc::new(bundled::model().unwrap());
        let soles = bundled::soles(&model).unwrap();
        let state = bundled::standing_state(&model).unwrap();
        (model, soles, state)
    }

    fn vertical(fz: f64, tau_y: f64) -> Vector6<f64> {
        Vector6::new(0.0, 0.0, fz, 0.0, tau_y, 0.0)
    }

    #[test]
    fn zmp_is_the_force_weighted_sole_point_shifted_by_the_pitch_torque() {
        let (model, soles, state) = standing();
        let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
        let (fl, fr, tau) = (200.0, 100.0, -6.0);
        let m = meter
            .measure(
                &state,
                &[vertical(fl, tau), vertical(fr, 0.0)],
                [true, true],
                4.0,
            )
            .unwrap();
        let (pl, pr) = (
            m.soles[0].translation.vector.xy(),
            m.soles[1].translation.vector.xy(),
        );
        // closed form: p = (f_l p_l + f_r p_r)/(f_l + f_r), x shifted by −τ_y/f_z
        let expected = (pl * fl + pr * fr) / (fl + fr) + Vector2::new(-tau / (fl + fr), 0.0);
        assert!(meter.zmp_from_wrenches());
        assert!((m.zmp - expected).norm() < 1e-12, "{} vs {expected}", m.zmp);
    }

    #[test]
    fn unloaded_or_unflagged_feet_give_the_com_projection() {
        let (model, soles, state) = standing();
        let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
        let weight = model.total_mass() * 9.81;
        // a foot not flagged in contact is ignored, however loaded
        let m = meter
            .measure(&state, &[vertical(weight, 0.0); 2], [false, false], 4.0)
            .unwrap();
        assert!(!meter.zmp_from_wrenches());
        assert_eq!(m.zmp, m.com.xy());
        // both flagged, just below and just above the load threshold
        for (share, from_wrenches) in [(0.99, false), (1.01, true)] {
            let fz = 0.5 * share * MIN_ZMP_LOAD * weight;
            meter
                .measure(&state, &[vertical(fz, 0.0); 2], [true, true], 4.0)
                .unwrap();
            assert_eq!(meter.zmp_from_wrenches(), from_wrenches, "share {share}");
        }
    }

    #[test]
    fn dcm_is_com_plus_its_velocity_over_omega() {
        let (model, soles, mut state) = standing();
        // a pure base translation moves every link, so the CoM, with the base's velocity
        state.base_velocity = nalgebra::Vector6::new(0.3, -0.1, 0.0, 0.0, 0.0, 0.0);
        let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
        let omega = 4.2;
        let m = meter
            .measure(&state, &[Vector6::zeros(); 2], [true, true], omega)
            .unwrap();
        let expected = m.com.xy() + Vector2::new(0.3, -0.1) / omega;
        assert!((m.com_velocity - Vector3::new(0.3, -0.1, 0.0)).norm() < 1e-12);
        assert!((m.dcm - expected).norm() < 1e-12);
    }
}
