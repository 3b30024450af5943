//! A sensor's offset estimated jointly with the inertial parameters of the body it carries, by least
//! squares on the force/torque-sensor regressor [Traversaro 2017, eqs. (5.1), (7.2)–(7.3)]: the model-based
//! companion of [`super::offset_from_rotations`], valid during motion as well as in static poses.

use nalgebra::{DMatrix, DVector, Vector6};
use stride_model::{KinDyn, RobotState};

use super::lsq::{StackedLeastSquares, RANK_TOLERANCE};
use super::CalibrationError;

/// Accumulates samples `r = Y_S ψ + b + n` of one sensor `S` (calibration matrix taken as identity):
/// `Y_S` its six rows of [`KinDyn::ft_sensor_regressor`] at the sample, `ψ` the inertial parameters of
/// its child side (FT-split layout), `b` the offset, `n` white noise with σ `noise` per axis. The rows are
/// weighted by `1/σ`, so the solution is the maximum-likelihood estimate under that noise.
///
/// Only the columns of `ψ` the sensor sees are unknowns (`columns`, e.g. from [`child_side_columns`]);
/// combinations of them that the motion does not excite are left at the minimum norm. The offset must be
/// determined ([`CalibrationError::NotIdentifiable`] otherwise): in static poses that needs gravity in
/// at least two directions of the sensor frame that are not parallel plus one off their plane, as
/// [`super::offset_from_rotations`].
#[derive(Clone, Debug)]
pub struct RegressorOffset {
    columns: Vec<usize>,
    weights: Vector6<f64>,
    ls: StackedLeastSquares,
    row: Vec<f64>,
}

/// The result of [`RegressorOffset::solve`].
#[derive(Clone, Debug)]
pub struct RegressorOffsetFit {
    /// The offset `b`, `[f; τ]`, N and N·m.
    pub offset: Vector6<f64>,
    /// Standard deviation of each offset component under the given noise, N and N·m.
    pub offset_std: Vector6<f64>,
    /// The child side's parameters in the order of `columns` (minimum norm on the unexcited combinations).
    pub parameters: DVector<f64>,
    /// Rank of the weighted regressor `[Y_S, 1₆]` and its number of columns.
    pub rank: usize,
    /// Number of unknowns (6 + columns).
    pub unknowns: usize,
    /// `√(χ² / rows)`: about 1 when the residuals match the noise model.
    pub normalised_residual: f64,
}

impl RegressorOffset {
    /// A problem with the regressor columns `columns` and the noise σ per axis `noise` (N, N·m; all
    /// positive).
    pub fn new(columns: Vec<usize>, noise: Vector6<f64>) -> Result<Self, CalibrationError> {
        if !noise.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(CalibrationError::NonFinite {
                what: "noise σ (must be positive and finite)",
                index: 0,
            });
        }
        let unknowns = 6 + columns.len();
        Ok(Self {
            weights: noise.map(|s| 1.0 / s),
            ls: StackedLeastSquares::new(unknowns),
            row: vec![0.0; unknowns],
            columns,
        })
    }

    /// Adds a sample: `rows` are the sensor's six rows of the FT-sensor regressor (any number of columns
    /// covering `columns`), `raw` the reading.
    pub fn add(
        &mut self,
        rows: &nalgebra::DMatrixView<'_, f64>,
        raw: &Vector6<f64>,
    ) -> Result<(), CalibrationError> {
        if rows.nrows() != 6 {
            return Err(CalibrationError::Size {
                what: "regressor rows of one sensor",
                expected: 6,
                actual: rows.nrows(),
            });
        }
        if let Some(&c) = self.columns.iter().find(|&&c| c >= rows.ncols()) {
            return Err(CalibrationError::Size {
                what: "regressor columns (a selected column is beyond them)",
                expected: c + 1,
                actual: rows.ncols(),
            });
        }
        let index = self.ls.rows() / 6;
        if !raw.iter().all(|v| v.is_finite()) {
            return Err(CalibrationError::NonFinite {
                what: "raw reading",
                index,
            });
        }
        for a in 0..6 {
            let w = self.weights[a];
            self.row.fill(0.0);
            self.row[a] = w;
            for (k, &c) in self.columns.iter().enumerate() {
                self.row[6 + k] = w * rows[(a, c)];
            }
            if !self.row.iter().all(|v| v.is_finite()) {
                return Err(CalibrationError::NonFinite {
                    what: "regressor",
                    index,
                });
            }
            self.ls.add_row(&self.row, w * raw[a]);
        }
        Ok(())
    }

    /// Number of samples added.
    pub fn samples(&self) -> usize {
        self.ls.rows() / 6
    }

    /// The offset and parameters; [`CalibrationError::NotIdentifiable`] when the samples leave the offset
    /// undetermined.
    pub fn solve(&self) -> Result<RegressorOffsetFit, CalibrationError> {
        let unknowns = self.ls.unknowns();
        if self.ls.rows() < unknowns {
            return Err(CalibrationError::TooFewSamples {
                what: "offset with inertial parameters",
                needed: unknowns.div_ceil(6),
                got: self.samples(),
            });
        }
        let sol = self.ls.solve(RANK_TOLERANCE);
        if sol.null_component(0..6) > 1e-6 {
            return Err(CalibrationError::NotIdentifiable {
                what: "the offset",
                rank: sol.rank,
                unknowns,
                hint: "rotate the sensor so that gravity takes directions off one plane (two axes)",
            });
        }
        let offset = Vector6::from_iterator(sol.x.iter().take(6).cloned());
        let offset_std = Vector6::from_fn(|i, _| sol.covariance[(i, i)].max(0.0).sqrt());
        Ok(RegressorOffsetFit {
            offset,
            offset_std,
            parameters: sol.x.rows(6, unknowns - 6).into_owned(),
            rank: sol.rank,
            unknowns,
            normalised_residual: (sol.residual_squared / sol.rows as f64).sqrt(),
        })
    }
}

/// The columns of [`KinDyn::ft_sensor_regressor`] that can be non-zero in sensor `sensor`'s rows: the
/// parameters of its child side. Found at a generic state (every joint position, velocity and
/// acceleration non-zero and distinct), where only structural zeros remain.
pub fn child_side_columns(kd: &mut KinDyn, sensor: usize) -> Result<Vec<usize>, CalibrationError> {
    let model = std::sync::Arc::clone(kd.model());
    let ns = model.ft_sensors().len();
    if sensor >= ns {
        return Err(CalibrationError::Size {
            what: "sensor index (number of sensors)",
            expected: ns,
            actual: sensor,
        });
    }
    let mut state = RobotState::zero(&model);
    let generic = |i: usize, scale: f64| scale * (0.3 + 0.17 * i as f64).sin();
    for i in 0..model.dof() {
        state.joint_positions[i] = generic(i, 0.5);
        state.joint_velocities[i] = generic(i + 7, 0.8);
    }
    for i in 0..6 {
        state.base_velocity[i] = generic(i + 3, 0.4);
    }
    let nu_dot = DVector::from_fn(model.nv(), |i, _| generic(i + 11, 1.3));
    kd.set_state(&state)?;
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    kd.ft_sensor_regressor(&nu_dot, &mut y)?;
    let rows = y.rows(6 * sensor, 6);
    Ok((0..y.ncols())
        .filter(|&c| rows.column(c).iter().any(|v| *v != 0.0))
        .collect())
}
