#!/usr/bin/env python3
"""How much of the deflection observer's swing-leg error the swing-foot plan's acceleration explains
(docs/flexible-joints.md, "The CoM height floor removed"). From a `stride run` log of a TSID-Flex scenario,
at the ticks where `/sim/state` and `/wbc/input` share a time, for each leg while its foot is not in contact
(`/wbc/input`'s `left_in_contact` / `right_in_contact`): the hip pitch deflection error (the observer's
estimate in `/wbc/input`'s state against `/sim/state`), and what is left of it after a least-squares fit on
the planned swing-foot acceleration's x and z (`/wbc/input`'s `left_foot` / `right_foot` `acceleration`,
world) and a constant. In-sample: an upper bound on what an observer fed the plan's acceleration could remove.

    python3 tools/scenarios/flex-swing-acceleration.py LOG.mcap [LOG.mcap ...]     # needs `mcap`, `numpy`
"""
import json
import sys

import numpy as np
from mcap.reader import make_reader

TOPICS = ["/robot/description", "/sim/state", "/wbc/input"]


def read(path):
    d = {t: [] for t in TOPICS}
    for _, channel, message in make_reader(open(path, "rb")).iter_messages(topics=TOPICS):
        d[channel.topic].append(json.loads(message.data))
    return d


def swing_fit(d):
    names = d["/robot/description"][0]["joint_names"]
    sim = {round(m["time"] * 1000): m for m in d["/sim/state"]}
    wbc = {round(m["time_ns"] / 1e6): m for m in d["/wbc/input"]}
    keys = sorted(set(sim) & set(wbc))
    for side, foot, contact in (("l", "left_foot", "left_in_contact"), ("r", "right_foot", "right_in_contact")):
        i = names.index(f"{side}_hip_flex_pitch")
        swing = np.array([not wbc[k][contact] for k in keys])
        err = np.array([wbc[k]["state"]["joint_positions"][i] - sim[k]["joint_positions"][i] for k in keys]) * 1e3
        acc = np.array([[wbc[k][foot]["acceleration"][0], wbc[k][foot]["acceleration"][2]] for k in keys])
        x = np.column_stack([acc[swing], np.ones(swing.sum())])
        coef, *_ = np.linalg.lstsq(x, err[swing], rcond=None)
        left = err[swing] - x @ coef
        print(f"  {side}_hip_flex_pitch in swing ({swing.sum()} ticks): error RMS {np.sqrt(np.mean(err[swing] ** 2)):.2f} "
              f"mrad, {np.sqrt(np.mean(left ** 2)):.2f} after the fit (x {coef[0]:+.2f}, z {coef[1]:+.2f} mrad per m/s², "
              f"constant {coef[2]:+.2f} mrad)")


for path in sys.argv[1:]:
    print(path)
    swing_fit(read(path))
