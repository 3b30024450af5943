//! The inertial-parameter vector ψ of a whole model [Traversaro 2017, Definition 7.1] in the body and the
//! FT-split layouts (see [`crate::inertial`]).

use nalgebra::DVector;

use super::rigid_body::{inertia_of, parameters_of, InertialParameters};
use crate::error::ModelError;
use crate::model::Model;
use crate::spatial::Inertia;

impl Model {
    /// ψ in the body layout (see [`crate::inertial`]): `π = [m; m c; vech(I_B)]` of every lumped body in
    /// its own frame, stacked in body order (10·N).
    pub fn inertial_parameters(&self) -> DVector<f64> {
        let mut out = DVector::zeros(10 * self.body_count());
        for (b, inertia) in self.inertia.iter().enumerate() {
            out.fixed_rows_mut::<10>(10 * b)
                .copy_from(&parameters_of(inertia));
        }
        out
    }

    /// Checks that no two force/torque sensors lie in the same lumped body (the FT-split layout gives each
    /// host one child-side part).
    ///
    /// # Errors
    /// [`ModelError::SharedFtSensorHost`].
    pub(crate) fn check_ft_hosts(&self) -> Result<(), ModelError> {
        for (k, side) in self.ft_sides.iter().enumerate() {
            if let Some(j) = self.ft_sides[..k].iter().position(|s| s.host == side.host) {
                return Err(ModelError::SharedFtSensorHost {
                    body: self.bodies[side.host].name.clone(),
                    first: self.ft_sensors[j].name.clone(),
                    second: self.ft_sensors[k].name.clone(),
                });
            }
        }
        Ok(())
    }

    /// `π` of the child-side part of force/torque sensor `k`'s host body, in the host frame.
    pub(crate) fn ft_child_part(&self, k: usize) -> InertialParameters {
        let side = &self.ft_sides[k];
        parameters_of(&Inertia::from_com(
            side.mass,
            &side.com,
            &side.inertia_at_com,
        ))
    }

    /// ψ in the FT-split layout (see [`crate::inertial`]), 10·(N + S).
    ///
    /// # Errors
    /// [`ModelError::SharedFtSensorHost`] when two sensors lie in the same lumped body.
    pub fn ft_split_inertial_parameters(&self) -> Result<DVector<f64>, ModelError> {
        self.check_ft_hosts()?;
        let nb = self.body_count();
        let mut out = DVector::zeros(10 * (nb + self.ft_sensors.len()));
        out.rows_mut(0, 10 * nb)
            .copy_from(&self.inertial_parameters());
        for (k, side) in self.ft_sides.iter().enumerate() {
            let part = self.ft_child_part(k);
            out.fixed_rows_mut::<10>(10 * (nb + k)).copy_from(&part);
            let mut host = out.fixed_rows_mut::<10>(10 * side.host);
            host -= part;
        }
        Ok(out)
    }

    /// The body-layout ψ of an FT-split ψ: each sensor's child-side block added to its host's block (both
    /// are in the host frame).
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] when `split` is not 10·(N + S) long.
    pub fn merge_ft_split_parameters(
        &self,
        split: &DVector<f64>,
    ) -> Result<DVector<f64>, ModelError> {
        let nb = self.body_count();
        crate::error::check_len(
            "FT-split inertial parameters",
            10 * (nb + self.ft_sensors.len()),
            split.len(),
        )?;
        let mut out = split.rows(0, 10 * nb).into_owned();
        for (k, side) in self.ft_sides.iter().enumerate() {
            let part = split.fixed_rows::<10>(10 * (nb + k)).into_owned();
            let mut host = out.fixed_rows_mut::<10>(10 * side.host);
            host += part;
        }
        Ok(out)
    }

    /// A copy of the model with the inertial parameters `split` (FT-split layout, see
    /// [`crate::inertial`]): every body's and every sensor's child-side part's mass, CoM and inertia, so
    /// that inverse dynamics and the FT readings of the copy are `Y ψ` with the regressors of
    /// [`KinDyn`](crate::KinDyn). Without sensors the layout is the body layout. The parameters need not be
    /// physically consistent (check with [`crate::inertial::check_full_consistency`]), but a model stores
    /// mass and CoM, so each block needs `m ≥ 0`, and `m c = 0` when `m = 0`.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`], [`ModelError::NonFiniteInput`],
    /// [`ModelError::InvalidInertialParameters`], [`ModelError::SharedFtSensorHost`].
    pub fn with_ft_split_inertial_parameters(
        &self,
        split: &DVector<f64>,
    ) -> Result<Model, ModelError> {
        self.check_ft_hosts()?;
        let body = self.merge_ft_split_parameters(split)?;
        if !split.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFiniteInput {
                what: "inertial parameters",
            });
        }
        let nb = self.body_count();
        let mut out = self.clone();
        out.total_mass = 0.0;
        for b in 0..nb {
            let what = || format!("body `{}`", self.bodies[b].name);
            let inertia = checked_inertia(&body.fixed_rows::<10>(10 * b).into_owned(), what)?;
            out.inertia[b] = inertia;
            out.body_com[b] = inertia.com();
            out.body_inertia_com[b] = inertia.inertia_at_com();
            out.bodies[b].mass = inertia.m;
            out.bodies[b].com = out.body_com[b];
            out.bodies[b].inertia_at_com = out.body_inertia_com[b];
            out.total_mass += inertia.m;
        }
        for k in 0..self.ft_sensors.len() {
            let what = || {
                format!(
                    "the child side of force/torque sensor `{}`",
                    self.ft_sensors[k].name
                )
            };
            let part = checked_inertia(&split.fixed_rows::<10>(10 * (nb + k)).into_owned(), what)?;
            let side = &mut out.ft_sides[k];
            side.mass = part.m;
            side.com = part.com();
            side.inertia_at_com = part.inertia_at_com();
        }
        Ok(out)
    }
}

/// The [`Inertia`] of `π` if a model can hold it: `m ≥ 0`, and no first moment without mass.
fn checked_inertia(
    pi: &InertialParameters,
    what: impl Fn() -> String,
) -> Result<Inertia, ModelError> {
    let inertia = inertia_of(pi);
    if inertia.m < 0.0 {
        return Err(ModelError::InvalidInertialParameters {
            what: what(),
            reason: format!("negative mass {} kg", inertia.m),
        });
    }
    if inertia.m == 0.0 && inertia.h.norm() > 0.0 {
        return Err(ModelError::InvalidInertialParameters {
            what: what(),
            reason: format!("first moment {:?} kg·m without mass", inertia.h),
        });
    }
    Ok(inertia)
}
