//! Test plans written in closed form, independent of stride-planner.
#![allow(dead_code)]

use nalgebra::Vector2;
use stride_simplified::{FootRectangle, SupportPolygon};

pub const OMEGA: f64 = 4.302_325_511_579_751; // sqrt(9.81 / 0.53)

/// Admissible rectangle of a foot centred on its sole frame (iCub-like size, slightly enlarged).
pub fn foot(x: f64, y: f64) -> FootRectangle {
    FootRectangle {
        position: Vector2::new(x, y),
        yaw: 0.0,
        x_min: -0.05,
        x_max: 0.07,
        y_min: -0.03,
        y_max: 0.03,
    }
}

pub fn foot_center(f: &FootRectangle) -> Vector2<f64> {
    f.position + Vector2::new(0.5 * (f.x_min + f.x_max), 0.5 * (f.y_min + f.y_max))
}

/// A walk sampled at `period`: the ZMP is constant over each tick, so the DCM is the exact closed form
/// [Romualdi 2022, eq. 10.1.16] `ξ(t) = ẑ_k + e^{ω(t − t_k)} (ξ_k − ẑ_k)` over every tick, obtained by the backward recursion
/// from a final DCM at rest on the final ZMP. The CoM is the exact solution of `ẋ = −ω(x − ξ)` for that
/// DCM (stable forward propagation).
pub struct Plan {
    pub period: f64,
    pub omega: f64,
    pub zmp: Vec<Vector2<f64>>,
    pub dcm: Vec<Vector2<f64>>,
    pub dcm_velocity: Vec<Vector2<f64>>,
    pub com: Vec<Vector2<f64>>,
    pub com_velocity: Vec<Vector2<f64>>,
    pub support: Vec<SupportPolygon>,
    pub walking: Vec<bool>,
}

impl Plan {
    pub fn len(&self) -> usize {
        self.zmp.len()
    }

    /// Straight walk: `steps` steps of `step_length`, DS transfers of `ds` s, SS of `ss` s, standing
    /// 1 s at the start and `final_stand` s at the end. `feet_y` is half the feet distance.
    pub fn walk(
        period: f64,
        steps: usize,
        step_length: f64,
        ss: f64,
        ds: f64,
        final_stand: f64,
    ) -> Plan {
        let omega = OMEGA;
        let feet_y = 0.08;
        let mut left = foot(0.0, feet_y);
        let mut right = foot(0.0, -feet_y);
        // Phases: (duration, zmp start, zmp end, support feet, walking)
        struct Phase {
            duration: f64,
            from: Vector2<f64>,
            to: Vector2<f64>,
            support: SupportPolygon,
            walking: bool,
        }
        let both = |l: &FootRectangle, r: &FootRectangle| {
            stride_simplified::feet_support_polygon(&[*l, *r]).unwrap()
        };
        let mut phases = Vec::new();
        let mut zmp = 0.5 * (foot_center(&left) + foot_center(&right));
        phases.push(Phase {
            duration: 1.0,
            from: zmp,
            to: zmp,
            support: both(&left, &right),
            walking: false,
        });
        for j in 0..steps {
            // the right foot swings on even steps, the left on odd ones
            let swing_right = j % 2 == 0;
            let stance = if swing_right { left } else { right };
            let target = foot_center(&stance);
            phases.push(Phase {
                duration: ds,
                from: zmp,
                to: target,
                support: both(&left, &right),
                walking: true,
            });
            phases.push(Phase {
                duration: ss,
                from: target,
                to: target,
                support: stride_simplified::feet_support_polygon(&[stance]).unwrap(),
                walking: true,
            });
            zmp = target;
            let new_x = (j as f64 + 1.0) * step_length;
            if swing_right {
                right = foot(new_x, -feet_y);
            } else {
                left = foot(new_x, feet_y);
            }
        }
        let end = 0.5 * (foot_center(&left) + foot_center(&right));
        phases.push(Phase {
            duration: ds,
            from: zmp,
            to: end,
            support: both(&left, &right),
            walking: true,
        });
        phases.push(Phase {
            duration: final_stand,
            from: end,
            to: end,
            support: both(&left, &right),
            walking: false,
        });
        let mut plan = Plan {
            period,
            omega,
            zmp: vec![],
            dcm: vec![],
            dcm_velocity: vec![],
            com: vec![],
            com_velocity: vec![],
            support: vec![],
            walking: vec![],
        };
        for phase in &phases {
            let ticks = (phase.duration / period).round() as usize;
            for i in 0..ticks {
                let s = i as f64 / ticks as f64;
                plan.zmp.push(phase.from + (phase.to - phase.from) * s);
                plan.support.push(phase.support);
                plan.walking.push(phase.walking);
            }
        }
        let k_end = plan.zmp.len();
        let decay = (-omega * period).exp();
        let mut dcm = vec![Vector2::zeros(); k_end + 1];
        dcm[k_end] = plan.zmp[k_end - 1];
        for k in (0..k_end).rev() {
            dcm[k] = plan.zmp[k] + (dcm[k + 1] - plan.zmp[k]) * decay;
        }
        // CoM: ẋ = −ω(x − ξ), ξ(τ) = ẑ + e^{ωτ}(ξ_k − ẑ) ⇒ x(τ) = ẑ + (x_k − ẑ)e^{−ωτ} + (ξ_k − ẑ) sinh(ωτ).
        let mut com = vec![Vector2::zeros(); k_end + 1];
        com[0] = dcm[0];
        let sinh = (omega * period).sinh();
        for k in 0..k_end {
            let z = plan.zmp[k];
            com[k + 1] = z + (com[k] - z) * decay + (dcm[k] - z) * sinh;
        }
        for k in 0..=k_end {
            let z = plan.zmp[k.min(k_end - 1)];
            plan.dcm_velocity.push((dcm[k] - z) * omega);
            plan.com_velocity.push((dcm[k] - com[k]) * omega);
        }
        plan.dcm = dcm;
        plan.com = com;
        // one extra sample so that index k_end exists everywhere
        let last_zmp = plan.zmp[k_end - 1];
        let last_support = plan.support[k_end - 1];
        plan.zmp.push(last_zmp);
        plan.support.push(last_support);
        plan.walking.push(false);
        plan
    }

    /// Default test walk: 6 steps of 0.1 m, SS 0.6 s, DS 0.2 s, stand 1.5 s at the end, at 100 Hz.
    pub fn default_walk() -> Plan {
        Plan::walk(0.01, 6, 0.1, 0.6, 0.2, 1.5)
    }
}
