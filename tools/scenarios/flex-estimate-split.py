#!/usr/bin/env python3
"""Where a walk's CoM error comes from on the estimated state (docs/flexible-joints.md, "The 3 mm goal: where
the estimate's error comes from"). From a `stride run` log, at the state log's rate (the ticks where
`/estimation/state`, `/sim/state` and `/wbc/input` share a time):

- the CoM error as the summary computes it (`/runner/tracking`: the simplified layer's CoM reference, the
  plan's height, against the true CoM), split into horizontal and vertical, the horizontal one into the
  tracking of the estimate (reference against the estimated CoM, `/simplified/input`) and the estimate's
  error (estimated against true CoM);
- the base's position, linear velocity and tilt errors (`/estimation/state` against `/sim/state`);
- the flexible joints' (names containing `flex`) deflection and rate errors (`/wbc/input`'s state against
  `/sim/state`), overall and per phase of their leg (single stance, swing, double support, from the
  estimated contacts), as RMS and mean, in mrad;
- the estimated base x error's change across each change of the estimated contacts (one state-log period).

    python3 tools/scenarios/flex-estimate-split.py LOG.mcap [LOG.mcap ...]     # needs `mcap`, `numpy`
"""
import json
import sys

import numpy as np
from mcap.reader import make_reader

TOPICS = ["/robot/description", "/runner/tracking", "/simplified/input", "/simplified/output",
          "/planner/references", "/estimation/state", "/sim/state", "/wbc/input"]


def rms(a, axis=None):
    a = np.asarray(a)
    if a.ndim > 1 and axis is None:
        return float(np.sqrt(np.mean(np.sum(a * a, axis=-1))))
    return np.sqrt(np.mean(a * a, axis=axis))


def z_axis(q):
    x, y, z, w = q
    return np.array([2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)])


def read(path):
    d = {t: [] for t in TOPICS}
    for _, channel, message in make_reader(open(path, "rb")).iter_messages(topics=TOPICS):
        d[channel.topic].append(json.loads(message.data))
    return d


def com_split(d):
    tracking, simplified = d["/runner/tracking"], d["/simplified/input"]
    ref = np.array([m["com_position"] for m in d["/simplified/output"]])
    est = np.array([m["measured_com_position"] for m in simplified])
    true = np.array([m["measured_com"] for m in tracking])
    z_ref = np.array([m["com_position"][2] for m in d["/planner/references"]])
    total = rms([m["com_error"] for m in tracking])
    h = ref - true[:, :2]
    print(f"  CoM error RMS {total * 1e3:.2f} mm: horizontal {rms(h) * 1e3:.2f} "
          f"(tracking of the estimate {rms(ref - est) * 1e3:.2f}, estimate's error {rms(est - true[:, :2]) * 1e3:.2f}"
          f" = x {rms((est - true[:, :2])[:, 0]) * 1e3:.2f} / y {rms((est - true[:, :2])[:, 1]) * 1e3:.2f}), "
          f"vertical {rms(z_ref - true[:, 2]) * 1e3:.2f}")


def state_errors(d):
    sim = {round(m["time"] * 1000): m for m in d["/sim/state"]}
    est = {round(m["time"] * 1000): m for m in d["/estimation/state"]}
    wbc = {round(m["time_ns"] / 1e6): m for m in d["/wbc/input"]}
    keys = sorted(set(sim) & set(est) & set(wbc))
    names = d["/robot/description"][0]["joint_names"]
    flex = [i for i, n in enumerate(names) if "flex" in n]
    p = np.array([np.subtract(est[k]["base_position"], sim[k]["base"]["position"]) for k in keys])
    v = np.array([np.subtract(est[k]["base_linear_velocity"], sim[k]["base_velocity"][:3]) for k in keys])
    tilt = np.degrees([np.arccos(np.clip(z_axis(est[k]["base_orientation_xyzw"])
                                         @ z_axis(sim[k]["base"]["orientation_xyzw"]), -1, 1)) for k in keys])
    print(f"  base position error RMS x/y/z {' / '.join(f'{e * 1e3:.2f}' for e in rms(p, 0))} mm, velocity "
          f"{' / '.join(f'{e * 1e2:.2f}' for e in rms(v, 0))} cm/s, tilt {rms(tilt):.3f}°")
    contacts = np.array([[est[k]["contacts"]["left"], est[k]["contacts"]["right"]] for k in keys])
    if flex:
        s_err = np.array([[wbc[k]["state"]["joint_positions"][i] - sim[k]["joint_positions"][i] for i in flex]
                          for k in keys]) * 1e3
        s_true = np.array([[sim[k]["joint_positions"][i] for i in flex] for k in keys]) * 1e3
        r_err = np.array([[wbc[k]["state"]["joint_velocities"][i] - sim[k]["joint_velocities"][i] for i in flex]
                          for k in keys])
        for c, i in enumerate(flex):
            leg = 0 if names[i].startswith("l") else 1
            own, other = contacts[:, leg], contacts[:, 1 - leg]
            phases = {"stance": own & ~other, "swing": ~own, "double": own & other}
            per = ", ".join(f"{n} {rms(s_err[m, c]):.2f} / {np.mean(s_err[m, c]):+.2f}"
                            for n, m in phases.items() if m.any())
            print(f"  {names[i]}: deflection error RMS {rms(s_err[:, c]):.2f} mrad (true RMS {rms(s_true[:, c]):.1f}), "
                  f"rate {rms(r_err[:, c]):.3f} rad/s; per phase RMS / mean: {per}")
    def feet(c):
        return ("L" if c[0] else "-") + ("R" if c[1] else "-")

    jumps = [f"{keys[n] / 1000:.2f} s {feet(contacts[n - 1])}>{feet(contacts[n])} {(p[n, 0] - p[n - 1, 0]) * 1e3:+.2f}"
             for n in range(1, len(keys)) if feet(contacts[n]) != feet(contacts[n - 1])]
    print("  base x error change across the contact changes [mm]: " + "; ".join(jumps))


for path in sys.argv[1:]:
    log = read(path)
    print(path)
    com_split(log)
    state_errors(log)
