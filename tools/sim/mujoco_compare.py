#!/usr/bin/env python3
"""Cross-check stride-sim against MuJoCo: drop the bundled humanoid, joints held by PD servos in a knee-bent
posture, from a small height onto flat ground, and compare base trajectories, posture sag and contact forces.

Usage (from the repository root):
    pip install mujoco==3.17.0
    python3 tools/sim/mujoco_compare.py [--drop 0.02] [--duration 2.0] [--bend 0.2] [--json OUT.json]

The stride-sim trajectory comes from `cargo run --release -p stride-sim --example dump_trajectory`. The MuJoCo
model is built from the same URDF: MuJoCo's URDF import gives a fixed-base MJCF, to which this script adds a free
joint on the root link, a ground plane, position servos with the same gains and effort limits
(`kp`, `kv`, `forcerange`), and the same friction coefficient. Only the feet have collision geometry in the
URDF (their sole boxes). MuJoCo's contact is its own soft-constraint model (solref/solimp), so the static
penetration differs from stride-sim's spring law; everything else (inertias, gravity, servos) is identical.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import mujoco

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
URDF = os.path.join(ROOT, "models", "stride_humanoid.urdf")


def stride_trajectory(drop, duration, bend):
    cmd = ["cargo", "run", "--release", "-q", "-p", "stride-sim", "--example", "dump_trajectory", "--",
           str(drop), str(duration), str(bend)]
    out = subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def build_mujoco(stride, timestep):
    with open(URDF) as f:
        urdf = f.read()
    # MuJoCo compiler options inside the URDF: keep fixed-joint children as bodies (for the sole frames).
    urdf = urdf.replace('<robot name="stride_humanoid">',
                        '<robot name="stride_humanoid"><mujoco><compiler discardvisual="true" '
                        'fusestatic="false" balanceinertia="false" angle="radian"/></mujoco>', 1)
    model = mujoco.MjModel.from_xml_string(urdf)
    path = "/tmp/stride_humanoid_mjcf.xml"
    mujoco.mj_saveLastXML(path, model)
    tree = ET.parse(path)
    root = tree.getroot()
    option = root.find("option")
    if option is None:
        option = ET.SubElement(root, "option")
    option.set("timestep", str(timestep))
    option.set("integrator", "implicitfast")
    option.set("gravity", "0 0 -9.81")
    world = root.find("worldbody")
    base = world.find("body")
    ET.SubElement(base, "freejoint", {"name": "root"})
    # freejoint must be the first child of the body.
    fj = base.find("freejoint")
    base.remove(fj)
    base.insert(0, fj)
    p0 = stride["initial_base_position"]
    base.set("pos", f"{p0[0]} {p0[1]} {p0[2]}")
    world.insert(0, ET.Element("geom", {"name": "floor", "type": "plane", "size": "5 5 0.1",
                                        "friction": f"{stride['friction']} 0.005 0.0001"}))
    # Sole geoms get the same friction (MuJoCo takes the max of the two geoms).
    for geom in root.iter("geom"):
        if geom.get("name") != "floor":
            geom.set("friction", f"{stride['friction']} 0.005 0.0001")
    actuator = ET.SubElement(root, "actuator")
    joints = [j for j in root.iter("joint")]
    for j in joints:
        name = j.get("name")
        ET.SubElement(actuator, "position", {"name": name, "joint": name, "kp": str(stride["kp"]),
                                             "kv": str(stride["kd"])})
    tree.write(path)
    model = mujoco.MjModel.from_xml_path(path)
    # Effort limits from the URDF (MuJoCo keeps them as joint actuatorfrcrange).
    effort = {}
    for j in ET.parse(URDF).getroot().iter("joint"):
        lim = j.find("limit")
        if lim is not None and lim.get("effort"):
            effort[j.get("name")] = float(lim.get("effort"))
    for a in range(model.nu):
        jname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, model.actuator_trnid[a][0])
        if jname in effort:
            model.actuator_forcelimited[a] = 1
            model.actuator_forcerange[a] = [-effort[jname], effort[jname]]
    return model


def foot_of_body(model, body):
    # Walk up to the *_foot (or sole) body.
    while body > 0:
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body) or ""
        if name.startswith("l_"):
            return "left"
        if name.startswith("r_"):
            return "right"
        body = model.body_parentid[body]
    return None


def run_mujoco(model, stride, duration):
    data = mujoco.MjData(model)
    q0 = stride["initial_joint_positions"]
    for name, value in q0.items():
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        data.qpos[model.jnt_qposadr[jid]] = value
    for a in range(model.nu):
        jname = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, model.actuator_trnid[a][0])
        data.ctrl[a] = q0.get(jname, 0.0)
    mujoco.mj_forward(model, data)
    base_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "root_link")
    joint_names = list(q0.keys())
    every = max(1, round(0.005 / model.opt.timestep))
    steps = round(duration / model.opt.timestep)
    samples = []
    for k in range(steps + 1):
        if k > 0:
            mujoco.mj_step(model, data)
        if k % every:
            continue
        forces = {"left": np.zeros(3), "right": np.zeros(3)}
        moments = {"left": np.zeros(3), "right": np.zeros(3)}
        c6 = np.zeros(6)
        for i in range(data.ncon):
            con = data.contact[i]
            mujoco.mj_contactForce(model, data, i, c6)
            frame = con.frame.reshape(3, 3)  # rows: normal, tangent1, tangent2 (world)
            f_world = frame.T @ c6[:3]
            b1, b2 = model.geom_bodyid[con.geom1], model.geom_bodyid[con.geom2]
            # Force on geom2 from geom1 is +f (MuJoCo convention: force geom1 exerts on geom2 is -f?).
            foot = foot_of_body(model, b2) or foot_of_body(model, b1)
            sign = 1.0 if foot_of_body(model, b2) else -1.0
            f = sign * f_world
            forces[foot] += f
            moments[foot] += np.cross(con.pos, f)
        joints = {}
        for name in joint_names:
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            joints[name] = float(data.qpos[model.jnt_qposadr[jid]])
        feet = []
        for name in ("left", "right"):
            f, m = forces[name], moments[name]
            cop = [-m[1] / f[2], m[0] / f[2], 0.0] if f[2] > 1e-6 else [math.nan] * 3
            feet.append({"name": name, "normal_force": float(max(f[2], 0.0)), "force": f.tolist(), "cop": cop})
        samples.append({
            "time": float(data.time),
            "base_position": data.xpos[base_id].tolist(),
            "com_position": data.subtree_com[base_id].tolist(),
            "joint_positions": joints,
            "feet": feet,
        })
    return samples


def compare(stride, mj):
    n = min(len(stride), len(mj))
    s, m = stride[:n], mj[:n]
    t = np.array([x["time"] for x in s])
    bs = np.array([x["base_position"] for x in s])
    bm = np.array([x["base_position"] for x in m])
    fs = np.array([[f["normal_force"] for f in x["feet"]] for x in s])
    fm = np.array([[f["normal_force"] for f in x["feet"]] for x in m])
    settled = t >= t[-1] - 0.5
    leg = ["l_hip_pitch", "l_knee", "l_ankle_pitch"]
    result = {
        "samples": n,
        "base_height_rms_difference_m": float(np.sqrt(np.mean((bs[:, 2] - bm[:, 2]) ** 2))),
        "base_height_max_difference_m": float(np.max(np.abs(bs[:, 2] - bm[:, 2]))),
        "base_xy_max_difference_m": float(np.max(np.linalg.norm(bs[:, :2] - bm[:, :2], axis=1))),
        "final_base_height_stride_m": float(bs[-1, 2]),
        "final_base_height_mujoco_m": float(bm[-1, 2]),
        "settled_total_normal_force_stride_N": float(np.mean(fs[settled].sum(axis=1))),
        "settled_total_normal_force_mujoco_N": float(np.mean(fm[settled].sum(axis=1))),
        "settled_left_share_stride": float(np.mean(fs[settled, 0] / fs[settled].sum(axis=1))),
        "settled_left_share_mujoco": float(np.mean(fm[settled, 0] / fm[settled].sum(axis=1))),
        "impact_peak_total_force_stride_N": float(np.max(fs.sum(axis=1))),
        "impact_peak_total_force_mujoco_N": float(np.max(fm.sum(axis=1))),
        "first_contact_time_stride_s": float(t[np.argmax(fs.sum(axis=1) > 1.0)]),
        "first_contact_time_mujoco_s": float(t[np.argmax(fm.sum(axis=1) > 1.0)]),
        "final_joint_sag_stride_rad": {j: s[-1]["joint_positions"][j] - s[0]["joint_positions"][j] for j in leg},
        "final_joint_sag_mujoco_rad": {j: m[-1]["joint_positions"][j] - m[0]["joint_positions"][j] for j in leg},
        "settled_cop_x_stride_m": [float(np.mean([x["feet"][i]["cop"][0] for x in np.array(s)[settled]])) for i in (0, 1)],
        "settled_cop_x_mujoco_m": [float(np.mean([x["feet"][i]["cop"][0] for x in np.array(m)[settled]])) for i in (0, 1)],
        "settled_com_x_stride_m": float(np.mean([x["com_position"][0] for x in np.array(s)[settled]])),
        "settled_com_x_mujoco_m": float(np.mean([x["com_position"][0] for x in np.array(m)[settled]])),
    }
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--drop", type=float, default=0.02)
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--bend", type=float, default=0.2)
    ap.add_argument("--json", help="write the comparison (and both trajectories) to this file")
    args = ap.parse_args()
    stride = stride_trajectory(args.drop, args.duration, args.bend)
    model = build_mujoco(stride, 1.0 / stride["rate_hz"])
    mj = run_mujoco(model, stride, args.duration)
    result = compare(stride["samples"], mj)
    print(json.dumps(result, indent=2))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"comparison": result, "stride": stride["samples"], "mujoco": mj}, f)


if __name__ == "__main__":
    sys.exit(main())
