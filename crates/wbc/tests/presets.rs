//! The walking presets: the bundled humanoid's preset is exactly the task lists its robot file stated
//! before presets existed (a TOML fixture, written by hand), another robot's preset carries its own frames
//! and posture, and overrides replace or add tasks by name.

use std::collections::BTreeMap;

use serde::Deserialize;
use stride_wbc::presets::{
    walking_ik, walking_tsid, with_overrides, without, WalkingFrames, WalkingPreset,
};
use stride_wbc::{IkConfig, Priority, ReferenceOffset, TaskConfig, TsidConfig, Weight};

#[derive(Deserialize)]
struct Wbc {
    ik: IkConfig,
    tsid: TsidConfig,
}

#[derive(Deserialize)]
struct Fixture {
    wbc: Wbc,
}

fn explicit_lists() -> Wbc {
    let text = include_str!("fixtures/stride_humanoid_tasks.toml");
    toml::from_str::<Fixture>(text).expect("fixture parses").wbc
}

#[test]
fn the_bundled_preset_is_the_explicit_task_lists() {
    let explicit = explicit_lists();
    let preset = WalkingPreset::bundled();
    assert_eq!(walking_ik(&preset), explicit.ik);
    assert_eq!(walking_tsid(&preset), explicit.tsid);
    assert_eq!(IkConfig::default_for_bundled_model(), explicit.ik);
    assert_eq!(TsidConfig::default_for_bundled_model(), explicit.tsid);
}

fn g1_preset() -> WalkingPreset {
    let frames = WalkingFrames::new("left_sole", "right_sole", "torso_link", "pelvis");
    let posture: BTreeMap<String, f64> = [("left_knee_joint".to_string(), 0.7)].into();
    WalkingPreset {
        posture_joint_weights: [("left_elbow_joint".to_string(), 3.0)].into(),
        upright_offset: ReferenceOffset::Initial,
        cop_x: [-0.05, 0.07],
        cop_y: [-0.02, 0.02],
        ..WalkingPreset::new(frames, posture)
    }
}

/// Every frame, joint and parameter of the preset input lands in the tasks that use it.
#[test]
fn another_robots_preset_uses_its_frames_posture_and_contact_region() {
    let p = g1_preset();
    for tasks in [walking_ik(&p).tasks, walking_tsid(&p).tasks] {
        for t in &tasks {
            match t {
                TaskConfig::Se3(s) if s.name == "left_foot" => assert_eq!(s.frame, "left_sole"),
                TaskConfig::Se3(s) => assert_eq!(s.frame, "right_sole"),
                TaskConfig::So3(s) => {
                    let frame = if s.name == "torso" {
                        "torso_link"
                    } else {
                        "pelvis"
                    };
                    assert_eq!(s.frame, frame);
                    assert_eq!(s.reference_offset, ReferenceOffset::Initial);
                }
                TaskConfig::Contact(c) => {
                    assert_eq!((c.foot_x, c.foot_y), ([-0.05, 0.07], [-0.02, 0.02]));
                    let frame = if c.name == "left_contact" {
                        "left_sole"
                    } else {
                        "right_sole"
                    };
                    assert_eq!(c.frame, frame);
                }
                TaskConfig::JointRegularization(r) => {
                    assert_eq!(r.posture, p.posture);
                    assert_eq!(r.joint_weights, p.posture_joint_weights);
                }
                _ => {}
            }
        }
    }
}

#[test]
fn overrides_replace_tasks_by_name_in_place_and_append_new_ones() {
    let mut ik = walking_ik(&g1_preset());
    let names = |tasks: &[TaskConfig]| {
        tasks
            .iter()
            .map(|t| t.name().to_owned())
            .collect::<Vec<_>>()
    };
    let before = names(&ik.tasks);
    let mut torso = ik.tasks[3].clone();
    if let TaskConfig::So3(t) = &mut torso {
        t.weight = Some(Weight::Scalar(50.0));
    }
    let mut head = torso.clone();
    if let TaskConfig::So3(t) = &mut head {
        t.name = "head".into();
        t.frame = "head_link".into();
        t.priority = Priority::Soft;
    }
    with_overrides(&mut ik.tasks, &[torso.clone(), head.clone()]);
    let mut expected = before.clone();
    expected.push("head".into());
    assert_eq!(names(&ik.tasks), expected);
    assert_eq!(ik.tasks[3], torso);
    assert_eq!(ik.tasks.last(), Some(&head));

    let names_to_drop = ["pelvis".to_string(), "nope".to_string()];
    let unknown = without(&mut ik.tasks, &names_to_drop);
    assert_eq!(unknown, vec!["nope"]);
    assert!(ik.tasks.iter().all(|t| t.name() != "pelvis"));
    assert_eq!(ik.tasks.len(), before.len());
}
