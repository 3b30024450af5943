#!/usr/bin/env python3
"""Join criterion results of `cargo bench -p stride-model` with tools/bench/pinocchio_timings.py output.

Usage: compare.py CRITERION_DIR PINOCCHIO_JSON [--since EPOCH_SECONDS] [--json OUT]

Criterion benchmark ids are matched to algorithms and models by name (case-insensitive substrings):
  model:      "icub" or "v2_7" -> iCubGazeboV2_7, otherwise stride_humanoid
  algorithm:  set_state ("set_state": stride's state update = Pinocchio's forwardKinematics(q, v)),
              fk (forward kinematics of all frames: "kinematics", "fk", "poses"), jacobians ("joint" +
              "jacobian"), crba ("crba", "mass"), rnea ("rnea", "inverse", "bias"), aba ("aba", "forward_dyn"),
              cmm ("cmm", "centroidal")
Prints one line per algorithm and model:
  <model>/<algorithm> stride=<us> pinocchio=<us> ratio=<stride/pinocchio>
Only estimates written after --since are used (stale results of earlier runs are ignored).
"""

import argparse
import glob
import json
import os
import sys

ORDER = ["set_state", "fk", "jacobians", "crba", "rnea", "aba", "cmm"]


def classify(full_id):
    s = full_id.lower()
    model = "iCubGazeboV2_7" if ("icub" in s or "v2_7" in s) else "stride_humanoid"
    if "set_state" in s:
        algo = "set_state"
    elif "jacobian" in s and "com" not in s:
        # Pinocchio's computeJointJacobians fills the joint columns once: compare it with stride's one-pass
        # `joint_jacobians`, not with the per-link dense frame Jacobians (reported by criterion only).
        algo = "jacobians" if "joint" in s else None
    elif "crba" in s or "mass" in s:
        algo = "crba"
    elif "rnea" in s or "inverse" in s or "bias" in s:
        algo = "rnea"
    elif "aba" in s or "forward_dyn" in s or "forward dyn" in s:
        algo = "aba"
    elif "cmm" in s or "centroidal" in s:
        algo = "cmm"
    elif "kinematics" in s or "fk" in s or "poses" in s:
        algo = "fk"
    else:
        algo = None
    return model, algo


def criterion_results(directory, since):
    out = {}
    for est in glob.glob(os.path.join(directory, "**", "new", "estimates.json"), recursive=True):
        if os.path.getmtime(est) < since:
            continue
        bench = os.path.join(os.path.dirname(est), "benchmark.json")
        try:
            with open(bench) as f:
                full_id = json.load(f)["full_id"]
        except (OSError, KeyError, ValueError):
            full_id = os.path.relpath(os.path.dirname(os.path.dirname(est)), directory)
        with open(est) as f:
            e = json.load(f)
        ns = (e.get("slope") or e["mean"])["point_estimate"]
        model, algo = classify(full_id)
        if algo is None:
            continue
        key = "%s/%s" % (model, algo)
        # several benchmarks may map to one algorithm (e.g. two Jacobian variants): keep each, report the first
        out.setdefault(key, []).append((full_id, ns / 1000.0))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("criterion_dir")
    ap.add_argument("pinocchio_json")
    ap.add_argument("--since", type=float, default=0.0)
    ap.add_argument("--json")
    args = ap.parse_args()
    stride = criterion_results(args.criterion_dir, args.since)
    with open(args.pinocchio_json) as f:
        pinocchio = json.load(f)
    rows = []
    for model in ["stride_humanoid", "iCubGazeboV2_7"]:
        for algo in ORDER:
            key = "%s/%s" % (model, algo)
            s = stride.get(key)
            p = pinocchio.get(key)
            if s is None and p is None:
                continue
            s_us = min(v for _, v in s) if s else None
            ids = ",".join(i for i, _ in s) if s else "-"
            fmt = lambda x: "%.3f" % x if x is not None else "n/a"
            ratio = "%.2f" % (s_us / p) if (s_us is not None and p) else "n/a"
            print("%s stride=%s pinocchio=%s ratio=%s" % (key, fmt(s_us), fmt(p), ratio))
            rows.append({"model": model, "algorithm": algo, "stride_us": s_us, "pinocchio_us": p,
                         "stride_benchmarks": ids})
    unmatched = sorted(k for k in stride if k not in {"%s/%s" % (m, a) for m in ("stride_humanoid", "iCubGazeboV2_7") for a in ORDER})
    if unmatched:
        print("unmatched criterion benchmarks: %s" % unmatched, file=sys.stderr)
    if "stride_humanoid/overhead" in pinocchio:
        print("(pinocchio times are Python loops; the call overhead alone is %.2f us)"
              % pinocchio["stride_humanoid/overhead"], file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    if not rows:
        sys.exit("compare.py: no results")


if __name__ == "__main__":
    main()
