"""MuJoCo as the independent URDF evaluator: strip meshes, compile, evaluate by joint name."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "data" / "urdf"
COMPILER = {"discardvisual": "true", "fusestatic": "false", "boundmass": "1e-3", "boundinertia": "1e-6"}


def mujoco_ready(text: str, **compiler: str) -> str:
    """URDF text without <visual>/<collision> (their mesh files are not shipped) and with a
    <mujoco><compiler .../></mujoco> element that keeps fixed links as bodies."""
    root = ET.fromstring(text)
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    for element in root.findall("mujoco"):
        root.remove(element)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", {**COMPILER, **compiler})
    return ET.tostring(root, encoding="unicode")


class MujocoUrdf:
    """A URDF compiled by MuJoCo; positions of a link's body for joint angles given by name."""

    def __init__(self, text: str, **compiler: str):
        import mujoco

        self._mujoco = mujoco
        self.model = mujoco.MjModel.from_xml_string(mujoco_ready(text, **compiler))
        self.data = mujoco.MjData(self.model)

    def body_pose(self, link: str, names: list[str], q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) position [m] and (N, 3, 3) orientation of ``link`` for (N, n) angles of ``names``."""
        mujoco, mj, data = self._mujoco, self.model, self.data
        body = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, link)
        assert body >= 0, link
        address = []
        for name in names:
            joint = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, name)
            assert joint >= 0, name
            address.append(mj.jnt_qposadr[joint])
        points, rotations = np.empty((len(q), 3)), np.empty((len(q), 3, 3))
        for k, qk in enumerate(np.atleast_2d(q)):
            data.qpos[:] = 0.0
            data.qpos[address] = qk
            mujoco.mj_kinematics(mj, data)
            points[k], rotations[k] = data.xpos[body], data.xmat[body].reshape(3, 3)
        return points, rotations
