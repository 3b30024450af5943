//! `stride model feet`: sole frames and rectangles from collision geometry, checked against the
//! dimensions the test URDFs are built from; STL and OBJ meshes against the box they describe.
mod common;

use common::Scratch;
use nalgebra::{Point3, Vector3};
use stride_runner::feet::mesh::{box_triangles, read_mesh};
use stride_runner::feet::patch::{lowest_patch, Shapes};
use stride_runner::feet::{propose_feet, FeetError, FootProposal};

const INERTIAL: &str = r#"<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>"#;

fn leg(side: &str, y: f64, foot: &str) -> String {
    format!(
        r#"<joint name="{side}_hip" type="revolute"><parent link="pelvis"/><child link="{side}_foot"/>
  <origin xyz="0 {y} -0.5"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="100" velocity="10"/></joint>
<link name="{side}_foot">{INERTIAL}{foot}</link>"#
    )
}

fn urdf(left_foot: &str, right_foot: &str) -> String {
    format!(
        r#"<robot name="t"><link name="pelvis">{INERTIAL}</link>{}{}</robot>"#,
        leg("l", 0.1, left_foot),
        leg("r", -0.1, right_foot)
    )
}

/// A binary STL of `triangles`.
fn binary_stl(triangles: &[[Point3<f64>; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        out.extend([0f32; 3].iter().flat_map(|v| v.to_le_bytes()));
        for p in t {
            for c in [p.x, p.y, p.z] {
                out.extend((c as f32).to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

fn shifted(tris: Vec<[Point3<f64>; 3]>, d: Vector3<f64>) -> Vec<[Point3<f64>; 3]> {
    tris.into_iter().map(|t| t.map(|p| p + d)).collect()
}

#[test]
fn box_foot_and_corner_sphere_foot_give_their_sole_rectangles() {
    let s = Scratch::new("feet-box");
    let box_foot = r#"<collision><origin xyz="0.03 0 -0.04"/><geometry><box size="0.2 0.08 0.02"/></geometry></collision>
<visual><origin xyz="0.03 0 -0.04"/><geometry><box size="0.2 0.08 0.02"/></geometry></visual>"#;
    let mut spheres = String::new();
    for (x, y) in [(-0.05, 0.03), (-0.05, -0.03), (0.12, 0.03), (0.12, -0.03)] {
        spheres.push_str(&format!(
            r#"<collision><origin xyz="{x} {y} -0.045"/><geometry><sphere radius="0.005"/></geometry></collision>"#
        ));
    }
    // The visual mesh is longer than the sphere rectangle: a disagreement to report.
    let visual = shifted(
        box_triangles([0.25, 0.06, 0.02]),
        Vector3::new(0.035, 0.0, -0.04),
    );
    std::fs::create_dir_all(s.path("meshes")).unwrap();
    std::fs::write(s.path("meshes/foot.stl"), binary_stl(&visual)).unwrap();
    spheres.push_str(r#"<visual><geometry><mesh filename="meshes/foot.stl"/></geometry></visual>"#);
    let path = s.write("robot.urdf", &urdf(box_foot, &spheres));
    let [l, r] = propose_feet(&path).unwrap();

    assert_eq!(l.link, "l_foot");
    assert!((l.patch.length - 0.2).abs() < 1e-9 && (l.patch.width - 0.08).abs() < 1e-9);
    let c = l.patch.centre;
    assert!((c - Point3::new(0.03, 0.1, -0.55)).norm() < 1e-9, "{c}");
    let t = l.sole_in_link.translation.vector;
    assert!((t - Vector3::new(0.03, 0.0, -0.05)).norm() < 1e-9, "{t}");
    assert!(l.sole_in_link.rotation.angle() < 1e-12);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);

    assert_eq!(r.link, "r_foot");
    assert!((r.patch.length - 0.17).abs() < 1e-9 && (r.patch.width - 0.06).abs() < 1e-9);
    let t = r.sole_in_link.translation.vector;
    assert!((t - Vector3::new(0.035, 0.0, -0.05)).norm() < 1e-9, "{t}");
    assert!(
        r.warnings.iter().any(|w| w.contains("0.250 m × 0.060 m")),
        "{:?}",
        r.warnings
    );
    // Point contacts: the four corner spheres form a 2 × 2 grid; the box sole has none.
    assert_eq!(r.point_contacts.len(), 4);
    assert_eq!(r.point_contact_grid(), Some([2, 2]));
    assert!(l.point_contacts.is_empty());
    assert_eq!(l.point_contact_grid(), None);
}

#[test]
fn a_foot_without_a_flat_bottom_is_not_proposed() {
    let s = Scratch::new("feet-round");
    let ball = r#"<collision><origin xyz="0 0 -0.05"/><geometry><sphere radius="0.03"/></geometry></collision>"#;
    let flat = r#"<collision><origin xyz="0 0 -0.07"/><geometry><box size="0.2 0.08 0.02"/></geometry></collision>"#;
    let path = s.write("robot.urdf", &urdf(ball, flat));
    match propose_feet(&path) {
        Err(FeetError::NoFoot { side, .. }) => assert_eq!(side, "y > 0"),
        other => panic!("expected no left foot, got {other:?}"),
    }
}

#[test]
fn stl_and_obj_meshes_read_the_box_they_describe() {
    let s = Scratch::new("feet-mesh");
    let tris = box_triangles([0.3, 0.1, 0.05]);
    let stl = s.write("b.stl", "");
    std::fs::write(&stl, binary_stl(&tris)).unwrap();
    let mut ascii = String::from("solid b\n");
    let mut obj = String::new();
    for (i, t) in tris.iter().enumerate() {
        ascii.push_str("facet normal 0 0 0\nouter loop\n");
        for p in t {
            ascii.push_str(&format!("vertex {} {} {}\n", p.x, p.y, p.z));
            obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        ascii.push_str("endloop\nendfacet\n");
        obj.push_str(&format!(
            "f {} {}/1 {}/1/1\n",
            3 * i + 1,
            3 * i + 2,
            3 * i + 3
        ));
    }
    let ascii_path = s.write("a.stl", &ascii);
    let obj_path = s.write("b.obj", &obj);
    for path in [stl, ascii_path, obj_path] {
        let read = read_mesh(&path, [2.0, 1.0, 1.0]).unwrap();
        let patch = lowest_patch(&Shapes {
            triangles: read,
            spheres: Vec::new(),
        })
        .unwrap();
        // Scaled by 2 along x.
        assert!(
            (patch.length - 0.6).abs() < 1e-6,
            "{}: {patch:?}",
            path.display()
        );
        assert!((patch.width - 0.1).abs() < 1e-6);
        assert!((patch.centre.z + 0.025).abs() < 1e-6);
    }
    let dae = s.write("m.dae", "<COLLADA/>");
    let e = read_mesh(&dae, [1.0; 3]).unwrap_err().to_string();
    assert!(e.contains("unsupported format"), "{e}");
}

/// `link_H_frame` of a frame rigidly attached to `link` (a body of the model).
fn placement_in(model: &stride_model::Model, frame: &str, link: &str) -> nalgebra::Isometry3<f64> {
    let f = &model.frames()[model.frame_id(frame).unwrap().index()];
    let body = &model.frames()[model.frame_id(link).unwrap().index()];
    assert_eq!(f.link, body.link, "{frame} and {link} share a body");
    body.placement.inverse() * f.placement
}

/// Each foot proposed for the URDF at `path`, with the URDF's own sole frame it should match and
/// `d = urdf_sole⁻¹ · proposed_sole`; `pairs` are (sole frame, foot link), left then right.
fn against_urdf_soles(
    path: &std::path::Path,
    pairs: [(&'static str, &str); 2],
) -> Vec<(FootProposal, &'static str, nalgebra::Isometry3<f64>)> {
    let model = stride_model::Model::from_urdf_file(path).unwrap();
    let feet = propose_feet(path).unwrap();
    feet.into_iter()
        .zip(pairs)
        .map(|(f, (sole, link))| {
            assert_eq!(f.link, link);
            let d = placement_in(&model, sole, link).inverse() * f.sole_in_link;
            (f, sole, d)
        })
        .collect()
}

#[test]
fn the_bundled_humanoid_feet_are_its_urdf_sole_frames() {
    let path = common::root().join("models/stride_humanoid.urdf");
    for (f, sole, d) in against_urdf_soles(&path, [("l_sole", "l_foot"), ("r_sole", "r_foot")]) {
        assert!(d.translation.vector.norm() < 1e-9, "{sole}: {d}");
        assert!(d.rotation.angle() < 1e-9);
        // 0.20 m × 0.09 m soles (the URDF's header).
        assert!((f.patch.length - 0.2).abs() < 1e-9 && (f.patch.width - 0.09).abs() < 1e-9);
        assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    }
}

#[test]
fn icub_feet_are_near_its_urdf_sole_frames() {
    let Some(path) = stride_testkit::icub_model_urdf(
        "icub_feet_are_near_its_urdf_sole_frames",
        "iCubGazeboV2_7",
    ) else {
        return;
    };
    for (_, sole, d) in against_urdf_soles(&path, [("l_sole", "l_foot"), ("r_sole", "r_foot")]) {
        // Same axes as iCub's sole frame (z up, x forward). The collision box is not centred on it: its
        // bottom is 11 mm below `l_sole` and its centre 26 mm ahead (measured 2026-12-02: d = [0.026,
        // ±0.005, −0.011] m), so the proposal is near, not on, the URDF's frame.
        assert!(d.rotation.angle() < 1e-9, "{sole}: {d}");
        assert!(
            d.translation.z < 0.0,
            "{sole}: the box reaches below the sole frame: {d}"
        );
        assert!(d.translation.vector.norm() < 0.03, "{sole}: {d}");
    }
}

/// `$STRIDE_EXAMPLE_ROBOT_DATA_DIR/<rel>`, or `None` (said loudly on stderr) when the variable is unset
/// (`tools/reference/example-robot-data-dir.sh` installs the package and prints the folder).
fn example_robot(test: &str, rel: &str) -> Option<std::path::PathBuf> {
    let dir = std::env::var_os("STRIDE_EXAMPLE_ROBOT_DATA_DIR")
        .filter(|_| common::example_robot_data(test))?;
    let path = std::path::PathBuf::from(dir).join(rel);
    assert!(path.is_file(), "{} is missing", path.display());
    Some(path)
}

#[test]
fn talos_feet_lie_on_its_urdf_sole_links() {
    let test = "talos_feet_lie_on_its_urdf_sole_links";
    let Some(path) = example_robot(test, "talos_data/robots/talos_reduced.urdf") else {
        return;
    };
    let pairs = [
        ("left_sole_link", "leg_left_6_link"),
        ("right_sole_link", "leg_right_6_link"),
    ];
    // STL meshes, the right one mirrored (scale 1 −1 1).
    for (_, sole, d) in against_urdf_soles(&path, pairs) {
        // On the plane of TALOS's own sole link (0.107 m below the ankle), same axes; the flat patch of
        // the collision mesh is centred 5.6 mm behind the ankle axis, where TALOS puts its sole link.
        assert!(d.translation.z.abs() < 1e-4, "{sole}: {d}");
        assert!(d.rotation.angle() < 1e-9, "{sole}: {d}");
        assert!(d.translation.vector.xy().norm() < 0.01, "{sole}: {d}");
    }
}

#[test]
fn g1_feet_are_found_under_its_ankle_roll_links() {
    let test = "g1_feet_are_found_under_its_ankle_roll_links";
    let Some(path) = example_robot(test, "g1_description/urdf/g1_29dof_rev_1_0.urdf") else {
        return;
    };
    let [l, r] = propose_feet(&path).unwrap();
    // Four corner spheres (r = 5 mm) at x −0.05 / 0.12, y ±0.025 / ±0.03, z −0.03 in the ankle roll link:
    // the sole is 0.17 m × 0.06 m, 35 mm below the link, centred 35 mm ahead of it.
    for (f, link) in [(&l, "left_ankle_roll_link"), (&r, "right_ankle_roll_link")] {
        assert_eq!(f.link, link);
        assert!((f.patch.length - 0.17).abs() < 1e-9 && (f.patch.width - 0.06).abs() < 1e-9);
        let t = f.sole_in_link.translation.vector;
        assert!((t - Vector3::new(0.035, 0.0, -0.035)).norm() < 1e-9, "{t}");
        // The visual mesh is larger than the contact spheres' rectangle.
        assert!(
            f.warnings.iter().any(|w| w.contains("visual sole")),
            "{:?}",
            f.warnings
        );
    }
}
