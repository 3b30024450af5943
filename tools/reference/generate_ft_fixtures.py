#!/usr/bin/env python3
"""Generate the force/torque-sensor reference fixtures of stride-model from iDynTree.

For the bundled `models/stride_humanoid.urdf` and the official iCubGazeboV2_7 (icub-models), at seeded random
states (base pose and velocity, joint positions and velocities), generalized accelerations nu_dot (mixed
representation) and known external wrenches on l_sole and r_sole, this script computes what every six-axis
FT sensor measures, with iDynTree 15.1.0 on the UN-LUMPED model (iDynTree keeps every massive link joined by a
fixed joint, so each FT sensor's fixed joint is a joint of its model):

  1. KinDynComputations::inverseDynamicsWithInternalJointForceTorques (mixed representation) gives, per link L,
     f_{lambda(L),L}: the wrench the parent link applies on L, about L's origin, world orientation
     ([Traversaro 2017, eq. 4.17]; iDynTree's own unit test checks it against that equation).
  2. Each sensor's reading follows iDynTree's SixAxisForceTorqueSensor definition: the wrench applied ON the
     sensor's `appliedWrenchLink` by the other link of the joint (parent link for `child_to_parent`), expressed
     in the sensor frame (`getLinkSensorTransform`) about its origin [Traversaro 2017, eq. 4.1].

ExtWrenchesAndJointTorquesEstimator::computeExpectedFTSensorsMeasurements is NOT used: it estimates the
contact wrenches itself (least squares over the given unknowns), while these fixtures need arbitrary known
external wrenches. The link wrench convention is pinned by a check: inverse dynamics with the external
wrenches passed as link wrenches must equal inverse dynamics minus J^T w (the frames' mixed Jacobians), to
1e-10; the script aborts otherwise. Which link of the sensor's joint is the child is read from the
traversal from the floating base (the URDF root).

Conventions (also in each file under "conventions"): 6D vectors [linear; angular]; quaternion xyzw; the
joint-space order is "joint_names"; nu = [base (mixed: d/dt p_B, omega, world); joints]; external wrenches
[force; torque] act ON the robot at the frame origin, world orientation; gravity [0, 0, -9.81]; inputs are
written with all 17 digits, readings rounded to 12 significant digits.

Usage: python3 tools/reference/generate_ft_fixtures.py [--states N] [--out DIR] [--models ...]
Requires the pinned packages of tools/reference/requirements.txt (a venv:
  python3 -m venv ~/.cache/stride/reference-venv && ~/.cache/stride/reference-venv/bin/pip install -r tools/reference/requirements.txt).
"""

import argparse
import json
import os
import sys

import numpy as np
import idyntree.bindings as idt

# One definition of the fixtures' rounding and agreement checks: the dynamics fixtures' generator.
from generate_fixtures import AGREEMENT_TOL, DIGITS, check, exact, rnd, skew  # noqa: E402

try:
    import icub_models
except ImportError:  # pragma: no cover
    icub_models = None

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
GRAVITY = np.array([0.0, 0.0, -9.81])

MODELS = {
    "stride_humanoid": {
        "urdf": os.path.join(ROOT, "models", "stride_humanoid.urdf"),
        "base": "root_link",
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 20261202,
    },
    "iCubGazeboV2_7": {
        "icub": "iCubGazeboV2_7",
        "base": "root_link",
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 7,
    },
}


def shift_wrench(w, from_p, to_p):
    """A wrench about point from_p, re-expressed about to_p (same orientation)."""
    f = w[:3]
    return np.concatenate([f, w[3:] + np.cross(from_p - to_p, f)])


class Setup:
    def __init__(self, urdf_path, base, wrench_frames):
        loader = idt.ModelLoader()
        if not loader.loadModelFromFile(urdf_path):
            raise RuntimeError("iDynTree cannot load %s" % urdf_path)
        self.loader = loader  # keeps the sensors alive
        self.model = loader.model().copy()
        self.sensors = loader.sensors()
        self.kd = idt.KinDynComputations()
        assert self.kd.loadRobotModel(self.model)
        assert self.kd.setFloatingBase(base)
        assert self.kd.setFrameVelocityRepresentation(idt.MIXED_REPRESENTATION)
        self.base = base
        self.n = self.kd.getNrOfDegreesOfFreedom()
        self.nv = self.n + 6
        self.joint_names = [self.model.getJointName(self.dof_joint(i)) for i in range(self.n)]
        self.wrench_frames = wrench_frames
        count = self.sensors.getNrOfSensors(idt.SIX_AXIS_FORCE_TORQUE)
        self.ft = [self.sensors.getSixAxisForceTorqueSensor(i) for i in range(count)]
        # joint limits for the random states
        lo, hi = [], []
        for name in self.joint_names:
            j = self.model.getJoint(self.model.getJointIndex(name))
            if j.hasPosLimits():
                lo.append(j.getMinPosLimit(0))
                hi.append(j.getMaxPosLimit(0))
            else:
                lo.append(-np.pi)
                hi.append(np.pi)
        self.lo, self.hi = np.array(lo), np.array(hi)

    def dof_joint(self, dof):
        m = self.model
        for j in range(m.getNrOfJoints()):
            jt = m.getJoint(j)
            if jt.getNrOfDOFs() == 1 and jt.getDOFsOffset() == dof:
                return j
        raise RuntimeError("no joint for DOF %d" % dof)

    def pose(self, name):
        T = self.kd.getWorldTransform(name)
        return T.getRotation().toNumPy().copy(), T.getPosition().toNumPy().copy()

    def link_pose(self, index):
        return self.pose(self.model.getLinkName(index))

    def frame_link(self, frame):
        idx = self.model.getFrameIndex(frame)
        assert idx >= 0, frame
        return self.model.getFrameLink(idx) if idx >= self.model.getNrOfLinks() else idx


def random_state(su, rng):
    n = su.n
    s = su.lo + (su.hi - su.lo) * rng.uniform(0.0, 1.0, n)
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)  # xyzw
    if quat[3] < 0:
        quat = -quat
    p = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(0.3, 1.0)])
    x, y, z, w = quat
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    v_mixed = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-1.0, 1.0, 3)])
    s_dot = rng.uniform(-2.0, 2.0, n)
    nu_dot = np.concatenate([rng.uniform(-3.0, 3.0, 6), rng.uniform(-5.0, 5.0, n)])
    wrenches = []
    for f in su.wrench_frames:
        w = np.concatenate([rng.normal(0.0, 60.0, 3) + np.array([0.0, 0.0, 120.0]), rng.normal(0.0, 8.0, 3)])
        wrenches.append((f, w))
    return dict(p=p, R=R, quat=quat, s=s, v_mixed=v_mixed, s_dot=s_dot, nu_dot=nu_dot, wrenches=wrenches)


def ft_readings(su, st):
    """The FT readings for one state, with the two consistency checks of the doc string."""
    kd, model = su.kd, su.model
    H = idt.Transform(idt.Rotation.FromPython(st["R"]), idt.Position.FromPython(st["p"]))
    assert kd.setRobotState(H, idt.VectorDynSize.FromPython(st["s"]), idt.Twist.FromPython(st["v_mixed"]),
                            idt.VectorDynSize.FromPython(st["s_dot"]), idt.Vector3.FromPython(GRAVITY))
    nl = model.getNrOfLinks()
    # external wrenches as link wrenches: mixed representation = about the link origin, world orientation
    ext = idt.LinkWrenches(model)
    ext.zero()
    ext_np = np.zeros((nl, 6))
    for f, w in st["wrenches"]:
        link = su.frame_link(f)
        _, pf = su.pose(f)
        _, pl = su.link_pose(link)
        ext_np[link] += shift_wrench(w, pf, pl)
    for link in range(nl):
        ext[link] = idt.Wrench.FromPython(ext_np[link])
    base_acc = idt.Vector6.FromPython(st["nu_dot"][:6])
    s_ddot = idt.VectorDynSize.FromPython(st["nu_dot"][6:])
    gt = idt.FreeFloatingGeneralizedTorques(model)
    internal = idt.LinkWrenches(model)
    assert kd.inverseDynamicsWithInternalJointForceTorques(base_acc, s_ddot, ext, gt, internal)
    with_links = np.concatenate([gt.baseWrench().toNumPy(), gt.jointTorques().toNumPy()])
    # check 1: the link wrench convention, against inverse dynamics minus J^T w
    zero = idt.LinkWrenches(model)
    zero.zero()
    gt0 = idt.FreeFloatingGeneralizedTorques(model)
    assert kd.inverseDynamics(base_acc, s_ddot, zero, gt0)
    ref = np.concatenate([gt0.baseWrench().toNumPy(), gt0.jointTorques().toNumPy()])
    for f, w in st["wrenches"]:
        J = idt.MatrixDynSize(6, su.nv)
        assert kd.getFrameFreeFloatingJacobian(f, J)
        ref -= J.toNumPy().T @ w
    check("external link wrenches vs J^T w", with_links, ref)
    f_parent = np.array([internal[link].toNumPy() for link in range(nl)])  # f_{lambda(L),L}, L[A]
    readings = []
    for sensor in su.ft:
        joint = model.getJoint(sensor.getParentJointIndex())
        a, b = joint.getFirstAttachedLink(), joint.getSecondAttachedLink()
        # the child (in the traversal from the base) of the sensor's joint
        child = b if model.getLinkName(b) in child_links(su, a) else a
        parent = a if child == b else b
        _, pc = su.link_pose(child)
        w_parent_on_child = f_parent[child]  # about the child origin, world orientation
        applied = sensor.getAppliedWrenchLink()
        # the wrench applied ON `applied` by the other link
        w = w_parent_on_child if applied == child else -w_parent_on_child
        assert applied in (child, parent)
        child_H_sensor = idt.Transform()
        assert sensor.getLinkSensorTransform(child, child_H_sensor)
        X = child_H_sensor.asHomogeneousTransform().toNumPy()
        Rc, _ = su.link_pose(child)
        Rs = Rc @ X[:3, :3]
        ps = pc + Rc @ X[:3, 3]
        w_s = shift_wrench(w, pc, ps)
        readings.append(np.concatenate([Rs.T @ w_s[:3], Rs.T @ w_s[3:]]))
    return readings


_CHILDREN = {}


def child_links(su, link):
    """Names of the links in the subtree of `link` (traversal from the base), including it."""
    key = (id(su), link)
    if key not in _CHILDREN:
        tr = idt.Traversal()
        assert su.model.computeFullTreeTraversal(tr, su.model.getLinkIndex(su.base))
        names = set()
        for k in range(tr.getNrOfVisitedLinks()):
            lk = tr.getLink(k).getIndex()
            x = lk
            while x >= 0:
                if x == link:
                    names.add(su.model.getLinkName(lk))
                    break
                par = tr.getParentLinkFromLinkIndex(x)
                x = par.getIndex() if par is not None else -1
        _CHILDREN[key] = names
    return _CHILDREN[key]


def generate(name, spec, urdf_path, n_states):
    su = Setup(urdf_path, spec["base"], spec["wrench_frames"])
    rng = np.random.default_rng(spec["seed"])
    states = []
    for _ in range(n_states):
        st = random_state(su, rng)
        readings = ft_readings(su, st)
        states.append({
            "base_position": exact(st["p"]),
            "base_orientation_xyzw": exact(st["quat"]),
            "joint_positions": exact(st["s"]),
            "base_velocity_mixed": exact(st["v_mixed"]),
            "joint_velocities": exact(st["s_dot"]),
            "nu_dot_mixed": exact(st["nu_dot"]),
            "external_wrenches": [{"frame": f, "wrench": exact(w)} for f, w in st["wrenches"]],
            "ft_readings": [rnd(r) for r in readings],
        })
    return {
        "model": name,
        "urdf": spec.get("urdf") and os.path.relpath(spec["urdf"], ROOT),
        "icub_model": spec.get("icub"),
        "generator": {
            "script": "tools/reference/generate_ft_fixtures.py",
            "idyntree": "15.1.0",
            "icub_models": "3.2.0",
            "seed": spec["seed"],
            "method": "KinDynComputations::inverseDynamicsWithInternalJointForceTorques on the un-lumped model + SixAxisForceTorqueSensor applied-wrench link and sensor frame",
        },
        "conventions": {
            "vectors_6d": "[linear; angular]",
            "quaternion": "xyzw",
            "nu": "[6 base (mixed: d/dt p_B, omega, world); joints in joint_names order]",
            "external_wrench": "[force; torque] applied on the robot at the frame, torque about the frame origin, world orientation",
            "ft_reading": "[force; torque] in the sensor frame about its origin: the wrench applied on the sensor's applied-wrench link (parent link for child_to_parent) by the other link",
        },
        "gravity": rnd(GRAVITY),
        "base_link": su.base,
        "joint_names": su.joint_names,
        "ft_sensors": [s.getName() for s in su.ft],
        "ft_applied_wrench_link": [su.model.getLinkName(s.getAppliedWrenchLink()) for s in su.ft],
        "states": states,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--states", type=int, default=10)
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
        out = os.path.join(args.out, "ft_" + name + ".json")
        with open(out, "w") as f:
            json.dump(fixture, f, separators=(",", ":"))
            f.write("\n")
        print("%s: %d states, %d FT sensors -> %s" % (name, len(fixture["states"]), len(fixture["ft_sensors"]),
                                                      os.path.relpath(out, ROOT)))


if __name__ == "__main__":
    main()
