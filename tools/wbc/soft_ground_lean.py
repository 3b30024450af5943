#!/usr/bin/env python3
"""Where the torso's lean comes from in a soft-ground walk's log (docs/soft-ground.md, "Stage 2b").

Prints, every STEP seconds, the torso tilt (/runner/tracking), the pelvis roll and pitch (/estimation/state),
the torso, shoulder, hip and ankle roll joints (/wbc/input state), the contacts' loads (/wbc/output), the
measured normal forces, the running count of QP fallbacks and the DCM error: the counter-rotation of the
upper body against the legs' roll shows as torso or pelvis roll of the opposite sign to the hip rolls.
Needs the `mcap` package: `python3 tools/wbc/soft_ground_lean.py LOG.mcap [STEP] [FROM]`.
"""
import json
import math
import sys

from mcap.reader import make_reader

JOINTS = ["torso_pitch", "torso_roll", "l_shoulder_roll", "r_shoulder_roll",
          "l_hip_roll", "r_hip_roll", "l_ankle_roll", "r_ankle_roll"]


def roll_pitch_deg(q):
    x, y, z, w = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return math.degrees(roll), math.degrees(pitch)


def main():
    path = sys.argv[1]
    step = float(sys.argv[2]) if len(sys.argv) > 2 else 0.1
    start = float(sys.argv[3]) if len(sys.argv) > 3 else 0.0
    names, rows, t = None, {}, 0.0
    topics = ["/robot/description", "/wbc/input", "/wbc/output", "/estimation/state", "/runner/tracking"]
    with open(path, "rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=topics):
            d = json.loads(message.data)
            if channel.topic == "/robot/description":
                names = d["joint_names"]
            elif channel.topic == "/wbc/input":
                t = round(d["time_ns"] * 1e-9, 4)
                rows.setdefault(t, {})["in"] = d
            elif channel.topic == "/wbc/output":
                rows.setdefault(t, {})["out"] = d
            else:
                rows.setdefault(round(d["time"], 4), {})[channel.topic] = d
    index = [names.index(j) for j in JOINTS]
    print("t [s]  tilt  pelvis r/p | " + " ".join(f"{j[:10]:>10}" for j in JOINTS)
          + " | loads L R | fz L, R [N] | fallbacks | DCM [mm]")
    last, fallbacks = -1.0, 0
    for t in sorted(rows):
        e = rows[t]
        if "out" in e and e["out"]["report"]["fallback"]:
            fallbacks += 1
        if t < start or t - last < step - 1e-9:
            continue
        if not all(k in e for k in ("in", "out", "/estimation/state", "/runner/tracking")):
            continue
        last = t
        q = e["in"]["state"]["joint_positions"]
        s, tr, out = e["/estimation/state"], e["/runner/tracking"], e["out"]
        roll, pitch = roll_pitch_deg(s["base_orientation_xyzw"])
        joints = " ".join(f"{math.degrees(q[i]):10.1f}" for i in index)
        print(f"{t:5.2f} {tr['tilt_deg']:5.1f} {roll:5.1f} {pitch:5.1f} | {joints} | "
              f"{out['contact_load'][0]:.2f} {out['contact_load'][1]:.2f} | "
              f"{s['left_foot_wrench'][2]:6.1f} {s['right_foot_wrench'][2]:6.1f} | {fallbacks:5d} | "
              f"{tr['dcm_error'] * 1000:5.1f}")


if __name__ == "__main__":
    main()
