//! The element reader against urdf-rs itself (`urdf_rs::read_from_string`, the independent reference): the
//! same `Robot` (compared through its full `Debug` text, every number included) on every URDF at hand, and
//! the same verdict (accepted or rejected) on the cases each version rule covers, both sides of each.

use super::read_robot;
use crate::urdf::texture::strip_textures_without_filename;

/// `Ok(Debug text)` of the robot or `Err(())`, by this module and by urdf-rs.
fn both(text: &str) -> (Result<String, ()>, Result<String, ()>) {
    let text = strip_textures_without_filename(text);
    let ours = text
        .parse::<xml::Element>()
        .map_err(|_| ())
        .and_then(|root| read_robot(&root).map_err(|_| ()))
        .map(|r| format!("{r:?}"));
    let reference = urdf_rs::read_from_string(&text)
        .map(|r| format!("{r:?}"))
        .map_err(|_| ());
    (ours, reference)
}

fn assert_same(text: &str) {
    let (ours, reference) = both(text);
    assert_eq!(ours, reference, "on\n{text}");
}

fn assert_accepted(text: &str) {
    let (ours, _) = both(text);
    assert!(ours.is_ok(), "rejected:\n{text}");
    assert_same(text);
}

fn assert_rejected(text: &str) {
    let (ours, reference) = both(text);
    assert!(reference.is_err(), "urdf-rs accepts:\n{text}");
    assert!(ours.is_err(), "accepted:\n{text}");
}

fn robot(version: &str, body: &str) -> String {
    format!(r#"<robot name="r"{version}><link name="a"/><link name="b"/>{body}</robot>"#)
}

fn joint(version: &str, inner: &str) -> String {
    robot(
        version,
        &format!(
            r#"<joint name="j" type="revolute"><parent link="a"/><child link="b"/>{inner}</joint>"#
        ),
    )
}

#[test]
fn the_bundled_models_read_as_urdf_rs_reads_them() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    for name in ["stride_humanoid.urdf", "stride_humanoid_flex.urdf"] {
        let text = std::fs::read_to_string(root.join(name)).expect("bundled model");
        assert_accepted(&text);
    }
}

#[test]
fn every_official_icub_model_reads_as_urdf_rs_reads_it() {
    let Some(dir) =
        stride_testkit::icub_models_dir("every_official_icub_model_reads_as_urdf_rs_reads_it")
    else {
        return;
    };
    let mut read = 0;
    for entry in std::fs::read_dir(dir).expect("iCub models folder") {
        let urdf = entry.expect("entry").path().join("model.urdf");
        if let Ok(text) = std::fs::read_to_string(&urdf) {
            assert_accepted(&text);
            read += 1;
        }
    }
    assert!(read >= 10, "only {read} iCub models read");
}

#[test]
fn every_element_and_attribute_reads_as_urdf_rs_reads_it() {
    let link = r#"<link name="c">
        <inertial><origin xyz="0.1 0 -0.2" rpy="0.3 0 0"/><mass value=" 2.5 "/>
          <inertia ixx="1" ixy="0.1" ixz="0" iyy="2" iyz="0" izz="3"/></inertial>
        <visual name="v"><origin xyz="1 2 3"/><geometry><mesh filename="m.stl" scale="1 2 3"/></geometry>
          <material name="red"><color rgba="1 0 0 1"/></material></visual>
        <visual><geometry><cylinder radius="0.1" length="0.2"/></geometry></visual>
        <collision name="c1"><geometry><box size="0.1 junk 0.2 0.3"/></geometry></collision>
        <collision><origin rpy="0 0 1"/><geometry><sphere radius="0.05"/></geometry></collision>
        <collision><geometry><capsule radius="0.05" length="0.3"/></geometry></collision>
      </link>"#;
    let joints = r#"<joint name="j" type="revolute"><origin xyz="0 0 0.1" rpy="0 0.5 0"/>
        <parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
        <limit lower="-1" upper="1" effort="10" velocity="2"/><dynamics damping="0.5"/>
        <calibration rising="0.1"/><mimic joint="k" multiplier="2"/>
        <safety_controller k_velocity="3" soft_upper_limit="0.9"/></joint>
      <joint name="k" type="continuous"><parent link="b"/><child link="c"/></joint>
      <joint name="f" type="fixed"><parent link="a"/><child link="d"/><limit velocity="1"/></joint>
      <material name="blue"><color rgba="0 0 1 1"/></material>"#;
    for version in [
        "",
        r#" version="1.0""#,
        r#" version="1.1""#,
        r#" version="1.2""#,
    ] {
        assert_accepted(&robot(
            version,
            &format!("{link}<link name=\"d\"/>{joints}"),
        ));
    }
}

#[test]
fn quaternion_origins_follow_the_version() {
    let origin = r#"<origin xyz="0 0 1" quat_xyzw="0.1 0.2 0.3 0.9"/>"#;
    let gimbal = r#"<origin quat_xyzw="0 0.7071067811865476 0 0.7071067811865476"/>"#;
    for version in ["", r#" version="1.1""#, r#" version="1.2""#] {
        assert_accepted(&joint(version, origin));
        assert_accepted(&joint(version, gimbal));
        assert_accepted(&joint(version, r#"<origin quat_xyzw="0 0 0 0"/>"#));
    }
    // Both orientations, or a malformed quaternion: rejected from 1.1, ignored before.
    let both_given = r#"<origin rpy="0 0 1" quat_xyzw="0 0 0 1"/>"#;
    assert_accepted(&joint("", both_given));
    assert_rejected(&joint(r#" version="1.1""#, both_given));
    assert_rejected(&joint(
        r#" version="1.1""#,
        r#"<origin quat_xyzw="0 0 1"/>"#,
    ));
}

#[test]
fn limits_follow_the_version() {
    let v12 = r#" version="1.2""#;
    // 1.2: missing bounds are unbounded, deceleration defaults to acceleration.
    assert_accepted(&joint(v12, r#"<limit lower="-1" acceleration="5"/>"#));
    assert_accepted(&joint(v12, r#"<limit/>"#));
    assert_accepted(&joint(
        v12,
        r#"<limit lower="-1" upper="1" effort="2" velocity="3" jerk="9" deceleration="4"/>"#,
    ));
    assert_rejected(&joint(v12, r#"<limit lower="1" upper="-1"/>"#));
    assert_rejected(&joint(v12, r#"<limit velocity="-1"/>"#));
    assert_rejected(&joint(v12, r#"<limit lower="nan"/>"#));
    // Before 1.2: velocity required, the 1.2 attributes ignored, no checks.
    assert_accepted(&joint(
        "",
        r#"<limit velocity="1" lower="1" upper="-1" acceleration="-3"/>"#,
    ));
    assert_rejected(&joint("", r#"<limit lower="-1" upper="1"/>"#));
}

#[test]
fn shapes_are_checked_from_version_1_2() {
    let zero_radius =
        r#"<link name="c"><collision><geometry><sphere radius="0"/></geometry></collision></link>"#;
    assert_accepted(&robot("", zero_radius));
    assert_rejected(&robot(r#" version="1.2""#, zero_radius));
}

#[test]
fn malformed_elements_are_rejected() {
    for body in [
        r#"<link/>"#,
        r#"<joint name="j" type="hinge"><parent link="a"/><child link="b"/></joint>"#,
        r#"<joint name="j" type="fixed"><parent link="a"/></joint>"#,
        r#"<joint name="j" type="fixed"><parent link="a"/><child link="b"/><axis xyz="0 1"/></joint>"#,
        r#"<link name="c"><inertial><mass value="1"/></inertial></link>"#,
        r#"<link name="c"><inertial><mass value="x"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>"#,
        r#"<link name="c"><visual><geometry><cone radius="1"/></geometry></visual></link>"#,
        r#"<link name="c"><visual><geometry/></visual></link>"#,
        r#"<material/>"#,
    ] {
        assert_rejected(&robot("", body));
    }
}
