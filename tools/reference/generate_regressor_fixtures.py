#!/usr/bin/env python3
"""Generate the inertial-parameter regressor fixtures of stride-model from iDynTree.

For the bundled `models/stride_humanoid.urdf` and the official iCubGazeboV2_7 (icub-models), at seeded random
states (base pose and velocity, joint positions and velocities) and generalized accelerations nu_dot (mixed
representation), this script writes iDynTree 15.1.0's
KinDynComputations::inverseDynamicsInertialParametersRegressor Y (nv x 10 n_links, mixed representation,
floating base = the URDF root) and the model's parameter vector psi (Model::getInertialParameters), after
checking that Y psi equals KinDynComputations::inverseDynamics without external wrenches to 1e-10 (the script
aborts otherwise): this pins iDynTree's parameter order and representation.

iDynTree's parameter layout (also under "conventions"): one block of 10 per iDynTree link, in "link_names"
order (iDynTree keeps every massive link, so links joined by fixed joints -- e.g. across an FT sensor -- are
separate blocks; massless leaves are frames), each block
  [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]
in the link frame, I about the LINK ORIGIN: the same per-body order as stride-model's
[Traversaro 2017, eq. 6.3]. stride-model lumps links joined by fixed joints into one body, so its parameter
vector is P psi with P moving each link block into its body's frame and summing (the Rust test builds P from
the model's frames).

Usage: python3 tools/reference/generate_regressor_fixtures.py [--states N] [--out DIR] [--models ...]
Requires the pinned packages of tools/reference/requirements.txt (see generate_ft_fixtures.py).
"""

import argparse
import json
import os
import sys

import numpy as np
import idyntree.bindings as idt

from generate_fixtures import DIGITS, check, exact, rnd  # noqa: E402
from generate_ft_fixtures import GRAVITY, ROOT, Setup, icub_models, random_state  # noqa: E402

MODELS = {
    "stride_humanoid": {
        "urdf": os.path.join(ROOT, "models", "stride_humanoid.urdf"),
        "base": "root_link",
        "seed": 20261219,
    },
    "iCubGazeboV2_7": {
        "icub": "iCubGazeboV2_7",
        "base": "root_link",
        "seed": 719,
    },
}


def regressor(su, st):
    """iDynTree's regressor at one state, checked against its inverse dynamics."""
    kd, model = su.kd, su.model
    H = idt.Transform(idt.Rotation.FromPython(st["R"]), idt.Position.FromPython(st["p"]))
    assert kd.setRobotState(H, idt.VectorDynSize.FromPython(st["s"]), idt.Twist.FromPython(st["v_mixed"]),
                            idt.VectorDynSize.FromPython(st["s_dot"]), idt.Vector3.FromPython(GRAVITY))
    base_acc = idt.Vector6.FromPython(st["nu_dot"][:6])
    s_ddot = idt.VectorDynSize.FromPython(st["nu_dot"][6:])
    nl = model.getNrOfLinks()
    Y = idt.MatrixDynSize(su.nv, 10 * nl)
    assert kd.inverseDynamicsInertialParametersRegressor(base_acc, s_ddot, Y)
    Y = Y.toNumPy().copy()
    zero = idt.LinkWrenches(model)
    zero.zero()
    gt = idt.FreeFloatingGeneralizedTorques(model)
    assert kd.inverseDynamics(base_acc, s_ddot, zero, gt)
    tau = np.concatenate([gt.baseWrench().toNumPy(), gt.jointTorques().toNumPy()])
    check("regressor times parameters vs inverse dynamics", Y @ parameters(su), tau)
    return Y


def parameters(su):
    psi = idt.VectorDynSize(10 * su.model.getNrOfLinks())
    assert su.model.getInertialParameters(psi)
    return psi.toNumPy().copy()


def generate(name, spec, urdf_path, n_states):
    su = Setup(urdf_path, spec["base"], [])
    rng = np.random.default_rng(spec["seed"])
    states = []
    for _ in range(n_states):
        st = random_state(su, rng)
        Y = regressor(su, st)
        states.append({
            "base_position": exact(st["p"]),
            "base_orientation_xyzw": exact(st["quat"]),
            "joint_positions": exact(st["s"]),
            "base_velocity_mixed": exact(st["v_mixed"]),
            "joint_velocities": exact(st["s_dot"]),
            "nu_dot_mixed": exact(st["nu_dot"]),
            "regressor": [rnd(row) for row in Y],
        })
    nl = su.model.getNrOfLinks()
    return {
        "model": name,
        "urdf": spec.get("urdf") and os.path.relpath(spec["urdf"], ROOT),
        "icub_model": spec.get("icub"),
        "generator": {
            "script": "tools/reference/generate_regressor_fixtures.py",
            "idyntree": "15.1.0",
            "icub_models": "3.2.0",
            "seed": spec["seed"],
            "method": "KinDynComputations::inverseDynamicsInertialParametersRegressor (mixed), checked against inverseDynamics",
        },
        "conventions": {
            "nu": "[6 base (mixed: d/dt p_B, omega, world); joints in joint_names order]",
            "rows": "[base wrench dual to the mixed base velocity (6); joint torques in joint_names order]",
            "columns": "10 per link in link_names order: [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz], link frame, I about the link origin",
            "quaternion": "xyzw",
            "digits": DIGITS,
        },
        "gravity": rnd(GRAVITY),
        "base_link": su.base,
        "joint_names": su.joint_names,
        "link_names": [su.model.getLinkName(k) for k in range(nl)],
        "parameters": rnd(parameters(su)),
        "states": states,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--states", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "crates", "model", "tests", "fixtures"))
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    args = ap.parse_args()
    for name in args.models:
        spec = MODELS[name]
        if "urdf" in spec:
            path = spec["urdf"]
        else:
            if icub_models is None:
                sys.exit("icub-models is not installed (pip install -r tools/reference/requirements.txt)")
            path = os.path.join(icub_models.get_models_path(), spec["icub"], "model.urdf")
        fixture = generate(name, spec, path, args.states)
        out = os.path.join(args.out, "regressor_" + name + ".json")
        with open(out, "w") as f:
            json.dump(fixture, f, separators=(",", ":"))
            f.write("\n")
        print("%s: %d states, %d links -> %s" % (name, len(fixture["states"]), len(fixture["link_names"]),
                                                 os.path.relpath(out, ROOT)))


if __name__ == "__main__":
    main()
