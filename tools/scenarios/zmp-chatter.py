#!/usr/bin/env python3
"""Where a position walk's ZMP error comes from (docs/sim.md, "Is the default floor a hard floor"): the error of
the measured ZMP (/runner/tracking, what the summary's RMS uses) and of the true one (the plant's contact
wrenches, /sensors/feet) against the desired ZMP (/simplified/output, held between its ticks), each split into a
slow part (0.1 s moving average) and a fast rest, the fast rest's power by band, and the true error by planned
phase (double / single support), split into the load distribution between the feet (the ZMP with each foot's
CoP at its sole origin) and the CoPs' own motion. Log at `[log] state_hz = 500` for bands up to 250 Hz.

    python3 tools/scenarios/zmp-chatter.py LOG.mcap [T0 T1]     # needs `mcap` and `numpy`; default 2.5–12.5 s
"""
import json
import sys

import numpy as np
from mcap.reader import make_reader

BANDS = [(0, 5), (5, 10), (10, 20), (20, 50), (50, 100), (100, 250)]
TOPICS = ["/runner/tracking", "/simplified/output", "/sensors/feet", "/planner/references"]


def read(path):
    measured, desired, feet, phases = [], [], [], []
    for _, channel, message in make_reader(open(path, "rb")).iter_messages(topics=TOPICS):
        d = json.loads(message.data)
        if channel.topic == "/runner/tracking":
            measured.append((d["time"], *d["measured_zmp"]))
        elif channel.topic == "/simplified/output":
            desired.append((d["time"]["secs"] + d["time"]["nanos"] * 1e-9, *d["desired_zmp"]))
        elif channel.topic == "/planner/references":
            phases.append((d["time"], d["phase"] == "double_support"))
        else:
            row = [d["time"]]
            for side in ("left", "right"):
                f, tau, p = (np.array(d[side][k]) for k in ("force", "torque", "point"))
                cop = p[:2] + (np.array([-tau[1], tau[0]]) / f[2] if f[2] > 1.0 else 0.0)
                row += [f[2], *p[:2], *cop]
            feet.append(row)
    return np.array(measured), np.array(desired), np.array(feet), phases


def held(t, series):
    """The last sample of `series` (time in column 0) at or before each time of `t`."""
    i = np.clip(np.searchsorted(series[:, 0], t + 1e-9) - 1, 0, None)
    return series[i, 1:3]


def split(t, e):
    n = max(1, int(round(0.1 / float(np.median(np.diff(t))))))
    slow = np.stack([np.convolve(e[:, i], np.ones(n) / n, "same") for i in (0, 1)], 1)
    return slow, e - slow


def rms(x):
    return np.sqrt(np.mean(x ** 2, axis=0)) * 1e3


def report(name, t, zmp, desired):
    e = zmp - held(t, desired)
    slow, fast = split(t, e)
    print(f"{name} ({1 / np.median(np.diff(t)):.0f} Hz), x / y mm: error {rms(e).round(1)}, "
          f"slow {rms(slow).round(1)}, fast {rms(fast).round(1)}")
    f = np.fft.rfftfreq(len(t), float(np.median(np.diff(t))))
    for i, axis in enumerate("xy"):
        p = np.abs(np.fft.rfft(fast[:, i])) ** 2
        shares = ", ".join(f"{a}–{b} Hz {100 * p[(f >= a) & (f < b)].sum() / p.sum():.0f} %"
                           for a, b in BANDS if a < f[-1])
        print(f"  fast {axis}: peak {f[np.argmax(p)]:.1f} Hz; {shares}")


def main():
    path = sys.argv[1]
    t0, t1 = (float(sys.argv[2]), float(sys.argv[3])) if len(sys.argv) > 3 else (2.5, 12.5)
    measured, desired, feet, phases = read(path)
    w = (measured[:, 0] >= t0) & (measured[:, 0] <= t1)
    report("measured ZMP", measured[w, 0], measured[w, 1:3], desired)
    t, fl, fr = feet[:, 0], feet[:, 1], feet[:, 6]
    total = fl + fr
    ok = (total > 50.0) & (t >= t0) & (t <= t1)
    zmp = (fl[:, None] * feet[:, 4:6] + fr[:, None] * feet[:, 9:11]) / np.maximum(total, 1.0)[:, None]
    origins = (fl[:, None] * feet[:, 2:4] + fr[:, None] * feet[:, 7:9]) / np.maximum(total, 1.0)[:, None]
    report("true ZMP", t[ok], zmp[ok], desired)
    pt = np.array([p[0] for p in phases])
    double = np.array([p[1] for p in phases])[np.clip(np.searchsorted(pt, t + 1e-9) - 1, 0, None)]
    _, fast = split(t, zmp - held(t, desired))
    _, fast_load = split(t, origins)
    _, fast_cop = split(t, zmp - origins)
    for name, sel in (("double support", ok & double), ("single support", ok & ~double)):
        print(f"{name}, true ZMP, fast x / y mm: {rms(fast[sel]).round(1)}; of the load distribution "
              f"{rms(fast_load[sel]).round(1)}, of the CoPs {rms(fast_cop[sel]).round(1)}")


if __name__ == "__main__":
    main()
