//! The planned foot wrenches the compliant TSID's wrench regularization pulls toward
//! [Romualdi 2022, eq. 8.2.9]: on soft ground a wrench cannot jump, so the load moves from foot to foot with
//! the plan's ZMP rather than by the rigid TSID's contact ramps.

use nalgebra::{Vector2, Vector3, Vector6};
use stride_simplified::right_foot_share;

/// The total ground force `m (ẍ* + g ẑ)` (N) split between the feet in contact (`contacts`, soles at
/// `soles`, world, m): in double support by [`right_foot_share`] of the desired ZMP `zmp` (world x-y, m),
/// `(1 − t)` on the left, `t` on the right, no torque about the soles (their CoP is the ZMP's projection on
/// the segment between them), in single support all on the stance foot with
/// its CoP at `zmp` (torque `(zmp − p) × f` about the sole, N·m). No foot in contact: zero wrenches.
pub fn planned_foot_wrenches(
    mass: f64,
    gravity: f64,
    com_acceleration: &Vector3<f64>,
    zmp: &Vector2<f64>,
    soles: &[Vector3<f64>; 2],
    contacts: [bool; 2],
) -> [Vector6<f64>; 2] {
    let force = mass * (com_acceleration + Vector3::new(0.0, 0.0, gravity));
    let wrench = |f: Vector3<f64>, torque: Vector3<f64>| {
        Vector6::new(f.x, f.y, f.z, torque.x, torque.y, torque.z)
    };
    match contacts {
        [true, true] => {
            let t = right_foot_share(zmp, &soles[0].xy(), &soles[1].xy());
            [
                wrench(force * (1.0 - t), Vector3::zeros()),
                wrench(force * t, Vector3::zeros()),
            ]
        }
        [left, right] if left || right => {
            let k = usize::from(right);
            let p = soles[k];
            let arm = Vector3::new(zmp.x - p.x, zmp.y - p.y, 0.0);
            let mut out = [Vector6::zeros(); 2];
            out[k] = wrench(force, arm.cross(&force));
            out
        }
        _ => [Vector6::zeros(); 2],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_support_puts_the_cop_at_the_zmp_projection_and_carries_the_total() {
        let soles = [Vector3::new(0.0, 0.1, 0.0), Vector3::new(0.2, -0.1, 0.0)];
        let acc = Vector3::new(0.3, -0.1, 0.2);
        let zmp = Vector2::new(0.15, -0.05);
        let w = planned_foot_wrenches(30.0, 9.81, &acc, &zmp, &soles, [true, true]);
        let total = w[0].fixed_rows::<3>(0) + w[1].fixed_rows::<3>(0);
        assert!((total - 30.0 * (acc + Vector3::new(0.0, 0.0, 9.81))).norm() < 1e-9);
        // the combined CoP of the two soles (torques zero about them) is the projection of the ZMP
        let cop = (soles[0] * w[0][2] + soles[1] * w[1][2]) / (w[0][2] + w[1][2]);
        let d = (soles[1] - soles[0]).xy();
        assert!((cop.xy() - soles[0].xy()).perp(&d).abs() < 1e-12);
        assert!(((zmp - cop.xy()).dot(&d)).abs() < 1e-12);
        // beyond a sole: all on it
        let far = planned_foot_wrenches(
            30.0,
            9.81,
            &acc,
            &Vector2::new(-1.0, 0.5),
            &soles,
            [true, true],
        );
        assert_eq!(far[1], Vector6::zeros());
    }

    #[test]
    fn single_support_puts_the_cop_at_the_zmp() {
        let soles = [Vector3::new(0.0, 0.1, 0.0), Vector3::new(0.2, -0.1, 0.0)];
        let zmp = Vector2::new(0.22, -0.09);
        let w = planned_foot_wrenches(30.0, 9.81, &Vector3::zeros(), &zmp, &soles, [false, true]);
        assert_eq!(w[0], Vector6::zeros());
        let (f, tau) = (w[1].fixed_rows::<3>(0), w[1].fixed_rows::<3>(3));
        // CoP of a wrench about p: p + (−τ_y, τ_x) / f_z
        let cop = soles[1].xy() + Vector2::new(-tau.y, tau.x) / f.z;
        assert!((cop - zmp).norm() < 1e-12);
        assert_eq!(
            planned_foot_wrenches(30.0, 9.81, &Vector3::zeros(), &zmp, &soles, [false, false]),
            [Vector6::zeros(); 2]
        );
    }
}
