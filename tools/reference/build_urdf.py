#!/usr/bin/env python3
"""Generate models/stride_humanoid.urdf, the humanoid model bundled with stride.

The model is written by the stride team. Its sizes and masses are in the range of a 1 m, 33 kg child-sized
humanoid (public iCub v2.7 figures were used as a guide for lengths, masses and joint ranges); no file of
another project was copied. Every link inertia is the exact inertia of a homogeneous solid (box or cylinder)
about its centre of mass, so all inertias are physically consistent (positive, triangle inequalities hold).

Conventions (see docs/models.md):
  * world: x forward, y left, z up; in the zero configuration every link frame is aligned with the world and
    the robot stands straight with both soles flat on the same plane (z = 0 when root_link is at z = ROOT_Z).
  * pitch joints of legs/arms/elbows: positive = flexion (leg/arm forward, knee bends backwards,
    elbow brings the forearm forward, ankle pitch lifts the toe);
  * roll/yaw joints are mirrored between left and right: positive = abduction / external rotation on both
    sides (left axes +x / +z, right axes -x / -z).

Usage: python3 tools/reference/build_urdf.py [--flex] [output]
  default output: models/stride_humanoid.urdf, with --flex models/stride_humanoid_flex.urdf.

--flex writes the variant with flexible hips (Romualdi 2022, ch. 9): between the pelvis and
each leg, a passive pitch joint (<side>_hip_flex_pitch, axis as <side>_hip_pitch) and a passive roll joint
(<side>_hip_flex_roll, axis as <side>_hip_roll), both 6 cm above the hip (in the pelvis), through two massless
links. Everything
else is the bundled humanoid unchanged; the zero configuration (flex joints at 0) is the same robot. The joints
are passive visco-elastic springs in the simulator (`[sim.passive_joints]`), not motors.
"""

import math
import os
import sys

ROOT_Z = 0.6  # height of root_link above the sole plane in the zero configuration [m]
FOOT_LENGTH = 0.20  # [m] along x
FOOT_WIDTH = 0.09  # [m] along y
FOOT_HEIGHT = 0.03  # [m] thickness of the foot sole box
ANKLE_TO_FOOT_CENTRE_X = 0.03  # the ankle axis is 3 cm behind the foot centre [m]
HIP_Y = 0.075  # lateral offset of each hip from the pelvis centre -> feet 0.15 m apart [m]


def fmt(x):
    """Format a float as the shortest string that reads back to the same double."""
    if abs(x) < 1e-15:
        return "0"
    x = float(x)
    if x == int(x):
        return str(int(x))
    return repr(x)


def vec(v):
    return " ".join(fmt(x) for x in v)


def box_inertia(m, sx, sy, sz):
    return (m * (sy * sy + sz * sz) / 12.0, m * (sx * sx + sz * sz) / 12.0, m * (sx * sx + sy * sy) / 12.0)


def cyl_inertia(m, r, length, axis):
    """Solid cylinder of radius r and length `length` along `axis` ('x', 'y' or 'z')."""
    a = m * r * r / 2.0
    b = m * (3.0 * r * r + length * length) / 12.0
    return {"x": (a, b, b), "y": (b, a, b), "z": (b, b, a)}[axis]


class Link:
    def __init__(self, name, mass=None, com=(0, 0, 0), shape=None, comment=None):
        self.name = name
        self.mass = mass
        self.com = com
        self.shape = shape  # ("box", sx, sy, sz) or ("cyl", r, length, axis)
        self.comment = comment

    def inertia(self):
        kind = self.shape[0]
        if kind == "box":
            return box_inertia(self.mass, *self.shape[1:])
        return cyl_inertia(self.mass, *self.shape[1:])

    def geometry_xml(self):
        kind = self.shape[0]
        if kind == "box":
            return '<box size="%s"/>' % vec(self.shape[1:])
        r, length, axis = self.shape[1:]
        return '<cylinder radius="%s" length="%s"/>' % (fmt(r), fmt(length))

    def geometry_rpy(self):
        if self.shape[0] == "cyl":
            axis = self.shape[3]
            return {"x": (0, math.pi / 2, 0), "y": (math.pi / 2, 0, 0), "z": (0, 0, 0)}[axis]
        return (0, 0, 0)

    def xml(self):
        out = []
        if self.comment:
            out.append("  <!-- %s -->" % self.comment)
        if self.mass is None:
            out.append('  <link name="%s"/>' % self.name)
            return "\n".join(out)
        ixx, iyy, izz = self.inertia()
        out.append('  <link name="%s">' % self.name)
        out.append("    <inertial>")
        out.append('      <origin xyz="%s" rpy="0 0 0"/>' % vec(self.com))
        out.append('      <mass value="%s"/>' % fmt(self.mass))
        out.append(
            '      <inertia ixx="%s" ixy="0" ixz="0" iyy="%s" iyz="0" izz="%s"/>' % (fmt(ixx), fmt(iyy), fmt(izz))
        )
        out.append("    </inertial>")
        for tag in ("visual", "collision") if self.name.endswith("foot") else ("visual",):
            out.append("    <%s>" % tag)
            out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(self.com), vec(self.geometry_rpy())))
            out.append("      <geometry>%s</geometry>" % self.geometry_xml())
            out.append("    </%s>" % tag)
        out.append("  </link>")
        return "\n".join(out)


class Joint:
    def __init__(self, name, kind, parent, child, xyz, axis=None, limits=None, rpy=(0, 0, 0), comment=None):
        self.name = name
        self.kind = kind
        self.parent = parent
        self.child = child
        self.xyz = xyz
        self.rpy = rpy
        self.axis = axis
        self.limits = limits  # (lower, upper, velocity, effort)
        self.comment = comment

    def xml(self):
        out = []
        if self.comment:
            out.append("  <!-- %s -->" % self.comment)
        out.append('  <joint name="%s" type="%s">' % (self.name, self.kind))
        out.append('    <origin xyz="%s" rpy="%s"/>' % (vec(self.xyz), vec(self.rpy)))
        out.append('    <parent link="%s"/>' % self.parent)
        out.append('    <child link="%s"/>' % self.child)
        if self.kind != "fixed":
            out.append('    <axis xyz="%s"/>' % vec(self.axis))
            lo, up, vel, eff = self.limits
            out.append(
                '    <limit lower="%s" upper="%s" velocity="%s" effort="%s"/>' % (fmt(lo), fmt(up), fmt(vel), fmt(eff))
            )
            out.append('    <dynamics damping="0" friction="0"/>')
        out.append("  </joint>")
        return "\n".join(out)


def deg(x):
    return math.radians(x)


FLEX_RANGE = 0.5  # [rad] range of the passive hip joints (far beyond any deflection a walk produces)
FLEX_ABOVE_HIP = 0.06  # [m] the passive hip joints are at the pelvis, this far above the hip joints
FLEX_EFFORT = 1000.0  # [N m] nominal effort bound of the passive hip joints (no motor: never commanded)


def build(flex=False):
    links = []
    joints = []
    L = links.append
    J = joints.append

    # ---------------- pelvis, torso, head ----------------
    L(Link("root_link", 4.6, (0.0, 0.0, -0.01), ("box", 0.12, 0.22, 0.10), "pelvis (floating base)"))
    L(Link("imu_frame", comment="IMU on the pelvis (massless frame)"))
    J(Joint("imu_frame_fixed_joint", "fixed", "root_link", "imu_frame", (0.02, 0.0, 0.04)))

    L(Link("torso_1", 0.6, (0.0, 0.0, 0.0), ("cyl", 0.04, 0.08, "y")))
    L(Link("torso_2", 0.5, (0.0, 0.0, 0.01), ("cyl", 0.04, 0.08, "x")))
    L(Link("chest", 5.0, (-0.01, 0.0, 0.11), ("box", 0.14, 0.22, 0.24), "chest: electronics and battery"))
    J(Joint("torso_pitch", "revolute", "root_link", "torso_1", (0.0, 0.0, 0.05), (0, 1, 0),
            (deg(-20), deg(70), 8.0, 40.0), comment="positive: lean forward"))
    J(Joint("torso_roll", "revolute", "torso_1", "torso_2", (0.0, 0.0, 0.0), (1, 0, 0),
            (deg(-30), deg(30), 8.0, 40.0), comment="positive: right-hand rule about +x (lean to the right)"))
    J(Joint("torso_yaw", "revolute", "torso_2", "chest", (0.0, 0.0, 0.03), (0, 0, 1),
            (deg(-50), deg(50), 8.0, 30.0), comment="positive: turn to the left"))

    L(Link("neck_1", 0.15, (0.0, 0.0, 0.0), ("cyl", 0.02, 0.05, "y")))
    L(Link("neck_2", 0.15, (0.0, 0.0, 0.01), ("cyl", 0.02, 0.05, "x")))
    L(Link("head", 2.4, (0.01, 0.0, 0.05), ("box", 0.15, 0.13, 0.12)))
    L(Link("head_imu", comment="IMU in the head (massless frame)"))
    J(Joint("neck_pitch", "revolute", "chest", "neck_1", (0.0, 0.0, 0.24), (0, 1, 0),
            (deg(-40), deg(30), 8.0, 10.0), comment="positive: look down"))
    J(Joint("neck_roll", "revolute", "neck_1", "neck_2", (0.0, 0.0, 0.0), (1, 0, 0),
            (deg(-20), deg(20), 8.0, 10.0)))
    J(Joint("neck_yaw", "revolute", "neck_2", "head", (0.0, 0.0, 0.02), (0, 0, 1),
            (deg(-45), deg(45), 8.0, 10.0), comment="positive: look left"))
    J(Joint("head_imu_fixed_joint", "fixed", "head", "head_imu", (0.04, 0.0, 0.06)))

    # ---------------- arms ----------------
    for side, s in (("l", 1.0), ("r", -1.0)):
        L(Link(side + "_shoulder_1", 0.2, (0.0, s * 0.015, 0.0), ("cyl", 0.03, 0.05, "y")))
        L(Link(side + "_shoulder_2", 0.3, (0.0, 0.0, -0.02), ("cyl", 0.03, 0.06, "x")))
        L(Link(side + "_upper_arm", 1.05, (0.0, 0.0, -0.05), ("cyl", 0.035, 0.10, "z")))
        L(Link(side + "_forearm", 0.55, (0.0, 0.0, -0.05), ("cyl", 0.03, 0.10, "z")))
        L(Link(side + "_wrist_1", 0.1, (0.0, 0.0, 0.0), ("cyl", 0.02, 0.04, "y")))
        L(Link(side + "_hand", 0.3, (0.0, 0.0, -0.045), ("box", 0.03, 0.07, 0.09)))
        J(Joint(side + "_shoulder_pitch", "revolute", "chest", side + "_shoulder_1", (0.0, s * 0.11, 0.22),
                (0, -1, 0), (deg(-30), deg(160), 8.0, 30.0), comment="positive: arm forward"))
        J(Joint(side + "_shoulder_roll", "revolute", side + "_shoulder_1", side + "_shoulder_2",
                (0.0, s * 0.03, 0.0), (s, 0, 0), (deg(-5), deg(160), 8.0, 30.0),
                comment="positive: abduction (arm away from the body)"))
        J(Joint(side + "_shoulder_yaw", "revolute", side + "_shoulder_2", side + "_upper_arm",
                (0.0, 0.0, -0.05), (0, 0, s), (deg(-37), deg(80), 8.0, 20.0),
                comment="positive: external rotation"))
        J(Joint(side + "_elbow", "revolute", side + "_upper_arm", side + "_forearm", (0.0, 0.0, -0.10),
                (0, -1, 0), (deg(0), deg(105), 8.0, 20.0), comment="positive: flexion (forearm forward)"))
        J(Joint(side + "_wrist_prosup", "revolute", side + "_forearm", side + "_wrist_1", (0.0, 0.0, -0.14),
                (0, 0, s), (deg(-60), deg(60), 8.0, 5.0)))
        J(Joint(side + "_wrist_pitch", "revolute", side + "_wrist_1", side + "_wrist_2", (0.0, 0.0, 0.0),
                (0, -1, 0), (deg(-65), deg(65), 8.0, 5.0)))
        L(Link(side + "_wrist_2", 0.05, (0.0, 0.0, 0.0), ("cyl", 0.015, 0.03, "x")))
        J(Joint(side + "_wrist_yaw", "revolute", side + "_wrist_2", side + "_hand", (0.0, 0.0, -0.01),
                (s, 0, 0), (deg(-25), deg(25), 8.0, 5.0)))
        L(Link(side + "_hand_palm", comment="centre of the palm (massless frame)"))
        J(Joint(side + "_hand_palm_fixed_joint", "fixed", side + "_hand", side + "_hand_palm",
                (0.0, 0.0, -0.06), rpy=(0.0, math.pi / 2, 0.0)))

    # ---------------- legs ----------------
    for side, s in (("l", 1.0), ("r", -1.0)):
        up = side + "_"
        L(Link(up + "hip_1", 0.6, (0.0, s * 0.0, 0.0), ("cyl", 0.04, 0.06, "x")))
        L(Link(up + "hip_2", 0.9, (0.0, 0.0, -0.03), ("cyl", 0.04, 0.08, "z")))
        L(Link(up + "upper_thigh", 0.5, (0.0, 0.0, -0.015), ("cyl", 0.045, 0.03, "z"),
               "thigh part above the leg force/torque sensor"))
        L(Link(up + "thigh", 2.2, (0.0, 0.0, -0.07), ("cyl", 0.05, 0.12, "z"),
               "thigh part below the leg force/torque sensor (lumped into " + up + "upper_thigh)"))
        L(Link(up + "lower_leg", 1.7, (0.0, 0.0, -0.10), ("cyl", 0.045, 0.20, "z")))
        L(Link(up + "ankle_1", 0.4, (0.0, 0.0, 0.0), ("cyl", 0.03, 0.06, "y")))
        L(Link(up + "ankle_2", 0.15, (0.0, 0.0, -0.015), ("cyl", 0.025, 0.03, "z"),
               "ankle part above the foot force/torque sensor"))
        L(Link(up + "foot", 0.7, (ANKLE_TO_FOOT_CENTRE_X, 0.0, -0.045 + FOOT_HEIGHT / 2.0),
               ("box", FOOT_LENGTH, FOOT_WIDTH, FOOT_HEIGHT),
               "foot: %.2f m x %.2f m rectangular sole; below the foot force/torque sensor" % (FOOT_LENGTH, FOOT_WIDTH)))
        L(Link(up + "sole", comment="bottom centre of the rectangular foot, x forward, z up (massless frame)"))

        hip_parent, hip_xyz = "root_link", (0.0, s * HIP_Y, -0.06)
        if flex:
            # The passive joints sit FLEX_ABOVE_HIP above the hip: at the hip itself, through massless links,
            # the passive pitch would be coaxial with the hip pitch and the mass matrix singular (the two
            # joints turning opposite ways would move nothing).
            flex_limits = (-FLEX_RANGE, FLEX_RANGE, 10.0, FLEX_EFFORT)
            L(Link(up + "hip_flex_1", comment="massless link between the passive hip joints"))
            L(Link(up + "hip_flex_2", comment="massless link between the passive hip joints and the leg"))
            flex_xyz = (0.0, s * HIP_Y, -0.06 + FLEX_ABOVE_HIP)
            J(Joint(up + "hip_flex_pitch", "revolute", "root_link", up + "hip_flex_1", flex_xyz, (0, -1, 0),
                    flex_limits, comment="passive visco-elastic joint (no motor), axis as the hip pitch"))
            J(Joint(up + "hip_flex_roll", "revolute", up + "hip_flex_1", up + "hip_flex_2", (0.0, 0.0, 0.0),
                    (s, 0, 0), flex_limits, comment="passive visco-elastic joint (no motor), axis as the hip roll"))
            hip_parent, hip_xyz = up + "hip_flex_2", (0.0, 0.0, -FLEX_ABOVE_HIP)
        J(Joint(up + "hip_pitch", "revolute", hip_parent, up + "hip_1", hip_xyz, (0, -1, 0),
                (deg(-40), deg(120), 10.0, 60.0), comment="positive: flexion (leg forward)"))
        J(Joint(up + "hip_roll", "revolute", up + "hip_1", up + "hip_2", (0.0, 0.0, 0.0), (s, 0, 0),
                (deg(-25), deg(80), 10.0, 60.0), comment="positive: abduction (leg away from the body)"))
        J(Joint(up + "hip_yaw", "revolute", up + "hip_2", up + "upper_thigh", (0.0, 0.0, -0.07), (0, 0, s),
                (deg(-75), deg(75), 10.0, 40.0), comment="positive: external rotation (toe outwards)"))
        J(Joint(up + "leg_ft_sensor", "fixed", up + "upper_thigh", up + "thigh", (0.0, 0.0, -0.03),
                comment="six-axis force/torque sensor in the thigh"))
        J(Joint(up + "knee", "revolute", up + "thigh", up + "lower_leg", (0.0, 0.0, -0.125), (0, 1, 0),
                (deg(0), deg(100), 10.0, 60.0), comment="positive: flexion (the knee bends backwards, like a human's)"))
        J(Joint(up + "ankle_pitch", "revolute", up + "lower_leg", up + "ankle_1", (0.0, 0.0, -0.24), (0, -1, 0),
                (deg(-40), deg(40), 10.0, 40.0), comment="positive: dorsiflexion (toe up)"))
        J(Joint(up + "ankle_roll", "revolute", up + "ankle_1", up + "ankle_2", (0.0, 0.0, 0.0), (s, 0, 0),
                (deg(-20), deg(20), 10.0, 30.0), comment="positive: sole turns outwards"))
        J(Joint(up + "foot_ft_sensor", "fixed", up + "ankle_2", up + "foot", (0.0, 0.0, -0.03),
                comment="six-axis force/torque sensor between ankle and foot"))
        J(Joint(up + "sole_fixed_joint", "fixed", up + "foot", up + "sole",
                (ANKLE_TO_FOOT_CENTRE_X, 0.0, -0.045)))

    sensors = ["l_leg_ft_sensor", "r_leg_ft_sensor", "l_foot_ft_sensor", "r_foot_ft_sensor"]
    return links, joints, sensors


def check_heights(links, joints):
    """Sanity check: soles at z = -ROOT_Z in root coordinates (zero configuration, all rotations identity)."""
    by_child = {j.child: j for j in joints}

    def pos(link):
        p = [0.0, 0.0, 0.0]
        while link in by_child:
            j = by_child[link]
            p = [p[i] + j.xyz[i] for i in range(3)]
            link = j.parent
        return p

    for side in ("l", "r"):
        z = pos(side + "_sole")[2]
        assert abs(z + ROOT_Z) < 1e-12, (side, z)


def render(links, joints, sensors, flex=False):
    total = sum(l.mass for l in links if l.mass is not None)
    out = ['<?xml version="1.0"?>']
    out.append("<!--")
    out.append("  stride_humanoid: the humanoid model bundled with stride (written by the stride team).")
    if flex:
        out.append("  Variant with flexible hips (build_urdf.py with its flex option): passive pitch and roll joints")
        out.append("  l/r_hip_flex_pitch, l/r_hip_flex_roll between the pelvis and each leg (no motors).")
    out.append("  Generated by tools/reference/build_urdf.py - edit the generator, not this file.")
    out.append("  Total mass %.3f kg, %d revolute joints. World/link axes: x forward, y left, z up." %
               (total, sum(1 for j in joints if j.kind == "revolute")))
    out.append("  Zero configuration: straight standing pose, all link frames aligned with root_link;")
    out.append("  with root_link at z = %.2f m both soles (l_sole, r_sole) lie flat on z = 0." % ROOT_Z)
    out.append("  Feet: rectangular soles %.2f m (x) x %.2f m (y); l_sole/r_sole at the bottom centre," %
               (FOOT_LENGTH, FOOT_WIDTH))
    out.append("  axes aligned with the world at the zero configuration; nominal lateral distance %.2f m." %
               (2 * HIP_Y))
    out.append("  Sign conventions: pitch joints positive = flexion (hip/shoulder forward, knee backwards,")
    out.append("  elbow forward, ankle toe up); roll/yaw joints mirrored: positive = abduction / external")
    out.append("  rotation on both sides. Inertias: homogeneous boxes/cylinders (physically consistent).")
    out.append("-->")
    out.append('<robot name="stride_humanoid">')
    link_by_name = {l.name: l for l in links}
    emitted = set()
    # emit root first, then in joint order (child link just before its joint) for readability
    out.append(link_by_name["root_link"].xml())
    emitted.add("root_link")
    for j in joints:
        if j.child not in emitted:
            out.append(link_by_name[j.child].xml())
            emitted.add(j.child)
        out.append(j.xml())
    assert emitted == set(link_by_name), set(link_by_name) - emitted
    for s in sensors:
        out.append('  <gazebo reference="%s">' % s)
        out.append('    <sensor name="%s" type="force_torque">' % s)
        out.append("      <always_on>1</always_on>")
        out.append("      <update_rate>100</update_rate>")
        out.append("      <force_torque>")
        out.append("        <frame>sensor</frame>")
        out.append("        <measure_direction>child_to_parent</measure_direction>")
        out.append("      </force_torque>")
        out.append('      <pose>0 0 0 0 0 0</pose>')
        out.append("    </sensor>")
        out.append("  </gazebo>")
        # the same sensor in the iDynTree URDF sensor extension, as the iCub models also declare it
        out.append('  <sensor name="%s" type="force_torque">' % s)
        out.append('    <parent joint="%s"/>' % s)
        out.append("    <force_torque>")
        out.append("      <frame>sensor</frame>")
        out.append("      <measure_direction>child_to_parent</measure_direction>")
        out.append("    </force_torque>")
        out.append('    <origin xyz="0 0 0" rpy="0 0 0"/>')
        out.append("  </sensor>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    args = sys.argv[1:]
    flex = "--flex" in args
    args = [a for a in args if a != "--flex"]
    name = "stride_humanoid_flex.urdf" if flex else "stride_humanoid.urdf"
    default = os.path.normpath(os.path.join(here, "..", "..", "models", name))
    path = args[0] if args else default
    links, joints, sensors = build(flex)
    check_heights(links, joints)
    text = render(links, joints, sensors, flex)
    with open(path, "w") as f:
        f.write(text)
    total = sum(l.mass for l in links if l.mass is not None)
    print("wrote %s: %d links, %d joints, total mass %.3f kg" % (path, len(links), len(joints), total))


if __name__ == "__main__":
    main()
