//! The text table and the TOML report of `stride identify`.

use std::fmt::Write as _;

use nalgebra::{DVector, Vector3};
use stride_model::inertial::{check_full_consistency, mass_com_inertia, vech, InertialParameters};
use stride_model::Model;

use super::IdentificationReport;

/// Name of block `b` of the FT-split layout: the body, or `<child link> (child side of <sensor>)`.
pub(super) fn block_name(model: &Model, b: usize) -> String {
    let nb = model.body_count();
    if b < nb {
        model.bodies()[b].name.clone()
    } else {
        let s = &model.ft_sensors()[b - nb];
        format!("{} (child side of {})", s.child_link, s.name)
    }
}

/// Block `b` of a ψ.
pub(super) fn block(psi: &DVector<f64>, b: usize) -> InertialParameters {
    InertialParameters::from_column_slice(&psi.as_slice()[10 * b..10 * b + 10])
}

/// Names of the blocks of `psi` that are not fully consistent (with a non-zero mass: zero-mass blocks are
/// the URDF's massless links).
pub(super) fn violations(model: &Model, psi: &DVector<f64>) -> Vec<String> {
    (0..psi.len() / 10)
        .filter(|&b| {
            let pi = block(psi, b);
            pi.amax() > 0.0 && check_full_consistency(&pi).is_err()
        })
        .map(|b| block_name(model, b))
        .collect()
}

/// The total mass of a ψ (kg): the sum of its blocks' masses.
pub(super) fn total_mass(psi: &DVector<f64>) -> f64 {
    psi.iter().step_by(10).sum()
}

fn vec3(v: &Vector3<f64>) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

fn list(v: impl IntoIterator<Item = f64>) -> String {
    let items: Vec<String> = v.into_iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", items.join(", "))
}

impl IdentificationReport {
    /// `‖Bᵀ(ψ − ψ_true)‖ / ‖Bᵀ ψ_true‖`: the relative error of the identifiable combinations of `psi`
    /// against the simulated plant (`None` without a plant truth).
    pub fn identifiable_error(&self, psi: &DVector<f64>) -> Option<f64> {
        let truth = self.truth.as_ref()?;
        let t = self.base.base_parameters(truth).ok()?;
        let e = self.base.base_parameters(psi).ok()? - &t;
        Some(e.norm() / t.norm())
    }

    /// The table printed by `stride identify`.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "inertial parameters from {} samples ({} rows, {} of them base rows) of {} log(s); {} identifiable \
             combinations of {} parameters (σ > {:e} σ_max; condition number over them {:.3e})",
            self.samples,
            self.rows,
            self.base_rows,
            self.logs.len(),
            self.base.rank(),
            self.prior.len(),
            super::IDENTIFIABLE_TOLERANCE,
            self.condition_number
        );
        let _ = writeln!(
            s,
            "normalised residual √(χ²/rows): prior {:.3}, identified {:.3} ({} iterations{}, objective {:.6e}), unconstrained {:.3}",
            self.residuals[0],
            self.residuals[1],
            self.iterations.0,
            if self.iterations.1 { "" } else { ", not converged" },
            self.objective,
            self.residuals[2]
        );
        if let Some(e) = self.identifiable_error(&self.prior) {
            let _ = writeln!(
                s,
                "identifiable combinations vs the simulated plant: prior {:.2} %, identified {:.2} %, unconstrained {:.2} %",
                100.0 * e,
                100.0 * self.identifiable_error(&self.identified).unwrap_or(f64::NAN),
                100.0 * self.identifiable_error(&self.unconstrained).unwrap_or(f64::NAN)
            );
        }
        let _ = writeln!(
            s,
            "total mass [kg]: prior {:.3}, identified {:.3}, plant {}",
            total_mass(&self.prior),
            total_mass(&self.identified),
            self.truth
                .as_ref()
                .map(|t| format!("{:.3}", total_mass(t)))
                .unwrap_or_else(|| "-".into())
        );
        let _ = writeln!(
            s,
            "unconstrained least squares: {} bodies not fully consistent{}",
            self.unconstrained_violations.len(),
            if self.unconstrained_violations.is_empty() {
                String::new()
            } else {
                format!(" ({})", self.unconstrained_violations.join(", "))
            }
        );
        let _ = writeln!(
            s,
            "  {:<42} {:>9} {:>9} {:>9}   {:<26} {:<26}",
            "body", "m prior", "m ident", "m true", "CoM prior [m]", "CoM ident [m]"
        );
        for b in 0..self.prior.len() / 10 {
            let (mp, cp, _) = mass_com_inertia(&block(&self.prior, b));
            let (mi, ci, _) = mass_com_inertia(&block(&self.identified, b));
            let mt = self
                .truth
                .as_ref()
                .map(|t| format!("{:>9.4}", block(t, b)[0]))
                .unwrap_or_else(|| format!("{:>9}", "-"));
            let _ = writeln!(
                s,
                "  {:<42} {mp:>9.4} {mi:>9.4} {mt}   {:<26} {:<26}",
                block_name(&self.model, b),
                format!("{:.4} {:.4} {:.4}", cp.x, cp.y, cp.z),
                format!("{:.4} {:.4} {:.4}", ci.x, ci.y, ci.z),
            );
        }
        s
    }

    /// The `--report` TOML: summary, per-body parameters before/after (and the plant's), friction,
    /// offsets and the singular values.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let logs: Vec<String> = self
            .logs
            .iter()
            .map(|p| format!("{:?}", p.display().to_string()))
            .collect();
        let _ = writeln!(
            s,
            "# `stride identify` report [Traversaro 2017, ch. 6-7]: masses kg, CoM m (body frame), inertia about\n\
             # the CoM kg m^2 [xx, xy, xz, yy, yz, zz], friction N m and N m s/rad, offsets N and N m.\n\
             [summary]\nlogs = [{}]\nsamples = {}\nrows = {}\nbase_rows = {}\nparameters = {}\nidentifiable = {}\n\
             condition_number = {:?}\nresidual_prior = {:?}\nresidual_identified = {:?}\nresidual_unconstrained = {:?}\n\
             iterations = {}\nconverged = {}\nobjective = {:?}\nunconstrained_not_fully_consistent = {}",
            logs.join(", "),
            self.samples,
            self.rows,
            self.base_rows,
            self.prior.len(),
            self.base.rank(),
            self.condition_number,
            self.residuals[0],
            self.residuals[1],
            self.residuals[2],
            self.iterations.0,
            self.iterations.1,
            self.objective,
            self.unconstrained_violations.len()
        );
        if let Some(e) = self.identifiable_error(&self.prior) {
            let _ = writeln!(
                s,
                "identifiable_error_prior = {e:?}\nidentifiable_error_identified = {:?}\nidentifiable_error_unconstrained = {:?}",
                self.identifiable_error(&self.identified).unwrap_or(f64::NAN),
                self.identifiable_error(&self.unconstrained).unwrap_or(f64::NAN)
            );
        }
        let _ = writeln!(
            s,
            "singular_values = {}",
            list(self.base.singular_values.iter().cloned())
        );
        for b in 0..self.prior.len() / 10 {
            let _ = writeln!(s, "\n[[body]]\nname = {:?}", block_name(&self.model, b));
            let mut sets = vec![("prior", &self.prior), ("identified", &self.identified)];
            sets.push(("unconstrained", &self.unconstrained));
            if let Some(t) = &self.truth {
                sets.push(("true", t));
            }
            for (what, psi) in sets {
                let (m, c, i) = mass_com_inertia(&block(psi, b));
                let _ = writeln!(
                    s,
                    "{what} = {{ mass = {m:?}, com = {}, inertia = {} }}",
                    vec3(&c),
                    list(vech(&i))
                );
            }
        }
        self.extras_toml(&mut s);
        s
    }

    fn extras_toml(&self, s: &mut String) {
        let dof = self.model.dof();
        let mut at = 0;
        if self.options.use_torques {
            let names: Vec<String> = self
                .model
                .joints()
                .iter()
                .map(|j| format!("{:?}", j.name))
                .collect();
            let _ = writeln!(
                s,
                "\n[friction]\njoints = [{}]\ncoulomb = {}\nviscous = {}",
                names.join(", "),
                list(self.extras.rows(0, dof).iter().cloned()),
                list(self.extras.rows(dof, dof).iter().cloned())
            );
            at = 2 * dof;
        }
        if self.options.use_ft && !self.model.ft_sensors().is_empty() {
            let _ = writeln!(s, "\n[ft_offsets]");
            for (k, sensor) in self.model.ft_sensors().iter().enumerate() {
                let _ = writeln!(
                    s,
                    "{:?} = {}",
                    sensor.name,
                    list(self.extras.rows(at + 6 * k, 6).iter().cloned())
                );
            }
        }
    }
}
