//! URDF loading: structure, merged fixed joints, sensors, mimic joints, errors and warnings.

mod common;

use common::{test_model, TEST_URDF};
use stride_model::{FrameKind, JointKind, Model, ModelError};

#[test]
fn test_model_structure() {
    let m = test_model();
    assert_eq!(m.name(), "test_tree");
    assert_eq!(m.root_link(), "torso");
    assert_eq!(m.dof(), 9);
    assert_eq!(m.nv(), 15);
    let names: Vec<&str> = m.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "l_hip",
            "l_knee",
            "l_ankle",
            "r_hip",
            "r_knee",
            "arm_slide",
            "wrist_roll",
            "finger_a_joint",
            "finger_b_joint"
        ]
    );
    assert_eq!(m.joints()[5].kind, JointKind::Prismatic);
    assert_eq!(m.joints()[6].kind, JointKind::Continuous);
    assert!(m.joints()[6].lower.is_infinite() && m.joints()[6].upper.is_infinite());
    // Axis normalised.
    assert!((m.joints()[1].axis.norm() - 1.0).abs() < 1e-15);
    assert!((m.joints()[3].axis - nalgebra::Vector3::new(0.0, 0.6, 0.8)).norm() < 1e-15);
    // Mimic flagged.
    let mimic = m.joints()[8].mimic.as_ref().expect("mimic");
    assert_eq!(mimic.joint, "finger_a_joint");
    assert!(m.joints()[7].mimic.is_none());
    // Total mass = sum of link masses.
    let expected = 5.0 + 1.0 + 2.0 + 1.0 + 0.5 + 0.7 + 2.0 + 0.7 + 1.5 + 0.3 + 0.05 + 0.05;
    assert!((m.total_mass() - expected).abs() < 1e-12);
    // Bodies and frames.
    assert_eq!(m.bodies().len(), 10);
    for name in [
        "torso",
        "head",
        "l_thigh",
        "l_shin_upper",
        "l_shin_lower",
        "l_foot",
        "l_sole",
        "r_sole",
        "tool",
        "finger_b",
    ] {
        assert!(m.frame_id(name).is_some(), "frame {name}");
    }
    let head = m.frame_id("head").unwrap();
    assert_eq!(m.frames()[head.index()].kind, FrameKind::MergedLink);
    assert_eq!(m.frames()[head.index()].link, 0);
    let lower = m.frame_id("l_shin_lower").unwrap();
    assert_eq!(m.frames()[lower.index()].link, 2); // merged into l_shin_upper (body 2)
    assert_eq!(m.frame_name(lower), "l_shin_lower");
    // FT sensor from the gazebo tag, frame = child link frame.
    assert_eq!(m.ft_sensors().len(), 1);
    let ft = &m.ft_sensors()[0];
    assert_eq!(ft.name, "l_ft");
    assert_eq!(ft.joint, "l_ft_sensor");
    assert_eq!(ft.parent_link, "l_shin_upper");
    assert_eq!(ft.child_link, "l_shin_lower");
    assert_eq!(
        m.frames()[ft.frame.index()].placement,
        m.frames()[lower.index()].placement
    );
    // Merged inertia of body 2 (l_shin_upper + l_shin_lower) = 1.5 kg.
    assert!((m.bodies()[2].mass - 1.5).abs() < 1e-15);
}

#[test]
fn revolute_without_limit_warns_and_is_unbounded() {
    let urdf = r#"<robot name="r"><link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>"#;
    let m = Model::from_urdf_str(urdf).unwrap();
    let j = &m.joints()[0];
    assert!(j.lower == f64::NEG_INFINITY && j.upper == f64::INFINITY);
    assert!(j.velocity_limit == f64::INFINITY && j.effort_limit == f64::INFINITY);
    assert!(
        m.warnings()
            .iter()
            .any(|w| w.contains("`j`") && w.contains("<limit>")),
        "{:?}",
        m.warnings()
    );
}

fn two_links(joint_type: &str, extra_link_b: &str) -> String {
    format!(
        r#"<robot name="r"><link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="b">{extra_link_b}</link>
      <joint name="j" type="{joint_type}"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#
    )
}

#[test]
fn errors_name_the_culprit() {
    let e = Model::from_urdf_str(&two_links("floating", "")).unwrap_err();
    assert!(
        matches!(&e, ModelError::UnsupportedJoint { joint, .. } if joint == "j"),
        "{e}"
    );
    let e = Model::from_urdf_str(&two_links("planar", "")).unwrap_err();
    assert!(
        matches!(&e, ModelError::UnsupportedJoint { joint, .. } if joint == "j"),
        "{e}"
    );
    let e = Model::from_urdf_str(&two_links(
        "revolute",
        r#"<inertial><mass value="-1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ))
    .unwrap_err();
    assert!(
        matches!(&e, ModelError::NegativeMass { link, .. } if link == "b"),
        "{e}"
    );
    let e = Model::from_urdf_str(&two_links(
        "revolute",
        r#"<inertial><mass value="1"/><inertia ixx="1" ixy="2" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ))
    .unwrap_err();
    assert!(
        matches!(&e, ModelError::NegativeInertia { link, .. } if link == "b"),
        "{e}"
    );
    let e = Model::from_urdf_str(&two_links(
        "revolute",
        r#"<inertial><mass value="nan"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>"#,
    ))
    .unwrap_err();
    assert!(
        matches!(&e, ModelError::NonFinite { element, .. } if element.contains("`b`")),
        "{e}"
    );

    // Missing link.
    let urdf = r#"<robot name="r"><link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="zz"/></joint></robot>"#;
    let e = Model::from_urdf_str(urdf).unwrap_err();
    assert!(
        matches!(&e, ModelError::MissingLink { link, .. } if link == "zz"),
        "{e}"
    );
    // Duplicate link.
    let urdf = r#"<robot name="r"><link name="a"/><link name="a"/></robot>"#;
    let e = Model::from_urdf_str(urdf).unwrap_err();
    assert!(
        matches!(&e, ModelError::DuplicateLink { link } if link == "a"),
        "{e}"
    );
    // Loop with no root.
    let urdf = r#"<robot name="r"><link name="a"/><link name="b"/>
      <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint></robot>"#;
    let e = Model::from_urdf_str(urdf).unwrap_err();
    assert!(matches!(e, ModelError::NoRoot), "{e}");
    // Loop (a link with two parents).
    let urdf = r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
      <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="j2" type="fixed"><parent link="a"/><child link="c"/></joint>
      <joint name="j3" type="fixed"><parent link="b"/><child link="c"/></joint></robot>"#;
    let e = Model::from_urdf_str(urdf).unwrap_err();
    assert!(
        matches!(&e, ModelError::MultipleParents { link, .. } if link == "c"),
        "{e}"
    );
    // A detached cycle next to a valid root.
    let urdf = r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
      <joint name="j1" type="fixed"><parent link="b"/><child link="c"/></joint>
      <joint name="j2" type="fixed"><parent link="c"/><child link="b"/></joint></robot>"#;
    let e = Model::from_urdf_str(urdf).unwrap_err();
    assert!(matches!(&e, ModelError::Loop { .. }), "{e}");
    // Missing file.
    let e = Model::from_urdf_file("/nonexistent/robot.urdf").unwrap_err();
    assert!(matches!(e, ModelError::Io { .. }), "{e}");
}

#[test]
fn inconsistent_inertias_and_point_masses_load_with_warnings() {
    let m = Model::from_urdf_str(&two_links(
        "revolute",
        r#"<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="3"/></inertial>"#,
    ))
    .unwrap();
    assert!(m
        .warnings()
        .iter()
        .any(|w| w.contains("`b`") && w.contains("triangle")));
    let m = Model::from_urdf_str(&two_links(
        "revolute",
        r#"<inertial><mass value="1"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>"#,
    ))
    .unwrap();
    assert!(m
        .warnings()
        .iter()
        .any(|w| w.contains("`b`") && w.contains("point mass")));
    let m = Model::from_urdf_str(&two_links("revolute", "")).unwrap();
    assert!(m
        .warnings()
        .iter()
        .any(|w| w.contains("`b`") && w.contains("massless")));
}

#[test]
fn the_loaders_triangle_warning_is_full_consistency_on_both_sides_of_the_boundary() {
    // Principal moments (1, 1, 2 + δ): the triangle inequality J₃ ≤ J₁ + J₂ (Traversaro 2017, eq. 6.18)
    // fails for δ > 0 beyond the relative tolerance, holds for δ ≤ 0.
    for (delta, violated) in [(1e-6, true), (0.0, false), (-1e-6, false)] {
        let izz = 2.0 + delta;
        let m = Model::from_urdf_str(&two_links(
            "revolute",
            &format!(
                r#"<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="{izz}"/></inertial>"#
            ),
        ))
        .unwrap();
        let warned = m
            .warnings()
            .iter()
            .any(|w| w.contains("`b`") && w.contains("triangle"));
        let body_b = m
            .inertia_violations(true)
            .into_iter()
            .any(|v| v.name == "b");
        assert_eq!(warned, violated, "δ = {delta}: loader warning");
        assert_eq!(body_b, violated, "δ = {delta}: check_full_consistency");
    }
}

#[test]
fn texture_without_filename_is_accepted() {
    // The test model has `<texture/>` in a material.
    assert!(TEST_URDF.contains("<texture/>"));
    let _ = test_model();
}

#[test]
fn top_level_sensor_declares_a_frame() {
    let urdf = r#"<robot name="r">
      <link name="a"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
      <joint name="ft_joint" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 -0.1"/></joint>
      <sensor name="ft" type="force_torque"><parent joint="ft_joint"/>
        <force_torque><frame>sensor</frame><measure_direction>parent_to_child</measure_direction></force_torque>
        <origin xyz="0 0 0.01" rpy="0 0 0"/></sensor>
    </robot>"#;
    let m = Model::from_urdf_str(urdf).unwrap();
    assert_eq!(m.ft_sensors().len(), 1);
    let s = &m.ft_sensors()[0];
    assert_eq!(s.measure_direction, "parent_to_child");
    let f = &m.frames()[s.frame.index()];
    assert_eq!(f.kind, FrameKind::Sensor);
    assert!(
        (f.placement.translation.vector - nalgebra::Vector3::new(0.0, 0.0, -0.09)).norm() < 1e-15
    );
}

#[test]
fn massless_leaf_gives_an_error_not_nan() {
    use nalgebra::DVector;
    use std::sync::Arc;
    use stride_model::{KinDyn, RobotState};
    let model = Arc::new(Model::from_urdf_str(&two_links("revolute", "")).unwrap());
    assert!(model
        .warnings()
        .iter()
        .any(|w| w.contains("`b`") && w.contains("forward dynamics will fail")));
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&RobotState::zero(&model)).unwrap();
    let mut out = DVector::zeros(model.nv());
    let e = kd
        .forward_dynamics(&DVector::zeros(1), &[], &mut out)
        .unwrap_err();
    assert!(
        matches!(&e, ModelError::SingularInertia { what } if what.contains("`j`")),
        "{e}"
    );
    // Wrong sizes and non-finite inputs are errors.
    let e = kd
        .forward_dynamics(&DVector::zeros(3), &[], &mut out)
        .unwrap_err();
    assert!(matches!(e, ModelError::DimensionMismatch { .. }), "{e}");
    let mut state = RobotState::zero(&model);
    state.joint_positions[0] = f64::NAN;
    assert!(matches!(
        kd.set_state(&state).unwrap_err(),
        ModelError::NonFiniteInput { .. }
    ));
}

/// An added frame knows what it is attached to: [`Model::urdf_frame_name`] follows a chain of added frames
/// to the URDF link (what a plant reading the URDF needs, e.g. MuJoCo keeping a sole's collision geometry),
/// at the placement composed along the chain; a URDF frame is its own.
#[test]
fn added_frames_name_the_urdf_link_they_stand_for() {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    let mut m = Model::from_urdf_str(TEST_URDF).unwrap();
    let down = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, -0.01),
        UnitQuaternion::identity(),
    );
    let contact = m.add_frame("l_contact", "l_sole", down).unwrap();
    let toe = m.add_frame("l_toe", "l_contact", down).unwrap();
    let sole = m.frame_id("l_sole").unwrap();
    assert_eq!(m.urdf_frame_name(contact), "l_sole");
    assert_eq!(m.urdf_frame_name(toe), "l_sole");
    assert_eq!(m.urdf_frame_name(sole), "l_sole");
    let [f_sole, f_toe] = [sole, toe].map(|f| m.frames()[f.index()].clone());
    assert_eq!(m.frames()[contact.index()].attached_to, Some(sole.index()));
    assert_eq!(f_sole.attached_to, None);
    assert_eq!(f_toe.link, f_sole.link);
    let dz = (f_sole.placement.inverse() * f_toe.placement)
        .translation
        .vector;
    assert!((dz - nalgebra::Vector3::new(0.0, 0.0, -0.02)).norm() < 1e-12);
}
