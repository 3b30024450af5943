//! The TSID's weights during a push (`[simplified.push] wbc_com_weight`, `wbc_upright_weight`, issue 13):
//! while the push response's estimate exceeds `wbc_force`, the walking preset's soft `com` task and its
//! `torso` and `pelvis` orientation tasks take the configured push weights, and their own weights again
//! once it falls below. With the CoM tracked hard (or heavily) a push the sole's CoP region cannot
//! balance is paid with the torso's orientation (docs/push-recovery.md, "Torque control: why the torso
//! tips"); with these weights the QP lets the CoM give way instead, and the DCM error that follows is what
//! the step adjustment reads.

use nalgebra::Vector2;
use stride_simplified::PushConfig;
use stride_wbc::{Priority, TaskConfig, Tsid, WbcError, Weight};

/// Which task a switched weight belongs to, and its weights outside and during a push.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Switched {
    task: &'static str,
    nominal: f64,
    pushed: f64,
}

/// The weight switch; no allocation after [`PushWeights::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct PushWeights {
    force: f64,
    nominal_in_hold: bool,
    tasks: [Option<Switched>; 3],
    /// Whether the push weights are in the TSID now.
    active: bool,
    /// Ticks with the push weights, for the summary.
    pub ticks: u64,
}

impl PushWeights {
    /// The switch of `config` for `tsid`, `None` when neither weight is set. Errors: a switched task
    /// (`com`; `torso`, `pelvis`) that the TSID lacks, that is hard, or whose weight is not one scalar.
    pub fn new(config: &PushConfig, tsid: &Tsid) -> Result<Option<Self>, WbcError> {
        let tasks = &tsid.config().tasks;
        let switched = |task: &'static str, pushed: f64| -> Result<Option<Switched>, WbcError> {
            if pushed <= 0.0 {
                return Ok(None);
            }
            let nominal = soft_scalar_weight(tasks, task)?;
            Ok(Some(Switched {
                task,
                nominal,
                pushed,
            }))
        };
        let tasks = [
            switched("com", config.wbc_com_weight)?,
            switched("torso", config.wbc_upright_weight)?,
            switched("pelvis", config.wbc_upright_weight)?,
        ];
        Ok(tasks.iter().any(Option::is_some).then_some(Self {
            force: config.wbc_force,
            nominal_in_hold: config.wbc_nominal_in_hold,
            tasks,
            active: false,
            ticks: 0,
        }))
    }

    /// Whether the push weights are in the TSID.
    pub fn active(&self) -> bool {
        self.active
    }

    /// Puts the push weights into `tsid` while `estimate` \[N\] exceeds `wbc_force` (and, with
    /// `wbc_nominal_in_hold`, no double support is `held`), the nominal ones otherwise (a change only
    /// when the state changes).
    pub fn update(
        &mut self,
        estimate: &Vector2<f64>,
        held: bool,
        tsid: &mut Tsid,
    ) -> Result<(), WbcError> {
        let pushed = estimate.norm() > self.force && !(self.nominal_in_hold && held);
        if pushed {
            self.ticks += 1;
        }
        if pushed == self.active {
            return Ok(());
        }
        for s in self.tasks.iter().flatten() {
            let w = if pushed { s.pushed } else { s.nominal };
            tsid.set_task_weight(s.task, &[w])?;
        }
        self.active = pushed;
        Ok(())
    }
}

/// The scalar weight of the soft task `name` of `tasks`.
fn soft_scalar_weight(tasks: &[TaskConfig], name: &str) -> Result<f64, WbcError> {
    let invalid = |reason: &str| WbcError::InvalidConfig {
        task: name.into(),
        key: "priority",
        reason: format!("simplified.push.wbc_*_weight switches this task's weight: {reason}"),
    };
    let (priority, weight) = match tasks.iter().find(|t| t.name() == name) {
        Some(TaskConfig::Com(c)) => (c.priority, &c.weight),
        Some(TaskConfig::So3(c)) => (c.priority, &c.weight),
        Some(_) => return Err(invalid("not a `com` or `so3` task")),
        None => return Err(invalid("the TSID has no task of this name")),
    };
    match (priority, weight) {
        (Priority::Soft, Some(Weight::Scalar(w))) => Ok(*w),
        (Priority::Soft, None) => Ok(1.0),
        (Priority::Soft, Some(Weight::PerRow(_))) => Err(invalid("it must have one scalar weight")),
        (Priority::Hard, _) => Err(invalid("it must be soft")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stride_wbc::{ComTaskConfig, Frame3TaskConfig, ZmpTaskConfig};

    fn com(priority: Priority, weight: Option<Weight>) -> TaskConfig {
        TaskConfig::Com(ComTaskConfig {
            name: "com".into(),
            kp: 25.0,
            kd: 5.0,
            kp_z: None,
            kd_z: None,
            mask: [true; 3],
            priority,
            weight,
        })
    }

    fn torso(weight: Option<Weight>) -> TaskConfig {
        TaskConfig::So3(Frame3TaskConfig {
            name: "torso".into(),
            frame: "chest".into(),
            reference: "torso".into(),
            reference_offset: Default::default(),
            kp: 100.0,
            kd: 20.0,
            mask: [true; 3],
            priority: Priority::Soft,
            weight,
        })
    }

    #[test]
    fn a_soft_scalar_weight_is_read_and_a_hard_or_missing_task_is_an_error_naming_it() {
        let tasks = [
            com(Priority::Soft, Some(Weight::Scalar(100.0))),
            torso(None),
        ];
        assert_eq!(soft_scalar_weight(&tasks, "com").unwrap(), 100.0);
        assert_eq!(soft_scalar_weight(&tasks, "torso").unwrap(), 1.0);
        let missing = soft_scalar_weight(&tasks, "pelvis").unwrap_err();
        assert!(missing.to_string().contains("`pelvis`"), "{missing}");
        let hard = soft_scalar_weight(&[com(Priority::Hard, None)], "com").unwrap_err();
        assert!(hard.to_string().contains("must be soft"), "{hard}");
        let per_row = [com(Priority::Soft, Some(Weight::PerRow(vec![1.0; 3])))];
        assert!(soft_scalar_weight(&per_row, "com").is_err());
        let zmp = [TaskConfig::Zmp(ZmpTaskConfig {
            name: "com".into(),
            priority: Priority::Soft,
            weight: Some(Weight::Scalar(1.0)),
        })];
        let kind = soft_scalar_weight(&zmp, "com").unwrap_err();
        assert!(
            kind.to_string().contains("not a `com` or `so3` task"),
            "{kind}"
        );
    }
}
