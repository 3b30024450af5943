#!/usr/bin/env python3
"""Time Pinocchio on the URDFs and states stride-model is timed on (tools/bench/vs-pinocchio).

For each model it loads the URDF with a free-flyer root and takes the 20 states of
crates/model/tests/fixtures/<model>.json (joints mapped by name; base velocity in the body representation,
Pinocchio's; `nu_dot` and `joint_torques` as the inputs of rnea and aba), the states stride's
`cargo run --release -p stride-model --example cpu_timings` reads, and times, per call:

  set_state  forwardKinematics(q, v) (joint placements and velocities: what stride's KinDyn::set_state does)
  fk         framesForwardKinematics (placements of every joint and frame)
  jacobians  computeJointJacobians (the Jacobians of every joint; a frame Jacobian is then a copy + transform)
  crba       crba (mass matrix)
  rnea       rnea (inverse dynamics, with velocities and accelerations)
  aba        aba (forward dynamics)
  cmm        computeCentroidalMap (centroidal momentum matrix)

The protocol is stride's: the states are cycled through in order; one untimed warm-up pass of calls/10
calls, then --rounds rounds of --calls calls; per round, the wall-clock time (time.perf_counter_ns, or
std::chrono::steady_clock in the harness) and the thread's CPU time (time.thread_time_ns, or
clock_gettime(CLOCK_THREAD_CPUTIME_ID) in the harness) divided by the calls; each clock's figure is its best
round, in microseconds.

With --harness BIN the algorithms are timed by the C++ program pinocchio_bench.cpp (linked against the
wheel's libpinocchio_default), on the same model (passed through Model.saveToBinary) and states, without the
Python call overhead. Without it they are timed by Python loops, which include the call overhead (about
0.2-0.4 us per call), also measured alone ("overhead": a call of a trivial Pinocchio function).

Output: one line per algorithm, "<model>/<algorithm> <wall us> <cpu us>" (the format of cpu_timings), on
stdout or in --out FILE.
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
    """(q, v, a, tau) in Pinocchio order for the fixture states of `name`."""
    fixture = os.path.join(ROOT, "crates", "model", "tests", "fixtures", name + ".json")
    if not os.path.exists(fixture):
        sys.exit("pinocchio_timings: no fixture %s (stride is timed on the fixture states only)" % fixture)
    with open(fixture) as f:
        fx = json.load(f)
    idx_q = [model.joints[model.getJointId(j)].idx_q for j in fx["joint_names"]]
    idx_v = [model.joints[model.getJointId(j)].idx_v for j in fx["joint_names"]]
    out = []
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
    return out


def time_loop(fn, states, calls, rounds):
    n = len(states)
    for k in range(calls // 10):
        fn(*states[k % n])
    wall, cpu = float("inf"), float("inf")
    for _ in range(rounds):
        c0, t0 = time.thread_time_ns(), time.perf_counter_ns()
        for k in range(calls):
            fn(*states[k % n])
        t1, c1 = time.perf_counter_ns(), time.thread_time_ns()
        wall = min(wall, (t1 - t0) / calls / 1000.0)
        cpu = min(cpu, (c1 - c0) / calls / 1000.0)
    return wall, cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", nargs="*", default=["stride_humanoid", "iCubGazeboV2_7"])
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=7)
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
                     str(args.calls), str(args.rounds)],
                    check=True, capture_output=True, text=True,
                )
            for line in out.stdout.splitlines():
                key, wall, cpu = line.split()
                results[key] = (float(wall), float(cpu))
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
            results["%s/%s" % (name, algo)] = time_loop(fn, states, args.calls, args.rounds)
        print("pinocchio_timings: %s nq=%d nv=%d frames=%d" % (name, m.nq, m.nv, m.nframes), file=sys.stderr)
    if args.dump:
        return
    text = "".join("%s %.4f %.4f\n" % (key, wall, cpu) for key, (wall, cpu) in results.items())
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)

if __name__ == "__main__":
    main()
