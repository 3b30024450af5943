#!/usr/bin/env python3
"""Generate the reference fixtures of stride-model from iDynTree and Pinocchio.

For each model (the bundled `models/stride_humanoid.urdf` and official iCub URDFs of the `icub-models`
package) and for seeded random states, this script computes with iDynTree (KinDynComputations, in the
mixed, body and inertial representations) and with Pinocchio (free-flyer, LOCAL frames, CRBA/RNEA/ABA):

  mass matrix M, bias forces h = C nu + G, gravity forces G, frame poses, frame Jacobians, frame bias
  accelerations (J_dot nu), frame velocities, CoM position / velocity / Jacobian / bias acceleration,
  centroidal momentum, centroidal momentum matrix (CMM) and its bias (d/dt CMM) nu, inverse dynamics with
  external wrenches, forward dynamics (ABA) with external wrenches,

checks that the two libraries agree (<= 1e-10 relative to each quantity's scale; the script aborts
otherwise) and writes compact JSON fixtures to crates/model/tests/fixtures/<model>.json.

Which library's numbers are written:  mixed and inertial -> iDynTree; body -> Pinocchio;
forward dynamics (every representation) -> Pinocchio ABA, converted to the representation;
centroidal momentum bias -> Pinocchio (iDynTree has no such function; cross-checked against the
Newton-Euler identity d/dt(h_G) = m g + base wrench of h, moved to the CoM).

Conventions of the fixture (also written into each file under "conventions"):
  * 6D vectors are [linear; angular]; quaternions are [x, y, z, w]; matrices are lists of rows; the
    symmetric mass matrix is stored as its upper triangle "mass_matrix_upper" (row r holds columns r..nv-1).
  * "joint_names" gives the order of every joint-space vector and of the joint columns of every matrix;
    the columns/rows of a nu-sized quantity are [6 base; joints in joint_names order].
  * base_velocity[rep] is the same physical motion written in each representation:
      mixed    = [d/dt p_B (world); omega (world)]
      body     = [R^T d/dt p_B; R^T omega]
      inertial = [d/dt p_B - omega x p_B; omega]   (velocity of the point at the world origin)
    where (p_B, R) is world_H_base of the root link `base_link` of the fixture.
  * nu_dot is ONE random vector, used as the generalized acceleration of each representation (so the
    inverse-dynamics results of different representations are different motions).
  * A frame's velocity/Jacobian/bias acceleration in representation rep: mixed = [d/dt p_F; omega] (world),
    body = frame's body twist, inertial = [d/dt p_F - omega x p_F; omega].
  * External wrenches are [force; torque] applied ON the robot at a frame, torque about the frame's
    origin, both in world orientation (iDynTree's mixed representation of the frame).
  * Generalized forces (h, G, inverse dynamics) have the base part dual to the base velocity of the
    representation.
  * Centroidal momentum [linear; angular about the CoM] in world orientation (G[A]) in every representation;
    its matrix maps nu of the representation to it (iDynTree's body representation would give G[B]).
  * Gravity [0, 0, -9.81].
  * The inputs of a state (pose, velocities, nu_dot, torques, wrenches) are written with all 17 digits, so the
    references are exact for them; the outputs are rounded to DIGITS significant digits.

Usage: python3 tools/reference/generate_fixtures.py [--states N] [--full-states K] [--out DIR]
Requires the pinned packages of tools/reference/requirements.txt.
"""

import argparse
import json
import os
import sys

import numpy as np
import pinocchio as pin
import idyntree.bindings as idt

try:
    import icub_models
except ImportError:  # pragma: no cover
    icub_models = None

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
GRAVITY = np.array([0.0, 0.0, -9.81])
AGREEMENT_TOL = 1e-10
DIGITS = 12  # significant digits of the outputs (rounding error <= 5e-12 relative, 200x below the 1e-9 test tolerance)

# model name -> (how to find the URDF, frames with full kinematics, frames for external wrenches)
MODELS = {
    "stride_humanoid": {
        "urdf": os.path.join(ROOT, "models", "stride_humanoid.urdf"),
        "frames": ["l_sole", "r_sole", "l_hand", "l_hand_palm"],
        "pose_frames": ["r_hand", "imu_frame", "head_imu", "l_foot_ft_sensor", "r_leg_ft_sensor", "chest"],
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 20261121,
    },
    "iCubGazeboV2_7": {
        "icub": "iCubGazeboV2_7",
        "frames": ["l_sole", "r_sole", "r_hand", "l_hand_dh_frame"],
        "pose_frames": ["l_hand", "head", "chest", "l_foot", "r_upper_leg"],
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 27,
    },
    "iCubGenova04": {
        "icub": "iCubGenova04",
        "frames": ["l_sole", "r_sole", "l_hand", "r_hand_dh_frame"],
        "pose_frames": ["r_hand", "head", "chest", "l_foot", "r_upper_leg"],
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 4,
    },
    # an older-generation URDF: massless URDF root `base_link`, <texture/> tags, point-mass links, and a mass
    # matrix with condition number ~1e10: forward dynamics is ill-posed there at 1e-9, so its fixture has no
    # forward_dynamics (the Rust test checks the residual of the equations of motion instead).
    "iCubLisboa01": {
        "icub": "iCubLisboa01",
        "forward_dynamics": False,
        "states": 10,
        "frames": ["l_sole", "r_sole", "l_hand", "r_hand_dh_frame"],
        "pose_frames": ["r_hand", "head", "chest", "root_link", "l_foot"],
        "wrench_frames": ["l_sole", "r_sole"],
        "seed": 1,
    },
}

REPS = {
    "mixed": idt.MIXED_REPRESENTATION,
    "body": idt.BODY_FIXED_REPRESENTATION,
    "inertial": idt.INERTIAL_FIXED_REPRESENTATION,
}


# --------------------------------------------------------------------------------------------- helpers
def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def blockdiag(a, b):
    out = np.zeros((a.shape[0] + b.shape[0], a.shape[1] + b.shape[1]))
    out[: a.shape[0], : a.shape[1]] = a
    out[a.shape[0]:, a.shape[1]:] = b
    return out


def base_T(rep, R, p, omega_b, v_b):
    """T and dT/dt with nu_body_base = T nu_rep_base (6x6), for the base pose (R, p) and body twist."""
    Rt = R.T
    dRt = -skew(omega_b) @ Rt
    if rep == "body":
        return np.eye(6), np.zeros((6, 6))
    if rep == "mixed":
        return blockdiag(Rt, Rt), blockdiag(dRt, dRt)
    if rep == "inertial":
        pdot = R @ v_b
        T = np.zeros((6, 6))
        T[:3, :3] = Rt
        T[:3, 3:] = -Rt @ skew(p)
        T[3:, 3:] = Rt
        dT = np.zeros((6, 6))
        dT[:3, :3] = dRt
        dT[:3, 3:] = -dRt @ skew(p) - Rt @ skew(pdot)
        dT[3:, 3:] = dRt
        return T, dT
    raise ValueError(rep)


def frame_S(rep, R, p, omega_b, v_b):
    """S and dS/dt with v_rep_frame = S v_body_frame, for a frame with pose (R, p) and body twist."""
    dR = R @ skew(omega_b)
    if rep == "body":
        return np.eye(6), np.zeros((6, 6))
    if rep == "mixed":
        return blockdiag(R, R), blockdiag(dR, dR)
    if rep == "inertial":
        pdot = R @ v_b
        S = np.zeros((6, 6))
        S[:3, :3] = R
        S[:3, 3:] = skew(p) @ R
        S[3:, 3:] = R
        dS = np.zeros((6, 6))
        dS[:3, :3] = dR
        dS[:3, 3:] = skew(pdot) @ R + skew(p) @ dR
        dS[3:, 3:] = dR
        return S, dS
    raise ValueError(rep)


def full(Tb, n):
    return blockdiag(Tb, np.eye(n))


def rnd(x):
    """Round to DIGITS significant digits (JSON size)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        v = float("%.*g" % (DIGITS, float(a)))
        return 0 if v == 0.0 else v
    return [rnd(v) for v in a]


def exact(x):
    """Inputs are written with every digit (shortest round-trip repr), so the references are exact for them."""
    return [float(v) for v in np.asarray(x, dtype=float)]


def check(name, a, b, tol=AGREEMENT_TOL):
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    scale = max(1.0, float(np.max(np.abs(b))) if b.size else 1.0)
    err = float(np.max(np.abs(a - b))) if a.size else 0.0
    if not err <= tol * scale:
        raise AssertionError("%s: Pinocchio and iDynTree disagree by %.3e (scale %.3e)" % (name, err, scale))
    return err / scale


def quat_xyzw(R):
    q = pin.Quaternion(R)
    return np.array([q.x, q.y, q.z, q.w])


# --------------------------------------------------------------------------------------------- models
class Models:
    def __init__(self, urdf_path, frames, pose_frames, wrench_frames):
        self.urdf_path = urdf_path
        self.pin_model = pin.buildModelFromUrdf(urdf_path, pin.JointModelFreeFlyer())
        self.pin_data = self.pin_model.createData()
        # the URDF root link is the floating base (Pinocchio attaches the free flyer to it)
        self.base = self.pin_model.frames[2].name if self.pin_model.frames[1].name == "root_joint" else None
        assert self.base is not None
        loader = idt.ModelLoader()
        if not loader.loadModelFromFile(urdf_path):
            raise RuntimeError("iDynTree cannot load %s" % urdf_path)
        self.idt_model = loader.model().copy()
        self.kd = idt.KinDynComputations()
        assert self.kd.loadRobotModel(self.idt_model)
        if self.idt_model.getLinkIndex(self.base) >= 0:
            assert self.kd.setFloatingBase(self.base)
        else:
            # iDynTree turns a massless URDF root link attached by a fixed joint into an additional frame of
            # its child (e.g. iCubLisboa01's base_link); use that link if the frame coincides with it.
            fidx = self.idt_model.getFrameIndex(self.base)
            assert fidx >= 0, "iDynTree: no link or frame %s" % self.base
            link = self.idt_model.getFrameLink(fidx)
            X = self.idt_model.getFrameTransform(fidx).asHomogeneousTransform().toNumPy()
            assert np.allclose(X, np.eye(4), atol=1e-15), "base frame %s is not its link's frame" % self.base
            assert self.kd.setFloatingBase(self.idt_model.getLinkName(link))
        self.n = self.kd.getNrOfDegreesOfFreedom()
        self.nv = self.n + 6
        assert self.pin_model.nv == self.nv, (self.pin_model.nv, self.nv)
        # joint order of iDynTree = the fixture's joint order
        self.joint_names = [self.idt_model.getJointName(self.dof_joint(i)) for i in range(self.n)]
        # Pinocchio index (in q and v) of each fixture joint
        self.pin_q_idx = []
        self.pin_v_idx = []
        for name in self.joint_names:
            jid = self.pin_model.getJointId(name)
            assert jid < self.pin_model.njoints, name
            assert self.pin_model.joints[jid].nq == 1, name
            self.pin_q_idx.append(self.pin_model.joints[jid].idx_q)
            self.pin_v_idx.append(self.pin_model.joints[jid].idx_v)
        self.pin_q_idx = np.array(self.pin_q_idx)
        self.pin_v_idx = np.array(self.pin_v_idx)
        # permutation: fixture nu index -> pinocchio v index
        self.perm = np.concatenate([np.arange(6), self.pin_v_idx])
        self.frames = frames
        self.pose_frames = pose_frames
        self.wrench_frames = wrench_frames
        for f in frames + pose_frames + wrench_frames + [self.base]:
            assert self.pin_model.existFrame(f), "Pinocchio: no frame %s" % f
            assert self.kd.getFrameIndex(f) >= 0, "iDynTree: no frame %s" % f
        sensors = loader.sensors()
        count = sensors.getNrOfSensors(idt.SIX_AXIS_FORCE_TORQUE)
        self.ft_sensors = [sensors.getSixAxisForceTorqueSensor(i).getName() for i in range(count)]
        self.ft_sensor_joints = [sensors.getSixAxisForceTorqueSensor(i).getParentJoint() for i in range(count)]

    def dof_joint(self, dof):
        m = self.idt_model
        for j in range(m.getNrOfJoints()):
            jt = m.getJoint(j)
            if jt.getNrOfDOFs() == 1 and jt.getDOFsOffset() == dof:
                return j
        raise RuntimeError("no joint for DOF %d" % dof)

    def limits(self):
        lo = self.pin_model.lowerPositionLimit[self.pin_q_idx]
        hi = self.pin_model.upperPositionLimit[self.pin_q_idx]
        return lo, hi

    # permutations between fixture order and Pinocchio order
    def to_pin_v(self, x):
        out = np.zeros(self.nv)
        out[self.perm] = x
        return out

    def from_pin_v(self, x):
        return np.asarray(x)[self.perm]

    def from_pin_mat_cols(self, A):
        return np.asarray(A)[:, self.perm]

    def from_pin_mat(self, A):
        return np.asarray(A)[np.ix_(self.perm, self.perm)]


# --------------------------------------------------------------------------------------------- state
def random_state(models, rng):
    n = models.n
    lo, hi = models.limits()
    lo = np.where(np.isfinite(lo) & (lo > -1e10), lo, -np.pi)
    hi = np.where(np.isfinite(hi) & (hi < 1e10), hi, np.pi)
    s = lo + (hi - lo) * rng.uniform(0.0, 1.0, n)
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)  # xyzw
    if quat[3] < 0:
        quat = -quat
    p = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(0.3, 1.0)])
    R = pin.Quaternion(quat[3], quat[0], quat[1], quat[2]).toRotationMatrix()
    v_mixed = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-1.0, 1.0, 3)])
    s_dot = rng.uniform(-2.0, 2.0, n)
    nu_dot = np.concatenate([rng.uniform(-3.0, 3.0, 6), rng.uniform(-5.0, 5.0, n)])
    effort = models.pin_model.effortLimit[models.pin_v_idx]
    effort = np.where(np.isfinite(effort) & (effort > 0.0), np.minimum(effort, 100.0), 10.0)
    tau = 0.5 * effort * rng.uniform(-1.0, 1.0, n)
    wrenches = []
    for f in models.wrench_frames:
        w = np.concatenate([rng.normal(0.0, 60.0, 3) + np.array([0.0, 0.0, 120.0]), rng.normal(0.0, 8.0, 3)])
        wrenches.append((f, w))
    return dict(p=p, R=R, quat=quat, s=s, v_mixed=v_mixed, s_dot=s_dot, nu_dot=nu_dot, tau=tau, wrenches=wrenches)


def base_velocities(st):
    """The same base motion in the three representations."""
    R, p, vm = st["R"], st["p"], st["v_mixed"]
    pdot, omega = vm[:3], vm[3:]
    return {
        "mixed": vm.copy(),
        "body": np.concatenate([R.T @ pdot, R.T @ omega]),
        "inertial": np.concatenate([pdot - np.cross(omega, p), omega]),
    }


# --------------------------------------------------------------------------------------------- iDynTree
def idt_compute(models, st, rep, base_vel):
    kd = models.kd
    n, nv = models.n, models.nv
    assert kd.setFrameVelocityRepresentation(REPS[rep])
    H = idt.Transform(idt.Rotation.FromPython(st["R"]), idt.Position.FromPython(st["p"]))
    ok = kd.setRobotState(
        H,
        idt.VectorDynSize.FromPython(st["s"]),
        idt.Twist.FromPython(base_vel),
        idt.VectorDynSize.FromPython(st["s_dot"]),
        idt.Vector3.FromPython(GRAVITY),
    )
    assert ok
    out = {}
    M = idt.MatrixDynSize(nv, nv)
    assert kd.getFreeFloatingMassMatrix(M)
    out["mass_matrix"] = M.toNumPy().copy()
    gt = idt.FreeFloatingGeneralizedTorques(kd.model())
    assert kd.generalizedBiasForces(gt)
    out["bias_forces"] = np.concatenate([gt.baseWrench().toNumPy(), gt.jointTorques().toNumPy()])
    assert kd.generalizedGravityForces(gt)
    out["gravity_forces"] = np.concatenate([gt.baseWrench().toNumPy(), gt.jointTorques().toNumPy()])
    frames = {}
    for f in models.frames + models.wrench_frames:
        J = idt.MatrixDynSize(6, nv)
        assert kd.getFrameFreeFloatingJacobian(f, J)
        T = kd.getWorldTransform(f)
        frames[f] = {
            "jacobian": J.toNumPy().copy(),
            "bias_acceleration": kd.getFrameBiasAcc(f).toNumPy().copy(),
            "velocity": kd.getFrameVel(f).toNumPy().copy(),
            "R": T.getRotation().toNumPy().copy(),
            "p": T.getPosition().toNumPy().copy(),
        }
    out["frames"] = frames
    poses = {}
    for f in models.pose_frames + models.frames:
        T = kd.getWorldTransform(f)
        poses[f] = (T.getRotation().toNumPy().copy(), T.getPosition().toNumPy().copy())
    out["poses"] = poses
    out["com_position"] = kd.getCenterOfMassPosition().toNumPy().copy()
    out["com_velocity"] = kd.getCenterOfMassVelocity().toNumPy().copy()
    Jc = idt.MatrixDynSize(3, nv)
    assert kd.getCenterOfMassJacobian(Jc)
    out["com_jacobian"] = Jc.toNumPy().copy()
    out["com_bias_acceleration"] = kd.getCenterOfMassBiasAcc().toNumPy().copy()
    out["centroidal_momentum"] = kd.getCentroidalTotalMomentum().toNumPy().copy()
    A = idt.MatrixDynSize(6, nv)
    assert kd.getCentroidalTotalMomentumJacobian(A)
    out["centroidal_momentum_matrix"] = A.toNumPy().copy()
    # inverse dynamics without external wrenches; the wrenches are added through the frames' mixed Jacobians
    base_acc = idt.Vector6.FromPython(st["nu_dot"][:6])
    s_ddot = idt.VectorDynSize.FromPython(st["nu_dot"][6:])
    ext = idt.LinkWrenches(kd.model())
    ext.zero()
    assert kd.inverseDynamics(base_acc, s_ddot, ext, gt)
    tau_id = np.concatenate([gt.baseWrench().toNumPy(), gt.jointTorques().toNumPy()])
    for f, w in st["wrenches"]:
        fr = frames[f]
        S_rep, _ = frame_S(rep, fr["R"], fr["p"], np.zeros(3), np.zeros(3))
        S_mixed, _ = frame_S("mixed", fr["R"], fr["p"], np.zeros(3), np.zeros(3))
        J_mixed_frame = S_mixed @ np.linalg.solve(S_rep, fr["jacobian"])
        tau_id -= J_mixed_frame.T @ w
    out["inverse_dynamics"] = tau_id
    # forward dynamics from M and h (a second method next to Pinocchio's ABA)
    rhs = -out["bias_forces"].copy()
    rhs[6:] += st["tau"]
    for f, w in st["wrenches"]:
        fr = frames[f]
        S_rep, _ = frame_S(rep, fr["R"], fr["p"], np.zeros(3), np.zeros(3))
        S_mixed, _ = frame_S("mixed", fr["R"], fr["p"], np.zeros(3), np.zeros(3))
        rhs += (S_mixed @ np.linalg.solve(S_rep, fr["jacobian"])).T @ w
    out["forward_dynamics"] = np.linalg.solve(out["mass_matrix"], rhs)
    return out


# --------------------------------------------------------------------------------------------- Pinocchio
def pin_compute(models, st, rep):
    m, d = models.pin_model, models.pin_data
    n, nv = models.n, models.nv
    R, p = st["R"], st["p"]
    vb = base_velocities(st)
    v_rep_base = vb[rep]
    v_body_base = vb["body"]
    q = pin.neutral(m)
    q[:3] = p
    q[3:7] = st["quat"]
    q[models.pin_q_idx] = st["s"]
    Tb, dTb = base_T(rep, R, p, v_body_base[3:], v_body_base[:3])
    assert np.allclose(Tb @ v_rep_base, v_body_base, atol=1e-12)
    T = full(Tb, n)
    dT = full(dTb, n)
    dT[6:, 6:] = 0.0
    nu_rep = np.concatenate([v_rep_base, st["s_dot"]])
    v = models.to_pin_v(T @ nu_rep)
    a_bias = models.to_pin_v(dT @ nu_rep)  # body acceleration when the rep acceleration is zero
    out = {}
    M_b = models.from_pin_mat(pin.crba(m, d, q))
    M_b = np.triu(M_b) + np.triu(M_b, 1).T
    out["mass_matrix"] = T.T @ M_b @ T
    h_b = models.from_pin_v(pin.rnea(m, d, q, v, a_bias))
    out["bias_forces"] = T.T @ h_b
    G_b = models.from_pin_v(pin.computeGeneralizedGravity(m, d, q))
    out["gravity_forces"] = T.T @ G_b
    # kinematics with the bias acceleration
    pin.forwardKinematics(m, d, q, v, a_bias)
    pin.updateFramePlacements(m, d)
    pin.computeJointJacobians(m, d, q)
    frames = {}
    for f in models.frames + models.wrench_frames:
        fid = m.getFrameId(f)
        oMf = d.oMf[fid]
        J_local = models.from_pin_mat_cols(pin.getFrameJacobian(m, d, fid, pin.ReferenceFrame.LOCAL))
        v_local = pin.getFrameVelocity(m, d, fid, pin.ReferenceFrame.LOCAL).vector
        a_local = pin.getFrameAcceleration(m, d, fid, pin.ReferenceFrame.LOCAL).vector
        S, dS = frame_S(rep, oMf.rotation, oMf.translation, v_local[3:], v_local[:3])
        frames[f] = {
            "jacobian": S @ J_local @ T,
            "bias_acceleration": dS @ v_local + S @ a_local,
            "velocity": S @ v_local,
            "R": oMf.rotation.copy(),
            "p": oMf.translation.copy(),
        }
    out["frames"] = frames
    out["poses"] = {f: (d.oMf[m.getFrameId(f)].rotation.copy(), d.oMf[m.getFrameId(f)].translation.copy())
                    for f in models.pose_frames + models.frames}
    pin.centerOfMass(m, d, q, v, a_bias)
    out["com_position"] = d.com[0].copy()
    out["com_velocity"] = d.vcom[0].copy()
    out["com_bias_acceleration"] = d.acom[0].copy()
    out["com_jacobian"] = models.from_pin_mat_cols(pin.jacobianCenterOfMass(m, d, q)) @ T
    Ag = models.from_pin_mat_cols(pin.computeCentroidalMap(m, d, q))
    out["centroidal_momentum_matrix"] = Ag @ T
    pin.computeCentroidalMomentumTimeVariation(m, d, q, v, a_bias)
    out["centroidal_momentum"] = d.hg.vector.copy()
    out["centroidal_momentum_bias"] = d.dhg.vector.copy()
    # external wrenches -> Pinocchio joint-local forces
    fext = [pin.Force.Zero() for _ in range(m.njoints)]
    for f, w in st["wrenches"]:
        fid = m.getFrameId(f)
        jid = m.frames[fid].parentJoint
        oMj = d.oMi[jid]
        pf = d.oMf[fid].translation
        force = w[:3]
        torque_j = w[3:] + np.cross(pf - oMj.translation, force)
        fext[jid] = fext[jid] + pin.Force(oMj.rotation.T @ force, oMj.rotation.T @ torque_j)
    a_id = models.to_pin_v(T @ st["nu_dot"] + dT @ nu_rep)
    tau_b = models.from_pin_v(pin.rnea(m, d, q, v, a_id, fext))
    out["inverse_dynamics"] = T.T @ tau_b
    tau_full = np.zeros(nv)
    tau_full[6:] = st["tau"]
    a_b = models.from_pin_v(pin.aba(m, d, q, v, models.to_pin_v(tau_full), fext))
    out["forward_dynamics"] = np.linalg.solve(T, a_b - dT @ nu_rep)
    return out


# --------------------------------------------------------------------------------------------- fixture
def generate(model_name, spec, urdf_path, n_states, n_full, errors):
    models = Models(urdf_path, spec["frames"], spec["pose_frames"], spec["wrench_frames"])
    rng = np.random.default_rng(spec["seed"])
    with_fd = spec.get("forward_dynamics", True)
    n_states = spec.get("states", n_states)
    states = []
    worst = {}

    def chk(label, a, b):
        e = check("%s %s" % (model_name, label), a, b)
        key = label.split(" ")[-1]
        worst[key] = max(worst.get(key, 0.0), e)

    for k in range(n_states):
        st = random_state(models, rng)
        bv = base_velocities(st)
        rec = {
            "base_position": exact(st["p"]),
            "base_orientation_xyzw": exact(st["quat"]),
            "joint_positions": exact(st["s"]),
            "base_velocity": {r: exact(bv[r]) for r in REPS},
            "joint_velocities": exact(st["s_dot"]),
            "nu_dot": exact(st["nu_dot"]),
            "joint_torques": exact(st["tau"]),
            "external_wrenches": [{"frame": f, "wrench": exact(w)} for f, w in st["wrenches"]],
        }
        reps_out = {}
        for rep in REPS:
            i = idt_compute(models, st, rep, bv[rep])
            pn = pin_compute(models, st, rep)
            tag = "state %d %s" % (k, rep)
            for key in ("mass_matrix", "bias_forces", "gravity_forces", "com_position", "com_velocity",
                        "com_jacobian", "com_bias_acceleration", "inverse_dynamics"):
                chk("%s %s" % (tag, key), i[key], pn[key])
            if with_fd:
                chk("%s forward_dynamics" % tag, i["forward_dynamics"], pn["forward_dynamics"])
            # iDynTree writes the centroidal momentum in G[B] (base orientation) in the body representation;
            # the stride contract (and Pinocchio) always use G[A] (world orientation).
            rot = blockdiag(st["R"].T, st["R"].T) if rep == "body" else np.eye(6)
            chk("%s centroidal_momentum" % tag, i["centroidal_momentum"], rot @ pn["centroidal_momentum"])
            chk("%s centroidal_momentum_matrix" % tag, i["centroidal_momentum_matrix"],
                rot @ pn["centroidal_momentum_matrix"])
            for f in i["frames"]:
                for key in ("jacobian", "bias_acceleration", "velocity", "R", "p"):
                    chk("%s %s %s" % (tag, f, key), i["frames"][f][key], pn["frames"][f][key])
            for f in i["poses"]:
                chk("%s %s pose_R" % (tag, f), i["poses"][f][0], pn["poses"][f][0])
                chk("%s %s pose_p" % (tag, f), i["poses"][f][1], pn["poses"][f][1])
            # the centroidal momentum bias: Newton-Euler with iDynTree's bias forces (mixed only)
            if rep == "mixed":
                mass = models.kd.model().getTotalMass()
                hb = i["bias_forces"][:6]
                c = i["com_position"]
                ref = np.concatenate([mass * GRAVITY + hb[:3], hb[3:] + np.cross(st["p"] - c, hb[:3])])
                chk("%s centroidal_momentum_bias" % tag, ref, pn["centroidal_momentum_bias"])
            # ν̇ from ABA must reproduce the applied torques through the inverse dynamics (both libraries)
            if k == 0:
                st2 = dict(st)
                st2["nu_dot"] = pn["forward_dynamics"]
                back = pin_compute(models, st2, rep)["inverse_dynamics"]
                target = np.concatenate([np.zeros(6), st["tau"]])
                # scale: the size of the terms M nu_dot that cancel (M may be ill-conditioned)
                scale = max(1.0, np.max(np.abs(pn["mass_matrix"])) * np.max(np.abs(pn["forward_dynamics"])))
                err = np.max(np.abs(back - target))
                assert err <= AGREEMENT_TOL * scale, ("%s %s roundtrip" % (model_name, tag), err, scale)
            if rep == "mixed" or k < n_full:
                src = {"mixed": i, "inertial": i, "body": pn}[rep]
                cmm = pn["centroidal_momentum_matrix"] if rep == "body" else i["centroidal_momentum_matrix"]
                reps_out[rep] = {
                    "mass_matrix_upper": [rnd(row[r:]) for r, row in enumerate(src["mass_matrix"])],
                    "bias_forces": rnd(src["bias_forces"]),
                    "gravity_forces": rnd(src["gravity_forces"]),
                    "frames": {
                        f: {
                            "jacobian": [rnd(row) for row in src["frames"][f]["jacobian"]],
                            "bias_acceleration": rnd(src["frames"][f]["bias_acceleration"]),
                            "velocity": rnd(src["frames"][f]["velocity"]),
                        }
                        for f in models.frames
                    },
                    "com_jacobian": [rnd(row) for row in src["com_jacobian"]],
                    "com_bias_acceleration": rnd(src["com_bias_acceleration"]),
                    "centroidal_momentum_matrix": [rnd(row) for row in cmm],
                    "centroidal_momentum_bias": rnd(pn["centroidal_momentum_bias"]),
                    "inverse_dynamics": rnd(src["inverse_dynamics"]),
                }
                if with_fd:
                    reps_out[rep]["forward_dynamics"] = rnd(pn["forward_dynamics"])
            if rep == "mixed":
                rec["poses"] = {
                    f: {"position": rnd(i["poses"][f][1]), "orientation_xyzw": rnd(quat_xyzw(i["poses"][f][0]))}
                    for f in models.pose_frames + models.frames
                }
                rec["com_position"] = rnd(i["com_position"])
                rec["com_velocity"] = rnd(i["com_velocity"])
                rec["centroidal_momentum"] = rnd(i["centroidal_momentum"])
        rec["representations"] = reps_out
        states.append(rec)
    errors[model_name] = worst
    fixture = {
        "model": model_name,
        "urdf": spec.get("urdf") and os.path.relpath(spec["urdf"], ROOT),
        "icub_model": spec.get("icub"),
        "generator": {
            "script": "tools/reference/generate_fixtures.py",
            "pinocchio": pin.__version__,
            "idyntree": idt.__version__ if hasattr(idt, "__version__") else "15.1.0",
            "icub_models": "3.2.0",
            "seed": spec["seed"],
            "max_relative_disagreement_pinocchio_idyntree": max(worst.values()),
        },
        "conventions": {
            "vectors_6d": "[linear; angular]",
            "quaternion": "xyzw",
            "matrices": "list of rows; mass_matrix_upper: row r holds columns r..nv-1 of the symmetric M",
            "nu": "[6 base; joints in joint_names order]",
            "external_wrench": "[force; torque] applied on the robot at the frame, torque about the frame origin, world orientation",
            "nu_dot": "the same numbers are used as the generalized acceleration of every representation",
            "references": "mixed, inertial: iDynTree 15.1.0; body: Pinocchio 4.1.0; forward_dynamics and centroidal_momentum_bias: Pinocchio 4.1.0 (ABA, converted)",
        },
        "gravity": rnd(GRAVITY),
        "base_link": models.base,
        "total_mass": rnd(models.kd.model().getTotalMass()),
        "joint_names": models.joint_names,
        "frames": models.frames,
        "pose_frames": models.pose_frames + models.frames,
        "ft_sensors": models.ft_sensors,
        "ft_sensor_joints": models.ft_sensor_joints,
        "states": states,
    }
    return fixture


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--states", type=int, default=20, help="random states per model (default 20)")
    ap.add_argument("--full-states", type=int, default=3,
                    help="states that also get the body and inertial representations (default 4)")
    ap.add_argument("--out", default=os.path.join(ROOT, "crates", "model", "tests", "fixtures"))
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    errors = {}
    for name in args.models:
        spec = MODELS[name]
        if "urdf" in spec:
            path = spec["urdf"]
        else:
            if icub_models is None:
                sys.exit("icub-models is not installed (pip install -r tools/reference/requirements.txt)")
            path = os.path.join(icub_models.get_models_path(), spec["icub"], "model.urdf")
        fixture = generate(name, spec, path, args.states, args.full_states, errors)
        out = os.path.join(args.out, name + ".json")
        with open(out, "w") as f:
            json.dump(fixture, f, separators=(",", ":"))
            f.write("\n")
        worst = max(errors[name].values())
        print("%s: %d states, %d joints -> %s (%d KB); max Pinocchio/iDynTree disagreement %.2e (relative)"
              % (name, len(fixture["states"]), len(fixture["joint_names"]), os.path.relpath(out, ROOT),
                 os.path.getsize(out) // 1024, worst))


if __name__ == "__main__":
    main()
