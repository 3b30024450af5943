#!/usr/bin/env python3
"""Join the timings of stride (`cargo run --release -p stride-model --example cpu_timings`) and Pinocchio
(tools/bench/pinocchio_timings.py) measured in alternation by tools/bench/vs-pinocchio.

Usage: compare.py --stride S1 [S2 ...] --pinocchio P1 [P2 ...]

Every file holds lines "<model>/<algorithm> <wall us> <cpu us>", each the best of its rounds (see the two
tools). Run i is the pair (Si, Pi), measured back to back. For each algorithm and clock the table gives
the median over the runs of stride's figure, of Pinocchio's figure and of the ratio stride/Pinocchio of the
same run, with the smallest and largest of those ratios. Prints a Markdown table.
"""

import argparse
import statistics
import sys

ORDER = ["set_state", "fk", "jacobians", "link_jacobians", "crba", "rnea", "aba", "cmm"]
MODELS = ["stride_humanoid", "iCubGazeboV2_7"]


def read(path):
    out = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 3:
                continue
            out[parts[0]] = (float(parts[1]), float(parts[2]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--stride", nargs="+", required=True)
    ap.add_argument("--pinocchio", nargs="+", required=True)
    args = ap.parse_args()
    if len(args.stride) != len(args.pinocchio):
        sys.exit("compare.py: %d stride runs but %d Pinocchio runs" % (len(args.stride), len(args.pinocchio)))
    runs = [(read(s), read(p)) for s, p in zip(args.stride, args.pinocchio)]
    print("runs: %d (medians over runs; ratio range = smallest..largest ratio of one run)" % len(runs))
    print()
    print("| model / algorithm | stride wall µs | Pinocchio wall µs | ratio wall (range) "
          "| stride CPU µs | Pinocchio CPU µs | ratio CPU (range) |")
    print("|---|---|---|---|---|---|---|")
    rows = 0
    for model in MODELS:
        for algo in ORDER:
            key = "%s/%s" % (model, algo)
            if not any(key in s for s, _ in runs):
                continue
            cells = []
            for clock in (0, 1):
                st = [s[key][clock] for s, _ in runs if key in s]
                pn = [p[key][clock] for _, p in runs if key in p]
                ratios = [s[key][clock] / p[key][clock] for s, p in runs if key in s and key in p]
                cells.append("%.2f" % statistics.median(st))
                cells.append("%.2f" % statistics.median(pn) if pn else "–")
                cells.append("%.2f (%.2f–%.2f)" % (statistics.median(ratios), min(ratios), max(ratios))
                             if ratios else "–")
            print("| %s / %s | %s |" % (model, algo, " | ".join(cells)))
            rows += 1
    if not rows:
        sys.exit("compare.py: no results")


if __name__ == "__main__":
    main()
