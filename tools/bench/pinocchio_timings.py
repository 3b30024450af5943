#!/usr/bin/env python3
"""Time Pinocchio on the URDFs and states stride-model is benchmarked and tested on.

For each model it loads the URDF with a free-flyer root, takes the joint positions / velocities / torques of the
states of crates/model/tests/fixtures/<model>.json (joints mapped by name), and times, per call:

  set_state  forwardKinematics(q, v) (joint placements and velocities: what stride's KinDyn::set_state does)
  fk         framesForwardKinematics (placements of every joint and frame)
  jacobians  computeJointJacobians (the Jacobians of every joint; a frame Jacobian is then a copy + transform)
  crba       crba (mass matrix)
  rnea       rnea (inverse dynamics, with velocities and accelerations)
  aba        aba (forward dynamics)
  cmm        computeCentroidalMap (centroidal momentum matrix)

Each algorithm is run in a loop over the states (cycling) for --repeat rounds of --calls calls; the reported
time is the best round's mean, in microseconds. The Python call overhead (about 0.2-0.4 us per call) is
included and also measured alone ("overhead": a call of a trivial Pinocchio function) so it can be judged.

With --harness BIN the same algorithms are timed by the C++ program pinocchio_bench.cpp (linked against the
wheel's libpinocchio_default), on the same model (passed through Model.saveToBinary) and states, without the
Python overhead.

Output: one JSON object {"<model>/<algorithm>": microseconds, ...} on stdout (or --out FILE).
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def model_path(name):
    if name == "stride_humanoid":
        return os.path.join(ROOT, "models", "stride_humanoid.urdf")
    base = os.environ.get("STRIDE_ICUB_MODELS_DIR")
    if not base:
        import icub_models

        base = icub_models.get_models_path()
    return os.path.join(base, name, "model.urdf")


def states_for(model, name):
    """(q, v, a, tau) in Pinocchio order for the fixture states of `name` (random if there is no fixture)."""
    fixture = os.path.join(ROOT, "crates", "model", "tests", "fixtures", name + ".json")
    out = []
    if os.path.exists(fixture):
        with open(fixture) as f:
            fx = json.load(f)
        idx_q = [model.joints[model.getJointId(j)].idx_q for j in fx["joint_names"]]
        idx_v = [model.joints[model.getJointId(j)].idx_v for j in fx["joint_names"]]
        for st in fx["states"]:
            q = pin.neutral(model)
            q[:3] = st["base_position"]
            q[3:7] = st["base_orientation_xyzw"]
            q[3:7] /= np.linalg.norm(q[3:7])
            q[idx_q] = st["joint_positions"]
            v = np.zeros(model.nv)
            v[:6] = st["base_velocity"]["body"]
            v[idx_v] = st["joint_velocities"]
            a = np.zeros(model.nv)
            a[:6] = st["nu_dot"][:6]
            a[idx_v] = st["nu_dot"][6:]
            tau = np.zeros(model.nv)
            tau[idx_v] = st["joint_torques"]
            out.append((q, v, a, tau))
    else:
        rng = np.random.default_rng(0)
        for _ in range(20):
            q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
            out.append((q, rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)))
    return out


def time_loop(fn, states, calls, repeat):
    n = len(states)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter_ns()
        for k in range(calls):
            fn(*states[k % n])
        dt = (time.perf_counter_ns() - t0) / calls / 1000.0
        best = min(best, dt)
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", nargs="*", default=["stride_humanoid", "iCubGazeboV2_7"])
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out")
    ap.add_argument("--harness", metavar="BIN",
                    help="time with the C++ harness pinocchio_bench (built from pinocchio_bench.cpp) instead of "
                         "Python loops")
    ap.add_argument("--dump", metavar="DIR",
                    help="write <model>.bin (Model.saveToBinary) and <model>.states for pinocchio_bench, then exit")
    args = ap.parse_args()
    results = {}
    for name in args.models:
        path = model_path(name)
        if not os.path.exists(path):
            print("pinocchio_timings: skipping %s (no %s)" % (name, path), file=sys.stderr)
            continue
        m = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
        d = m.createData()
        states = states_for(m, name)
        if args.harness:
            import subprocess
            import tempfile

            with tempfile.TemporaryDirectory() as tmp:
                m.saveToBinary(os.path.join(tmp, name + ".bin"))
                with open(os.path.join(tmp, name + ".states"), "w") as f:
                    for q, v, a, tau in states:
                        f.write(" ".join(repr(float(x)) for x in np.concatenate([q, v, a, tau])) + "\n")
                out = subprocess.run(
                    [args.harness, name, os.path.join(tmp, name + ".bin"), os.path.join(tmp, name + ".states"),
                     str(args.calls)],
                    check=True, capture_output=True, text=True,
                )
            for line in out.stdout.splitlines():
                key, us = line.split()
                results[key] = float(us)
            print(out.stderr.strip(), file=sys.stderr)
            continue
        if args.dump:
            os.makedirs(args.dump, exist_ok=True)
            m.saveToBinary(os.path.join(args.dump, name + ".bin"))
            with open(os.path.join(args.dump, name + ".states"), "w") as f:
                for q, v, a, tau in states:
                    f.write(" ".join(repr(float(x)) for x in np.concatenate([q, v, a, tau])) + "\n")
            print(os.path.join(args.dump, name))
            continue
        algos = {
            "overhead": lambda q, v, a, tau: pin.SE3.Identity(),
            "set_state": lambda q, v, a, tau: pin.forwardKinematics(m, d, q, v),
            "fk": lambda q, v, a, tau: pin.framesForwardKinematics(m, d, q),
            "jacobians": lambda q, v, a, tau: pin.computeJointJacobians(m, d, q),
            "crba": lambda q, v, a, tau: pin.crba(m, d, q),
            "rnea": lambda q, v, a, tau: pin.rnea(m, d, q, v, a),
            "aba": lambda q, v, a, tau: pin.aba(m, d, q, v, tau),
            "cmm": lambda q, v, a, tau: pin.computeCentroidalMap(m, d, q),
        }
        for algo, fn in algos.items():
            results["%s/%s" % (name, algo)] = time_loop(fn, states, args.calls, args.repeat)
        print("pinocchio_timings: %s nq=%d nv=%d frames=%d" % (name, m.nq, m.nv, m.nframes), file=sys.stderr)
    if args.dump:
        return
    text = json.dumps(results, indent=1, sort_keys=True)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    else:
        print(text)


if __name__ == "__main__":
    main()
