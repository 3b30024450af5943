//! The JSON of the log's per-tick messages written straight into the message buffer: byte for byte what
//! `serde_json::to_writer` writes for the same value, without serde's field-by-field dispatch and key
//! escaping. The keys are constant bytes (from the field names, in declaration order, by `json_object!`
//! and `json_fields!`); numbers go through serde_json's own `CompactFormatter` (its float formatting,
//! `null` for NaN and ±∞ as its serializer writes); strings, enums and the rare sub-values through
//! serde_json itself (`Serde`). The pattern of `tf_json.rs`, for `/wbc/input`, `/wbc/output`,
//! `/planner/references`, `/simplified/input`, `/simplified/output`, `/runner/tracking` and the state
//! topics: the bulk of the log's bytes (docs/performance.md, "the log's per-tick messages without serde's
//! dispatch").
//!
//! A field added to one of these records without its line here makes the bytes differ from serde's: the
//! tests below compare both over random values of every record.

use std::borrow::Cow;
use std::time::Duration;

use nalgebra::SVector;
use serde::Serialize;
use serde_json::ser::{CompactFormatter, Formatter};
use stride_simplified::{
    MpcDiagnostics, SimplifiedDiagnostics, SimplifiedInput, SimplifiedOutput, ZmpComGains,
};
use stride_wbc::{SolveReport, TaskResidual};

use crate::records::{
    ContactsMsg, EstimationMsg, FeetMsg, FootMsg, FootReferenceRecord, FootSampleRecord, FtMsg,
    IkOutputRecord, ImuMsg, OrientationRecord, PlanSampleRecord, PlantTrackingMsg, PoseRecord,
    SimStateMsg, StateRecord, TrackingMsg, TsidOutputRecord, WbcInputRecord,
};

type Result = std::result::Result<(), serde_json::Error>;

/// A value that appends its JSON (serde_json's compact bytes) to a buffer.
pub(crate) trait Json {
    /// Appends the JSON of `self` to `out`.
    fn json(&self, out: &mut Vec<u8>) -> Result;
}

/// Appends `,"a":…,"b":…` for the fields `a`, `b`, … of `$v`, in the order given.
macro_rules! json_fields {
    ($out:ident, $v:expr; $($field:ident),* $(,)?) => {
        $(
            $out.extend_from_slice(concat!(",\"", stringify!($field), "\":").as_bytes());
            Json::json(&$v.$field, $out)?;
        )*
    };
}

/// Appends `{"a":…,"b":…}` for the fields `a`, `b`, … of `$v`, in the order given (serde's: the
/// declaration order).
macro_rules! json_object {
    ($out:ident, $v:expr; $first:ident $(, $rest:ident)* $(,)?) => {{
        $out.extend_from_slice(concat!("{\"", stringify!($first), "\":").as_bytes());
        Json::json(&$v.$first, $out)?;
        json_fields!($out, $v; $($rest),*);
        $out.push(b'}');
        Ok(())
    }};
}

/// Appends the bytes `key` (`,"name":`) and the JSON of `v`.
fn field(out: &mut Vec<u8>, key: &[u8], v: &(impl Json + ?Sized)) -> Result {
    out.extend_from_slice(key);
    v.json(out)
}

/// A value written by serde_json itself (enums, strings, rare sub-values).
struct Serde<'a, T: ?Sized>(&'a T);

impl<T: Serialize + ?Sized> Json for Serde<'_, T> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        serde_json::to_writer(&mut *out, self.0)
    }
}

impl Json for f64 {
    #[inline]
    fn json(&self, out: &mut Vec<u8>) -> Result {
        // serde_json's `serialize_f64`: `null` for NaN and ±∞, else its formatter's shortest round trip,
        // which writes the zeros (a sixth of the log's numbers) as `0.0` and `-0.0`.
        if *self == 0.0 {
            out.extend_from_slice(if self.is_sign_negative() {
                b"-0.0"
            } else {
                b"0.0"
            });
            return Ok(());
        }
        if self.is_finite() {
            CompactFormatter.write_f64(out, *self)
        } else {
            CompactFormatter.write_null(out)
        }
        .map_err(serde_json::Error::io)
    }
}

impl Json for u64 {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        CompactFormatter
            .write_u64(out, *self)
            .map_err(serde_json::Error::io)
    }
}

impl Json for u32 {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        CompactFormatter
            .write_u32(out, *self)
            .map_err(serde_json::Error::io)
    }
}

impl Json for usize {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        // serde serializes `usize` as `u64`.
        (*self as u64).json(out)
    }
}

impl Json for bool {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        out.extend_from_slice(if *self { b"true" } else { b"false" });
        Ok(())
    }
}

impl Json for str {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        Serde(self).json(out)
    }
}

impl Json for String {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        self.as_str().json(out)
    }
}

impl<T: Json + ?Sized> Json for &T {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        (**self).json(out)
    }
}

impl<T: Json> Json for [T] {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        out.push(b'[');
        for (i, v) in self.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            v.json(out)?;
        }
        out.push(b']');
        Ok(())
    }
}

impl<T: Json, const N: usize> Json for [T; N] {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        self.as_slice().json(out)
    }
}

impl<T: Json + ToOwned + ?Sized> Json for Cow<'_, T> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        (**self).json(out)
    }
}

impl<T: Json> Json for Option<T> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        match self {
            Some(v) => v.json(out),
            None => {
                out.extend_from_slice(b"null");
                Ok(())
            }
        }
    }
}

impl<const D: usize> Json for SVector<f64, D> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        // nalgebra's serde form of a fixed-size vector: the sequence of its entries.
        self.as_slice().json(out)
    }
}

impl Json for Duration {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        out.extend_from_slice(b"{\"secs\":");
        self.as_secs().json(out)?;
        out.extend_from_slice(b",\"nanos\":");
        self.subsec_nanos().json(out)?;
        out.push(b'}');
        Ok(())
    }
}

impl Json for PoseRecord {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; position, orientation_xyzw)
    }
}

impl Json for StateRecord<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; base, joint_positions, base_velocity, joint_velocities)
    }
}

impl Json for FootReferenceRecord {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; pose, velocity, acceleration)
    }
}

impl Json for OrientationRecord {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; orientation_xyzw, angular_velocity, angular_acceleration)
    }
}

impl Json for WbcInputRecord<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            time_ns, state, com_position, com_velocity, com_acceleration, left_foot, right_foot,
            left_in_contact, right_in_contact, desired_zmp, desired_wrenches, torso, posture,
            angular_momentum)
    }
}

impl Json for SolveReport {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        field(out, b"{\"status\":", &Serde(&self.status))?;
        field(
            out,
            b",\"relaxed_status\":",
            &self.relaxed_status.as_ref().map(Serde),
        )?;
        json_fields!(out, self; iterations, solve_time, tick_time, fallback, held);
        out.push(b'}');
        Ok(())
    }
}

impl Json for TaskResidual {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; name, hard, residual)
    }
}

impl Json for IkOutputRecord<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            joint_positions, joint_velocities, base_velocity, base_pose, report, residuals)
    }
}

impl Json for TsidOutputRecord<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            joint_torques, accelerations, contact_wrenches, contact_load, report, residuals)
    }
}

impl Json for FootSampleRecord {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; pose, twist, acceleration, in_contact)
    }
}

impl Json for PlanSampleRecord {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            time, omega, dcm_position, dcm_velocity, zmp, com_position, com_velocity,
            com_acceleration, left, right, phase)
    }
}

impl Json for SimplifiedInput {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        field(out, b"{\"time\":", &self.time)?;
        json_fields!(out, self;
            omega, walking, planned_dcm_position, planned_dcm_velocity, planned_zmp,
            planned_com_position, planned_com_velocity, measured_com_position,
            measured_com_velocity, measured_dcm, measured_zmp);
        field(
            out,
            b",\"support_polygon\":",
            self.support_polygon.vertices(),
        )?;
        field(out, b",\"horizon\":", &Serde(&self.horizon))?;
        out.push(b'}');
        Ok(())
    }
}

impl Json for ZmpComGains {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; k_zmp, k_com)
    }
}

impl Json for MpcDiagnostics {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        field(out, b"{\"status\":", &Serde(&self.status))?;
        json_fields!(out, self;
            iterations, solve_time, stages, held_samples, active_constraints, cost, fallback);
        out.push(b'}');
        Ok(())
    }
}

impl Json for SimplifiedDiagnostics {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        field(out, b"{\"controller\":", &Serde(&self.controller))?;
        json_fields!(out, self;
            dcm_error, integral_term, unprojected_zmp, projection_active, zmp_error, com_error,
            com_velocity_error, zmp_com_gains, gain_blend_progress, thesis_gain_conditions_met,
            mpc, solve_time);
        out.push(b'}');
        Ok(())
    }
}

impl Json for SimplifiedOutput {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            time, valid, desired_zmp, com_position, com_velocity, com_acceleration, diagnostics)
    }
}

impl Json for PlantTrackingMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; dcm_error, com_error, com, dcm)
    }
}

impl Json for TrackingMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        field(out, b"{\"time\":", &self.time)?;
        json_fields!(out, self;
            dcm_error, com_error, zmp_error, zmp_edge_distance, feet_error, measured_com,
            measured_dcm, measured_zmp, base_height, tilt_deg);
        // `#[serde(skip_serializing_if = "Option::is_none")]`
        if let Some(push) = &self.push_estimate {
            field(out, b",\"push_estimate\":", push)?;
        }
        if let Some(plant) = &self.plant {
            field(out, b",\"plant\":", plant)?;
        }
        out.push(b'}');
        Ok(())
    }
}

impl Json for SimStateMsg<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        // `state` is `#[serde(flatten)]`: its fields inline, between `time` and `joint_torques`.
        field(out, b"{\"time\":", &self.time)?;
        json_fields!(out, self.state; base, joint_positions, base_velocity, joint_velocities);
        json_fields!(out, self; joint_torques, saturated);
        out.push(b'}');
        Ok(())
    }
}

impl Json for FootMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; in_contact, yaw, force, torque, point)
    }
}

impl Json for FeetMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; time, left, right)
    }
}

impl Json for FtMsg<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; time, names, wrenches)
    }
}

impl Json for ContactsMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; left, right)
    }
}

impl Json for EstimationMsg<'_> {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self;
            time, base_position, base_orientation_xyzw, base_linear_velocity,
            base_angular_velocity, contacts, left_foot_wrench, right_foot_wrench, joint_torques)
    }
}

impl Json for ImuMsg {
    fn json(&self, out: &mut Vec<u8>) -> Result {
        json_object!(out, self; time, orientation_xyzw, angular_velocity, linear_acceleration)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector6};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use stride_simplified::{
        DcmControllerKind, DcmHorizon, HorizonSample, MpcStatus, SupportPolygon,
    };
    use stride_wbc::QpStatus;

    /// Floats of every kind serde_json formats differently: NaN and ±∞ (`null`), ±0, subnormals, the
    /// extremes, integers, the exponent thresholds, random bit patterns (every exponent) and the
    /// magnitudes of the log.
    fn float(rng: &mut ChaCha8Rng) -> f64 {
        const SPECIAL: [f64; 20] = [
            0.0,
            -0.0,
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            5e-324,
            -2.2250738585072014e-308,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            1.0,
            -3.0,
            1e15,
            1e16,
            1e17,
            123_456_789_012_345_680.0,
            1e-5,
            1e-7,
            0.1,
        ];
        match rng.random_range(0..4) {
            0 => SPECIAL[rng.random_range(0..SPECIAL.len())],
            1 => f64::from_bits(rng.random::<u64>()),
            2 => (rng.random::<f64>() - 0.5) * 10f64.powi(rng.random_range(-12..12)),
            _ => f64::from(rng.random_range(-1000..1000)) * 0.25,
        }
    }

    fn floats<const N: usize>(rng: &mut ChaCha8Rng) -> [f64; N] {
        std::array::from_fn(|_| float(rng))
    }

    fn vec2(rng: &mut ChaCha8Rng) -> Vector2<f64> {
        Vector2::new(float(rng), float(rng))
    }

    fn pose(rng: &mut ChaCha8Rng) -> PoseRecord {
        PoseRecord {
            position: floats(rng),
            orientation_xyzw: floats(rng),
        }
    }

    fn joints(rng: &mut ChaCha8Rng) -> Vec<f64> {
        let n = [0, 1, 7, 32][rng.random_range(0..4)];
        (0..n).map(|_| float(rng)).collect()
    }

    fn name(rng: &mut ChaCha8Rng) -> String {
        let names = [
            "left_foot",
            "",
            "quote\"d",
            "back\\slash",
            "tab\tnew\nline\u{1}",
            "ünïcode ✓",
        ];
        names[rng.random_range(0..names.len())].to_string()
    }

    fn polygon(rng: &mut ChaCha8Rng) -> SupportPolygon {
        let (x, y) = (rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
        SupportPolygon::rectangle(x - 0.1, x + 0.1, y - 0.05, y + 0.05).expect("rectangle")
    }

    /// Our bytes and serde_json's for `v`, equal.
    fn check<T: Json + Serialize>(v: &T, what: &str, k: usize) {
        let mut ours = Vec::new();
        v.json(&mut ours).expect("json");
        let theirs = serde_json::to_vec(v).expect("serde_json");
        assert_eq!(
            String::from_utf8_lossy(&ours),
            String::from_utf8_lossy(&theirs),
            "{what} #{k}"
        );
        assert_eq!(ours, theirs, "{what} #{k}");
    }

    const CASES: usize = 300;

    #[test]
    fn wbc_input_is_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for k in 0..CASES {
            let (q, v, posture) = (joints(&mut rng), joints(&mut rng), joints(&mut rng));
            let foot = |rng: &mut ChaCha8Rng| FootReferenceRecord {
                pose: pose(rng),
                velocity: floats(rng),
                acceleration: floats(rng),
            };
            let r = WbcInputRecord {
                time_ns: rng.random(),
                state: StateRecord {
                    base: pose(&mut rng),
                    joint_positions: Cow::Borrowed(&q),
                    base_velocity: floats(&mut rng),
                    joint_velocities: Cow::Owned(v),
                },
                com_position: floats(&mut rng),
                com_velocity: floats(&mut rng),
                com_acceleration: floats(&mut rng),
                left_foot: foot(&mut rng),
                right_foot: foot(&mut rng),
                left_in_contact: rng.random(),
                right_in_contact: rng.random(),
                desired_zmp: rng.random_bool(0.5).then(|| floats(&mut rng)),
                desired_wrenches: rng
                    .random_bool(0.5)
                    .then(|| [floats(&mut rng), floats(&mut rng)]),
                torso: OrientationRecord {
                    orientation_xyzw: floats(&mut rng),
                    angular_velocity: floats(&mut rng),
                    angular_acceleration: floats(&mut rng),
                },
                posture: rng.random_bool(0.5).then_some(Cow::Borrowed(&posture[..])),
                angular_momentum: floats(&mut rng),
            };
            check(&r, "/wbc/input", k);
        }
    }

    #[test]
    fn ik_output_is_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let statuses = [
            QpStatus::NotSolved,
            QpStatus::Solved,
            QpStatus::SolvedInaccurate,
            QpStatus::Infeasible,
            QpStatus::Unbounded,
            QpStatus::MaxIterations,
            QpStatus::HessianNotPositiveDefinite,
            QpStatus::InvalidData,
            QpStatus::NumericalError,
        ];
        for k in 0..CASES {
            let (q, v) = (joints(&mut rng), joints(&mut rng));
            let residuals: Vec<_> = (0..rng.random_range(0..9))
                .map(|_| TaskResidual {
                    name: name(&mut rng),
                    hard: rng.random(),
                    residual: float(&mut rng),
                })
                .collect();
            let status = |rng: &mut ChaCha8Rng| statuses[rng.random_range(0..statuses.len())];
            let r = IkOutputRecord {
                joint_positions: &q,
                joint_velocities: &v,
                base_velocity: floats(&mut rng),
                base_pose: pose(&mut rng),
                report: SolveReport {
                    status: status(&mut rng),
                    relaxed_status: rng.random_bool(0.5).then(|| status(&mut rng)),
                    iterations: rng.random::<u64>() as usize,
                    solve_time: float(&mut rng),
                    tick_time: float(&mut rng),
                    fallback: rng.random(),
                    held: rng.random(),
                },
                residuals: &residuals,
            };
            check(&r, "/wbc/output", k);
            let wrenches: Vec<Vector6<f64>> = (0..rng.random_range(0..5))
                .map(|_| Vector6::from(floats::<6>(&mut rng)))
                .collect();
            let load: Vec<f64> = wrenches.iter().map(|_| float(&mut rng)).collect();
            let tsid = TsidOutputRecord {
                joint_torques: &q,
                accelerations: &v,
                contact_wrenches: &wrenches,
                contact_load: &load,
                report: r.report,
                residuals: &residuals,
            };
            check(&tsid, "/wbc/output (TSID)", k);
        }
    }

    #[test]
    fn plan_sample_is_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for k in 0..CASES {
            let foot = |rng: &mut ChaCha8Rng| FootSampleRecord {
                pose: pose(rng),
                twist: floats(rng),
                acceleration: floats(rng),
                in_contact: rng.random(),
            };
            let phases = ["double_support", "left_stance", "right_stance"];
            let r = PlanSampleRecord {
                time: float(&mut rng),
                omega: float(&mut rng),
                dcm_position: floats(&mut rng),
                dcm_velocity: floats(&mut rng),
                zmp: floats(&mut rng),
                com_position: floats(&mut rng),
                com_velocity: floats(&mut rng),
                com_acceleration: floats(&mut rng),
                left: foot(&mut rng),
                right: foot(&mut rng),
                phase: if rng.random_bool(0.8) {
                    Cow::Borrowed(phases[rng.random_range(0..3)])
                } else {
                    Cow::Owned(name(&mut rng))
                },
            };
            check(&r, "/planner/references", k);
        }
    }

    #[test]
    fn simplified_input_and_output_are_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let kinds = [
            DcmControllerKind::Instantaneous,
            DcmControllerKind::Predictive,
            DcmControllerKind::CentroidalMpc,
        ];
        let statuses = [
            MpcStatus::NotRun,
            MpcStatus::Unconstrained,
            MpcStatus::Solved,
            MpcStatus::MaxIterations,
            MpcStatus::NumericalError,
        ];
        for k in 0..CASES {
            let mut horizon = DcmHorizon::with_capacity(3);
            for _ in 0..rng.random_range(0..4) {
                horizon
                    .push(HorizonSample {
                        dcm_position: vec2(&mut rng),
                        zmp: vec2(&mut rng),
                        support: polygon(&mut rng),
                    })
                    .expect("push");
            }
            let time = Duration::new(
                rng.random::<u64>() >> rng.random_range(0..64),
                rng.random_range(0..1_000_000_000),
            );
            let mut input = SimplifiedInput::new(3, polygon(&mut rng));
            input.time = time;
            input.omega = float(&mut rng);
            input.walking = rng.random();
            input.planned_dcm_position = vec2(&mut rng);
            input.planned_dcm_velocity = vec2(&mut rng);
            input.planned_zmp = vec2(&mut rng);
            input.planned_com_position = vec2(&mut rng);
            input.planned_com_velocity = vec2(&mut rng);
            input.measured_com_position = vec2(&mut rng);
            input.measured_com_velocity = vec2(&mut rng);
            input.measured_dcm = vec2(&mut rng);
            input.measured_zmp = vec2(&mut rng);
            input.horizon = horizon;
            check(&input, "/simplified/input", k);

            let mpc = MpcDiagnostics {
                status: statuses[rng.random_range(0..statuses.len())],
                iterations: rng.random(),
                solve_time: float(&mut rng),
                stages: rng.random::<u64>() as usize,
                held_samples: rng.random_range(0..100),
                active_constraints: rng.random_range(0..100),
                cost: float(&mut rng),
                fallback: rng.random(),
            };
            let output = SimplifiedOutput {
                time,
                valid: rng.random(),
                desired_zmp: vec2(&mut rng),
                com_position: vec2(&mut rng),
                com_velocity: vec2(&mut rng),
                com_acceleration: vec2(&mut rng),
                diagnostics: SimplifiedDiagnostics {
                    controller: kinds[rng.random_range(0..kinds.len())],
                    dcm_error: vec2(&mut rng),
                    integral_term: vec2(&mut rng),
                    unprojected_zmp: vec2(&mut rng),
                    projection_active: rng.random(),
                    zmp_error: vec2(&mut rng),
                    com_error: vec2(&mut rng),
                    com_velocity_error: vec2(&mut rng),
                    zmp_com_gains: rng.random_bool(0.5).then(|| ZmpComGains {
                        k_zmp: float(&mut rng),
                        k_com: float(&mut rng),
                    }),
                    gain_blend_progress: float(&mut rng),
                    thesis_gain_conditions_met: rng.random(),
                    mpc,
                    solve_time: float(&mut rng),
                },
            };
            check(&output, "/simplified/output", k);
        }
    }

    #[test]
    fn tracking_is_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for k in 0..CASES {
            let r = TrackingMsg {
                time: float(&mut rng),
                dcm_error: float(&mut rng),
                com_error: float(&mut rng),
                zmp_error: rng.random_bool(0.5).then(|| float(&mut rng)),
                zmp_edge_distance: rng.random_bool(0.5).then(|| float(&mut rng)),
                feet_error: float(&mut rng),
                measured_com: floats(&mut rng),
                measured_dcm: floats(&mut rng),
                measured_zmp: floats(&mut rng),
                base_height: float(&mut rng),
                tilt_deg: float(&mut rng),
                push_estimate: rng.random_bool(0.5).then(|| floats(&mut rng)),
                plant: rng.random_bool(0.5).then(|| PlantTrackingMsg {
                    dcm_error: float(&mut rng),
                    com_error: float(&mut rng),
                    com: floats(&mut rng),
                    dcm: floats(&mut rng),
                }),
            };
            check(&r, "/runner/tracking", k);
        }
    }

    #[test]
    fn state_topics_are_serde_json_s() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        for k in 0..CASES {
            let (q, v, tau) = (joints(&mut rng), joints(&mut rng), joints(&mut rng));
            let saturated: Vec<bool> = tau.iter().map(|_| rng.random()).collect();
            let state = SimStateMsg {
                time: float(&mut rng),
                state: StateRecord {
                    base: pose(&mut rng),
                    joint_positions: Cow::Borrowed(&q),
                    base_velocity: floats(&mut rng),
                    joint_velocities: Cow::Borrowed(&v),
                },
                joint_torques: &tau,
                saturated: &saturated,
            };
            check(&state, "/sim/state", k);
            let foot = |rng: &mut ChaCha8Rng| FootMsg {
                in_contact: rng.random(),
                yaw: float(rng),
                force: floats(rng),
                torque: floats(rng),
                point: floats(rng),
            };
            let feet = FeetMsg {
                time: float(&mut rng),
                left: foot(&mut rng),
                right: foot(&mut rng),
            };
            check(&feet, "/sensors/feet", k);
            let names: Vec<String> = (0..rng.random_range(0..5))
                .map(|_| name(&mut rng))
                .collect();
            let wrenches: Vec<[f64; 6]> = names.iter().map(|_| floats(&mut rng)).collect();
            let ft = FtMsg {
                time: float(&mut rng),
                names: &names,
                wrenches: &wrenches,
            };
            check(&ft, "/sensors/ft", k);
            let estimation = EstimationMsg {
                time: float(&mut rng),
                base_position: floats(&mut rng),
                base_orientation_xyzw: floats(&mut rng),
                base_linear_velocity: floats(&mut rng),
                base_angular_velocity: floats(&mut rng),
                contacts: ContactsMsg {
                    left: rng.random(),
                    right: rng.random(),
                },
                left_foot_wrench: floats(&mut rng),
                right_foot_wrench: floats(&mut rng),
                joint_torques: &tau,
            };
            check(&estimation, "/estimation/state", k);
            let imu = ImuMsg {
                time: float(&mut rng),
                orientation_xyzw: floats(&mut rng),
                angular_velocity: floats(&mut rng),
                linear_acceleration: floats(&mut rng),
            };
            check(&imu, "/sensors/imu", k);
        }
    }
}
