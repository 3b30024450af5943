//! Locked joints: movable joints turned into fixed joints at a given position when the model is built, the
//! way Pinocchio's `buildReducedModel` reduces a model (Carpentier et al. 2019, "The Pinocchio C++
//! library", §"reduced models"): the child link is placed at `origin · motion(q)` and merged into the
//! parent body (inertia lumped, link kept as a frame), so every algorithm sees the reduced tree.

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::error::ModelError;

/// One entry of a lock list: every movable joint whose name matches `pattern` is held at `position`.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `pattern` | – | a joint name, or a glob: `*` any run of characters, `?` one character |
/// | `position` | rad or m | the position the joint is locked at |
#[derive(Debug, Clone, PartialEq)]
pub struct JointLock {
    /// Joint name or glob.
    pub pattern: String,
    /// Locked position (rad for revolute and continuous joints, m for prismatic ones).
    pub position: f64,
}

impl JointLock {
    /// A lock of the joints matching `pattern` at `position`.
    pub fn new(pattern: &str, position: f64) -> Self {
        Self {
            pattern: pattern.into(),
            position,
        }
    }
}

/// Whether `name` matches the glob `pattern` (`*`: any run of characters, possibly empty; `?`: one
/// character; every other character itself).
pub fn glob_matches(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    // matched[j]: pattern prefix consumed so far matches name prefix of length j.
    let mut matched = vec![false; n.len() + 1];
    matched[0] = true;
    for &c in &p {
        let mut next = vec![false; n.len() + 1];
        for j in 0..=n.len() {
            next[j] = match c {
                '*' => matched[j] || (j > 0 && next[j - 1]),
                '?' => j > 0 && matched[j - 1],
                _ => j > 0 && matched[j - 1] && n[j - 1] == c,
            };
        }
        matched = next;
    }
    matched[n.len()]
}

/// The URDF joints (by index) the lock list holds, with their positions.
///
/// # Errors
/// [`ModelError::InvalidLock`] when a position is not finite, a pattern matches no movable joint, or two
/// patterns hold one joint at different positions.
pub(crate) fn resolve(
    robot: &urdf_rs::Robot,
    locks: &[JointLock],
) -> Result<BTreeMap<usize, f64>, ModelError> {
    let mut out: BTreeMap<usize, (f64, &str)> = BTreeMap::new();
    for lock in locks {
        let invalid = |reason: String| ModelError::InvalidLock {
            pattern: lock.pattern.clone(),
            reason,
        };
        if !lock.position.is_finite() {
            return Err(invalid(format!(
                "position {} is not finite; expected rad or m",
                lock.position
            )));
        }
        let mut any = false;
        for (k, joint) in robot.joints.iter().enumerate() {
            if joint.joint_type == urdf_rs::JointType::Fixed
                || !glob_matches(&lock.pattern, &joint.name)
            {
                continue;
            }
            any = true;
            if let Some((q, other)) = out.insert(k, (lock.position, &lock.pattern)) {
                if q != lock.position {
                    return Err(invalid(format!(
                        "joint `{}` is also locked by `{other}` at {q}; expected one position per joint",
                        joint.name
                    )));
                }
            }
        }
        if !any {
            return Err(invalid(
                "matches no movable joint of the URDF (names and globs with `*`, `?`)".into(),
            ));
        }
    }
    Ok(out.into_iter().map(|(k, (q, _))| (k, q)).collect())
}

/// The motion of a URDF joint held at `q`: a rotation by `q` about its unit axis (revolute, continuous), a
/// translation by `q` along it (prismatic).
///
/// # Errors
/// [`ModelError::ZeroAxis`] for a zero axis.
pub(crate) fn joint_motion(joint: &urdf_rs::Joint, q: f64) -> Result<Isometry3<f64>, ModelError> {
    let axis = Vector3::from(joint.axis.xyz.0);
    if axis.norm() < 1e-12 {
        return Err(ModelError::ZeroAxis {
            joint: joint.name.clone(),
        });
    }
    let axis = Unit::new_normalize(axis);
    Ok(match joint.joint_type {
        urdf_rs::JointType::Prismatic => Isometry3::from_parts(
            Translation3::from(axis.into_inner() * q),
            UnitQuaternion::identity(),
        ),
        _ => Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(&axis, q),
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::glob_matches;

    #[test]
    fn globs_match_names_and_only_names() {
        for (p, n) in [
            ("l_elbow", "l_elbow"),
            ("*", ""),
            ("*finger*", "l_hand_finger_2"),
            ("l_?and_*", "l_hand_thumb"),
            ("*_joint", "left_wrist_roll_joint"),
            ("a*b*c", "abbbc"),
        ] {
            assert!(glob_matches(p, n), "{p} should match {n}");
        }
        for (p, n) in [
            ("l_elbow", "r_elbow"),
            ("l_elbow", "l_elbow2"),
            ("?", ""),
            ("*finger", "finger_1"),
            ("a*b*c", "abcb"),
        ] {
            assert!(!glob_matches(p, n), "{p} should not match {n}");
        }
    }
}
