#!/usr/bin/env python3
"""RMS and spectrum by band of the signals behind docs/foot-admittance.md's "MuJoCo" table: the estimated sole
torques and normal forces (/estimation/state), the ankle joint torques (/sim/state) and the sole references'
angular velocities (/wbc/input) of a log, over a time window. Log at `[log] state_hz = 500` for a 250 Hz band.

    python3 tools/scenarios/band-power.py LOG.mcap T0 T1      # needs the `mcap` and `numpy` packages
"""
import json
import sys

import numpy as np
from mcap.reader import make_reader

BANDS = [(0, 5), (5, 25), (25, 50), (50, 125), (125, 250)]


def read(path, t0, t1):
    names, series = None, {}
    reader = make_reader(open(path, "rb"))
    topics = ["/robot/description", "/estimation/state", "/sim/state", "/wbc/input"]
    for _, channel, message in reader.iter_messages(topics=topics):
        d = json.loads(message.data)
        if channel.topic == "/robot/description":
            names = d["joint_names"]
            continue
        t = message.log_time * 1e-9
        if not t0 <= t <= t1:
            continue
        rows = []
        if channel.topic == "/estimation/state":
            for side in ("left", "right"):
                w = d[f"{side}_foot_wrench"]
                rows += [(f"{side} sole torque x (N·m)", w[3]), (f"{side} sole torque y (N·m)", w[4]),
                         (f"{side} sole f_z (N)", w[2])]
        elif channel.topic == "/sim/state":
            for j in ("l_ankle_pitch", "l_ankle_roll", "r_ankle_pitch", "r_ankle_roll"):
                rows.append((f"{j} torque (N·m)", d["joint_torques"][names.index(j)]))
        else:
            for side in ("left", "right"):
                v = d[f"{side}_foot"]["velocity"]
                rows += [(f"{side} sole ref. ω_x (rad/s)", v[3]), (f"{side} sole ref. ω_y (rad/s)", v[4])]
        for label, value in rows:
            series.setdefault(label, ([], []))
            series[label][0].append(t)
            series[label][1].append(value)
    return series


def main():
    path, t0, t1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    head = " | ".join(f"{a}–{b} Hz" for a, b in BANDS)
    print(f"| signal | RMS about the mean | {head} |")
    print("|---" * (len(BANDS) + 2) + "|")
    for label, (t, x) in read(path, t0, t1).items():
        x = np.asarray(x) - np.mean(x)
        dt = float(np.median(np.diff(t)))
        f = np.fft.rfftfreq(len(x), dt)
        p = np.abs(np.fft.rfft(x)) ** 2
        shares = " | ".join(f"{100 * p[(f >= a) & (f < b)].sum() / p.sum():.0f} %" for a, b in BANDS)
        print(f"| {label} | {x.std():.3g} | {shares} |")


if __name__ == "__main__":
    main()
