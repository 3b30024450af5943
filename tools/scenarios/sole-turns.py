#!/usr/bin/env python3
"""How far each loaded stance sole turns about the vertical on the floor (docs/estimation.md, "A stance sole
spinning on the floor"; docs/mujoco.md): for every stance (the foot's normal force in `/sensors/feet` over
100 N), the true yaw of the ankle's last link (`/tf`) from its value at load, its largest magnitude and its
value at unload. Prints the largest turn, the sum of the final turns, and each stance as `final/largest` in
degrees, in time order.

    python3 tools/scenarios/sole-turns.py LOG.mcap [LOG.mcap ...]     # needs `mcap`
"""
import bisect
import json
import math
import sys

from mcap.reader import make_reader

FEET = (("left", "l_ankle_2"), ("right", "r_ankle_2"))
LOADED = 100.0  # N


def yaw(q):
    return math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))


def read(path):
    """(time, {link: yaw}) from /tf and (time, left f_z, right f_z) from /sensors/feet."""
    links = {link for _, link in FEET}
    tf, feet = [], []
    for _, channel, message in make_reader(open(path, "rb")).iter_messages(topics=["/tf", "/sensors/feet"]):
        d = json.loads(message.data)
        if channel.topic == "/tf":
            stamp = d["transforms"][0]["timestamp"]
            yaws = {t["child_frame_id"]: yaw(t["rotation"]) for t in d["transforms"] if t["child_frame_id"] in links}
            tf.append((stamp["sec"] + 1e-9 * stamp["nsec"], yaws))
        else:
            feet.append((d["time"], d["left"]["force"][2], d["right"]["force"][2]))
    return tf, feet


def stances(tf, feet):
    """(load time, side, largest |turn|, final turn) of every loaded stance, in radians."""
    times = [f[0] for f in feet]
    out = []
    for column, (side, link) in enumerate(FEET, start=1):
        current = None
        for t, yaws in tf:
            i = max(0, bisect.bisect_right(times, t) - 1)
            loaded = bool(feet) and feet[i][column] > LOADED
            if loaded and current is None:
                current = [t, yaws[link], 0.0, 0.0]
            elif loaded:
                turn = (yaws[link] - current[1] + math.pi) % (2 * math.pi) - math.pi
                current[2] = max(current[2], abs(turn))
                current[3] = turn
            elif current is not None:
                out.append((current[0], side, current[2], current[3]))
                current = None
    return sorted(out)


def main():
    for path in sys.argv[1:]:
        s = stances(*read(path))
        largest = max((x[2] for x in s), default=0.0)
        total = sum(x[3] for x in s)
        print(f"{path}: {len(s)} stances; largest turn {math.degrees(largest):.2f}°; final turns sum to {math.degrees(total):.2f}°")
        print("  " + " ".join(f"{math.degrees(x[3]):+.2f}/{math.degrees(x[2]):.2f}" for x in s))


if __name__ == "__main__":
    main()
