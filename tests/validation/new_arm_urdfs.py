"""Two six-joint arms that are not a Panda, written inline for the new-arm trials (test_new_arm_trial_*.py).

``big_urdf``: an industrial-style arm of about 1.3 m reach (0.15 m shoulder offset, elbow offset, spherical wrist,
limits of +-170 to +-200 deg, a continuous last joint), no ``<inertial>``. ``small_urdf``: a 0.45 m arm with link
inertials. Both end at a ``ball`` link on the flange (the tool point).
"""

from __future__ import annotations

import math

#: name, parent, child, origin xyz [m], axis, lower, upper [deg] (None: continuous)
BIG_JOINTS = (
    ("joint1", "base_link", "link1", "0 0 0.45", "0 0 1", 170),
    ("joint2", "link1", "link2", "0.15 0 0", "0 1 0", 175),
    ("joint3", "link2", "link3", "0 0 0.5", "0 1 0", 170),
    ("joint4", "link3", "link4", "0.25 0 0.1", "1 0 0", 200),
    ("joint5", "link4", "link5", "0.30 0 0", "0 1 0", 170),
    ("joint6", "link5", "link6", "0.08 0 0", "1 0 0", None),
)
BIG_BALL = "0.04 0 0"
SMALL_JOINTS = (
    ("joint1", "base_link", "link1", "0 0 0.12", "0 0 1", 175),
    ("joint2", "link1", "link2", "0 0 0", "0 1 0", 120),
    ("joint3", "link2", "link3", "0 0 0.19", "0 1 0", 150),
    ("joint4", "link3", "link4", "0.10 0 0", "1 0 0", 175),
    ("joint5", "link4", "link5", "0.07 0 0", "0 1 0", 120),
    ("joint6", "link5", "link6", "0.05 0 0", "1 0 0", 175),
)
SMALL_BALL = "0.03 0 0"
#: link -> mass [kg], centre of mass [m] (the small arm's inertials)
SMALL_MASSES = {"base_link": (1.0, "0 0 0.05"), "link1": (0.6, "0 0 0.02"), "link2": (0.5, "0 0 0.09"),
                "link3": (0.35, "0.08 0 0"), "link4": (0.2, "0.02 0 0"), "link5": (0.15, "0.02 0 0"),
                "link6": (0.05, "0.01 0 0"), "ball": (0.03, "0 0 0")}


def _urdf(name: str, joints, ball: str, masses: dict | None) -> str:
    links = ["base_link", *(j[2] for j in joints), "ball"]
    text = [f'<?xml version="1.0"?>\n<robot name="{name}">']
    for link in links:
        inertial = ""
        if masses:
            m, com = masses[link]
            inertial = (f'<inertial><origin xyz="{com}"/><mass value="{m}"/><inertia ixx="{m * 1e-3}" ixy="0" '
                        f'ixz="0" iyy="{m * 1e-3}" iyz="0" izz="{m * 1e-3}"/></inertial>')
        text.append(f'  <link name="{link}">{inertial}</link>')
    for joint, parent, child, xyz, axis, limit in joints:
        kind = "continuous" if limit is None else "revolute"
        bounds = "" if limit is None else f'lower="{-math.radians(limit):.4f}" upper="{math.radians(limit):.4f}" '
        text.append(f'  <joint name="{joint}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                    f'<origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="{axis}"/>'
                    f'<limit {bounds}effort="100" velocity="2"/></joint>')
    text.append(f'  <joint name="ball_joint" type="fixed"><parent link="{joints[-1][2]}"/><child link="ball"/>'
                f'<origin xyz="{ball}" rpy="0 0 0"/></joint>\n</robot>\n')
    return "\n".join(text)


def big_urdf() -> str:
    """The 1.3 m arm (no inertials)."""
    return _urdf("big6", BIG_JOINTS, BIG_BALL, None)


def small_urdf() -> str:
    """The 0.45 m arm (with inertials)."""
    return _urdf("small6", SMALL_JOINTS, SMALL_BALL, SMALL_MASSES)
