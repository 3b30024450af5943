#!/usr/bin/env python3
"""The turn rate of a turn in place (issue 15's turning target, docs/gait.md "Turning"): the base's yaw
(`root_link` in `/tf`, the true state) unwrapped over the run, and its mean rate between 10 % and 90 % of the
whole turn, and over the whole run.

    python3 tools/scenarios/turn-rate.py LOG.mcap [LOG.mcap ...]     # needs `mcap`
"""
import json
import math
import sys

from mcap.reader import make_reader


def base_yaw(path, frame="root_link"):
    """(time [s], yaw [rad]) of `frame` in `/tf`, the yaw unwrapped."""
    times, yaws = [], []
    for _, _, message in make_reader(open(path, "rb")).iter_messages(topics=["/tf"]):
        for t in json.loads(message.data)["transforms"]:
            if t["child_frame_id"] != frame:
                continue
            q = t["rotation"]
            yaw = math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]), 1 - 2 * (q["y"] ** 2 + q["z"] ** 2))
            if yaws:
                step = yaw - yaws[-1]
                yaw = yaws[-1] + step - 2 * math.pi * round(step / (2 * math.pi))
            times.append(t["timestamp"]["sec"] + 1e-9 * t["timestamp"]["nsec"])
            yaws.append(yaw)
    return times, yaws


def main():
    for path in sys.argv[1:]:
        times, yaws = base_yaw(path)
        total = yaws[-1] - yaws[0]
        turned = [abs(y - yaws[0]) for y in yaws]
        t10 = next(t for t, a in zip(times, turned) if a >= 0.1 * abs(total))
        t90 = next(t for t, a in zip(times, turned) if a >= 0.9 * abs(total))
        deg = math.degrees(abs(total))
        print(
            f"{path}: turned {math.degrees(total):.1f}°; 10–90 % between {t10:.2f} and {t90:.2f} s: "
            f"{0.8 * deg / (t90 - t10):.1f}°/s; over the whole run ({times[-1]:.2f} s): {deg / times[-1]:.1f}°/s"
        )


if __name__ == "__main__":
    main()
