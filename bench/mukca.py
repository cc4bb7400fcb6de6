"""Load the real MUKCa ball-in-socket recordings (/work/shared/data/mukca) for the bench scripts.

Not the `spherecal import` command (another piece of work): a minimal reader of ``hole_0.csv`` /
``hole_1.csv`` (7 joint angles [rad] per row, no header) per placement, fixtures ``<placement>_h0`` /
``<placement>_h1`` with their 0.050 m centre distance, and the Panda's ball centre from the URDF.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, load_robot
from spherecal.correction.fixtures import FixtureSpec
from spherecal.correction.samples import Dataset

ROOT = Path("/work/shared/data/mukca")
#: Socket centre distance of the printed plate [m].
HOLE_DISTANCE = 0.050


def _transform(xyz: list[float], rpy: list[float]) -> np.ndarray:
    roll, pitch, yaw = rpy
    cx, sx, cy, sy, cz, sz = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    out = np.eye(4)
    out[:3, :3] = rz @ ry @ rx  # URDF: fixed-axis roll, pitch, yaw
    out[:3, 3] = xyz
    return out


def ball_tool(
    urdf: Path = ROOT / "urdf" / "panda.urdf", parent: str = "panda_link7", tip: str = "ball_link"
) -> np.ndarray:
    """(3,) the ball centre in ``parent``'s frame [m]: the fixed joints from ``parent`` to ``tip`` composed.

    The embedded Panda's last modified-DH frame is ``panda_link7`` (Franka's DH table and URDF agree).
    """
    by_child = {j.find("child").get("link"): j for j in ET.parse(urdf).getroot().iter("joint")}
    chain, link = [], tip
    while link != parent:  # walk up from the tip: a link has one parent joint, possibly many children
        joint = by_child[link]
        if joint.get("type") != "fixed":
            raise ValueError(f"{urdf}: joint {joint.get('name')} between {parent} and {tip} is not fixed")
        chain.append(joint)
        link = joint.find("parent").get("link")
    pose = np.eye(4)
    for joint in reversed(chain):
        origin = joint.find("origin")
        xyz = [float(v) for v in (origin.get("xyz") or "0 0 0").split()]
        rpy = [float(v) for v in (origin.get("rpy") or "0 0 0").split()]
        pose = pose @ _transform(xyz, rpy)
    return pose[:3, 3]


def mukca_panda() -> RobotModel:
    """The embedded nominal Panda with its tool point at the MUKCa ball centre."""
    from dataclasses import replace

    return replace(load_robot("panda"), tool=ball_tool())


def placements(robot: str) -> list[str]:
    """Placements recorded for ``robot`` (folder names), sorted."""
    return sorted(p.name for p in (ROOT / "data" / robot).iterdir() if (p / "hole_0.csv").exists())


def mukca_dataset(robot: str, chosen: list[str] | None = None) -> tuple[Dataset, FixtureSpec]:
    """Samples and fixtures of the placements ``chosen`` (all when None) of ``robot``."""
    labels, rows = [], []
    names, distances = [], []
    for placement in chosen or placements(robot):
        pair = []
        for hole in (0, 1):
            q = np.loadtxt(ROOT / "data" / robot / placement / f"hole_{hole}.csv", delimiter=",", ndmin=2)
            name = f"{placement}_h{hole}"
            labels += [name] * len(q)
            rows.append(q)
            names.append(name)
            pair.append(name)
        distances.append((pair[0], pair[1], HOLE_DISTANCE))
    dataset = Dataset(labels=np.array(labels), q=np.concatenate(rows), fixture_names=tuple(names))
    return dataset, FixtureSpec(names=tuple(names), distances=distances, source=f"mukca/{robot}")
