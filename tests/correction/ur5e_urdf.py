"""A UR5e-like URDF written inline (frames as in ur_description, DH from UR's datasheet)."""

from __future__ import annotations

import numpy as np

#: UR5e published (standard) DH: d1, a2, a3, d4, d5, d6 [m].
UR5E_DH = {"d1": 0.1625, "a2": -0.425, "a3": -0.3922, "d4": 0.1333, "d5": 0.0997, "d6": 0.0996}
NAMES = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
         "wrist_3_joint")


def ur5e_urdf(skew: float = 0.0, pi: float = np.pi) -> str:
    """URDF text; ``skew`` [rad] tilts the elbow and wrist-1 axes out of parallel about the
    link's x (a calibrated UR's kinematics file has such small angles)."""
    k = UR5E_DH
    h = pi / 2
    joints = [
        ("base_link_inertia", "shoulder_link", f"0 0 {k['d1']}", "0 0 0"),
        ("shoulder_link", "upper_arm_link", "0 0 0", f"{h} 0 0"),
        ("upper_arm_link", "forearm_link", f"{k['a2']} 0 0", f"{skew} 0 0"),
        ("forearm_link", "wrist_1_link", f"{k['a3']} 0 {k['d4']}", f"0 {-skew} 0"),
        ("wrist_1_link", "wrist_2_link", f"0 {-k['d5']} 0", f"{h} 0 0"),
        ("wrist_2_link", "wrist_3_link", f"0 {k['d6']} 0", f"{h} {pi} {pi}"),
    ]
    lines = ['<?xml version="1.0"?>', "<!-- a UR5e-like arm: kinematics only -->", '<robot name="ur5e">']
    links = ["base_link", "base_link_inertia"] + [child for _, child, _, _ in joints] + ["flange", "tool0", "ball"]
    for link in links:
        lines.append(f'  <link name="{link}"><visual><geometry><mesh filename="package://ur/{link}.dae"/>'
                     "</geometry></visual></link>")
    lines.append('  <joint name="base_link-base_link_inertia" type="fixed"><parent link="base_link"/>'
                 f'<child link="base_link_inertia"/><origin xyz="0 0 0" rpy="0 0 {pi}"/></joint>')
    for name, (parent, child, xyz, rpy) in zip(NAMES, joints, strict=True):
        lines.append(f'  <joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
                     f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
                     f'<limit lower="{-2 * pi}" upper="{2 * pi}" effort="150" velocity="3.14"/></joint>')
    for name, parent, child, xyz, rpy in (
        ("wrist_3-flange", "wrist_3_link", "flange", "0 0 0", f"0 {-h} {-h}"),
        ("flange-tool0", "flange", "tool0", "0 0 0", f"{h} 0 {h}"),
        ("tool0-ball", "tool0", "ball", "0.001 -0.002 0.05", "0 0 0"),
    ):
        lines.append(f'  <joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
                     f'<origin xyz="{xyz}" rpy="{rpy}"/></joint>')
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
