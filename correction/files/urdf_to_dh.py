"""A URDF chain converted exactly into a :class:`RobotModel` (DH, Hayati ``beta`` where needed).

The chain is evaluated at the URDF's zero configuration: every revolute joint gives a line in
the base link's frame (a point and the unit axis, sign kept, so that a positive URDF angle is a
positive model angle). Modified DH frames are then placed on those lines (Craig):

* frame ``k`` has ``z_k`` along joint ``k``'s axis and its origin on that axis;
* if axes ``k`` and ``k+1`` are not parallel, ``x_k`` lies on their common normal and the
  origin at its foot (classical DH; ``beta_{k+1} = 0``);
* if they are parallel or nearly parallel (angle below :data:`PARALLEL_TOL`, or a common normal
  more than :data:`FAR_NORMAL` away along the axis), the common
  normal is undefined or kilometres away: the origin stays where the previous link put it
  (``d_k = 0``), ``x_k`` points to where axis ``k+1`` crosses the plane normal to ``z_k``, and
  the misalignment is ``alpha_{k+1}`` (about ``x``) plus Hayati's ``beta_{k+1}`` (about ``y``):
  joint ``k+1`` is ``Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)``;
* frame 0 is joint 1's frame at ``q = 0`` with ``theta_1 = d_1 = 0`` moved to the foot of
  the base origin on axis 1 (so the base transform is a pure translation when axis 1 is the
  base's ``z``, as for Franka's ``panda_link0``); the last frame has ``d_n = 0`` and the
  ``x`` of joint ``n``'s child link (the tool point carries the rest). Free signs and
  directions follow the URDF child link frames, so a URDF written in DH frames (Franka's)
  gives back its own numbers.

The standard convention is the modified model converted by :func:`correction.to_standard`.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import replace

import numpy as np

from ..chain import link_frames
from ..conversion import convert
from ..inertia import lumped, rotated, six_of
from ..model import RobotModel, matrix_rpy
from .robot_file import RobotFileError, check_robot
from .urdf_read import MOVABLE, UrdfTree, chain, read_urdf

#: Angle [rad] below which consecutive axes count as parallel. A DH ``d`` grows like (offset
#: between the axes) / angle: at 1e-3 rad and 0.3 m links it is 300 m, ill-conditioned for
#: calibration and beyond 1e-12 m exactness in double precision; designed-in angles between
#: consecutive axes are degrees, and rounded URDF angles (1.5708 for pi/2) differ by ~1e-5.
PARALLEL_TOL = 1e-3
#: Distance [m] along an axis beyond which the common normal with the next axis counts as "at
#: infinity": the axes are nearly parallel for DH's purposes (a calibrated arm whose axes were
#: parallel and now differ by a few mrad, 0.1 m apart: d = 0.1 / 0.003 = 33 m) and get a Hayati
#: ``beta`` as well. No arm's joints are 2 m apart.
FAR_NORMAL = 2.0


class NearlyParallelAxesWarning(UserWarning):
    """Consecutive axes that are not exactly parallel were given a Hayati ``beta``."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _perpendicular(z: np.ndarray, hint: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Unit vector normal to ``z`` closest to ``hint`` (``fallback`` if ``hint`` is along ``z``)."""
    for v in (hint, fallback, np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        w = v - (v @ z) * z
        if np.linalg.norm(w) > 1e-6:
            return _unit(w)
    raise AssertionError("unreachable")


def _angle(x_from: np.ndarray, x_to: np.ndarray, axis: np.ndarray) -> float:
    """Signed angle [rad] turning ``x_from`` onto ``x_to`` about ``axis``."""
    return float(np.arctan2(np.cross(x_from, x_to) @ axis, x_from @ x_to))


def _frame(x: np.ndarray, z: np.ndarray) -> np.ndarray:
    y = np.cross(z, x)
    x = np.cross(y, z)
    return np.stack([_unit(x), _unit(y), _unit(z)], axis=1)


def _rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    if axis == "x":
        return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def dh_from_lines(points: np.ndarray, axes: np.ndarray, hints: np.ndarray, tip: np.ndarray,
                  parallel_tol: float = PARALLEL_TOL, far_normal: float = FAR_NORMAL) -> dict:
    """Modified DH (with Hayati ``beta``) of joint axes given as lines at q = 0.

    Args:
        points: (n, 3) a point on each axis [m], in the base frame.
        axes: (n, 3) unit axis directions.
        hints: (n, 4, 4) the child link pose of each joint at q = 0 (picks free signs).
        tip: (4, 4) pose of the tip link at q = 0.
        parallel_tol: see :data:`PARALLEL_TOL`.
        far_normal: see :data:`FAR_NORMAL` [m] (``inf`` and ``parallel_tol = 0``: classical DH everywhere).

    Returns:
        A mapping with ``a, alpha, beta, d, theta`` (n,), ``tool`` (3,), ``base`` (4, 4) and
        ``parallel`` (list of 0-based joint indices ``k+1`` whose axis is parallel to axis ``k``).
    """
    n = len(points)
    a, alpha, beta, d, theta = (np.zeros(n) for _ in range(5))
    parallel: list[int] = []
    # Frame 0: on axis 1, nearest the base origin, x as close to the base x as possible.
    z = axes[0]
    origin = points[0] - (points[0] @ z) * z
    rotation = _frame(_perpendicular(z, np.array([1.0, 0, 0]), np.array([0, 1.0, 0])), z)
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rotation, origin
    pre_o, pre_r = origin, rotation  # frame k before Rz(theta_k) Lz(d_k): on axis k
    for k in range(n):
        z = axes[k]
        hint_x = hints[k][:3, 0]
        if k + 1 < n:
            z_next, p_next = axes[k + 1], points[k + 1]
            cross = np.cross(z, z_next)
            s = np.inf
            if np.linalg.norm(cross) >= np.sin(parallel_tol):  # common normal: its foot on axis k
                w = pre_o - p_next
                b, dz, dn = z @ z_next, z @ w, z_next @ w
                s = (b * dn - dz) / (1.0 - b * b)
            if abs(s) <= far_normal:
                o = pre_o + s * z
                x = _unit(cross)
                if x @ hint_x < 0:
                    x = -x
            else:
                parallel.append(k + 1)
                o = pre_o
                # Where axis k+1 crosses the plane through o normal to z.
                foot = p_next + ((o - p_next) @ z) / (z_next @ z) * z_next
                offset = foot - o
                x = _unit(offset) if np.linalg.norm(offset) > 1e-9 else _perpendicular(z, hint_x, pre_r[:, 0])
        else:
            o = pre_o  # d_n = 0: the tip's offset along z_n goes into the tool point
            x = _perpendicular(z, hint_x, tip[:3, 0])
        theta[k] = _angle(pre_r[:, 0], x, z)
        d[k] = (o - pre_o) @ z
        r = _frame(x, z)
        if k + 1 == n:
            tool = r.T @ (tip[:3, 3] - o)
            break
        # Joint k+1's fixed part, Rx(alpha) Lx(a) Ry(beta), from frame k.
        z_next = axes[k + 1]
        local = r.T @ z_next  # = Rx(alpha) Ry(beta) e_z = (sin b, -sin a cos b, cos a cos b)
        alpha[k + 1] = np.arctan2(-local[1], local[2])
        if k + 1 in parallel:
            beta[k + 1] = np.arcsin(np.clip(local[0], -1.0, 1.0))
            a[k + 1] = (foot - o) @ x
        else:  # x is normal to both axes: the distance between them along x
            a[k + 1] = (points[k + 1] - o) @ x
        pre_o = o + a[k + 1] * x
        pre_r = r @ _rot("x", alpha[k + 1]) @ _rot("y", beta[k + 1])
    return {"a": a, "alpha": alpha, "beta": beta, "d": d, "theta": theta, "tool": tool, "base": base,
            "parallel": parallel}


def _inertials(tree: UrdfTree, base: str, joints: list, frames: list[np.ndarray], poses: dict) -> tuple[list, dict]:
    """Masses lumped per DH joint (child link of each joint and everything rigidly on it, at q = 0
    of side joints), and after the last joint (the payload: hand, fingers, ball)."""
    movable = [j for j in joints if j.type in MOVABLE]
    groups: list[list[str]] = [[] for _ in movable]
    payload: list[str] = []
    chain_children = {j.child: i for i, j in enumerate(movable)}
    for link in tree.links:
        path = tree.path(base, link)
        if not path:
            continue
        owner = None
        for joint in path:
            if joint.child in chain_children and joint.name == movable[chain_children[joint.child]].name:
                owner = chain_children[joint.child]
        if owner is None:
            continue
        if owner == len(movable) - 1 and link != movable[-1].child:
            payload.append(link)
        else:
            groups[owner].append(link)

    def lump(links: list[str], frame: np.ndarray) -> dict:
        """One body in ``frame`` (world pose at q = 0): mass, centre of mass and, when every link with a mass
        gives one, the inertia tensor about the centre (each link's turned into the world, moved by the
        parallel-axis theorem, turned into ``frame``)."""
        held = [(tree.inertials[k], poses[k]) for k in links if k in tree.inertials]
        masses = np.array([i.mass for i, _ in held])
        centres = np.array([pose[:3, :3] @ i.com + pose[:3, 3] for i, pose in held]).reshape(-1, 3)
        tensors = np.array([np.zeros((3, 3)) if i.inertia is None else rotated(i.inertia, pose[:3, :3])
                            for i, pose in held]).reshape(-1, 3, 3)
        mass, com, total = lumped(masses, centres, tensors)
        local = frame[:3, :3].T @ ((com if mass > 0 else frame[:3, 3]) - frame[:3, 3])
        entry = {"mass": mass, "com": [float(v) for v in local]}
        if held and all(i.inertia is not None for i, _ in held if i.mass > 0):
            entry["inertia"] = six_of(rotated(total, frame[:3, :3].T))
        return entry

    return [lump(g, frames[i]) for i, g in enumerate(groups)], lump(payload, frames[-1])


def urdf_model(tree: UrdfTree, tip_link: str | None = None, base_link: str | None = None,
               convention: str = "modified", parallel_tol: float = PARALLEL_TOL,
               far_normal: float = FAR_NORMAL) -> RobotModel:
    """The revolute chain of a parsed URDF as a :class:`RobotModel` (see the module docstring).

    ``extras`` carries ``urdf`` (base and tip link, joint and child link names, the axes
    found parallel, the continuous ones, and ``effort`` [N m] and ``velocity`` [rad/s] when every joint's
    ``<limit>`` gives them),
    ``joint_names`` and, when the URDF has masses, ``inertials`` and ``payload``.
    ``parallel_tol`` [rad] and ``far_normal`` [m] decide which joints get a Hayati ``beta``
    (:data:`PARALLEL_TOL`, :data:`FAR_NORMAL`).
    """
    base, tip, joints = chain(tree, base_link, tip_link)
    poses = tree.world_poses(base)
    movable = [j for j in joints if j.type in MOVABLE]
    points, axes, hints = [], [], []
    for joint in movable:
        pose = poses[joint.child]  # the child frame at q = 0 is the joint frame
        points.append(pose[:3, 3])
        axes.append(_unit(pose[:3, :3] @ joint.axis))
        hints.append(pose)
    dh = dh_from_lines(np.array(points), np.array(axes), np.array(hints), poses[tip], parallel_tol, far_normal)
    lower = [j.lower if j.type == "revolute" else -np.pi for j in movable]
    upper = [j.upper if j.type == "revolute" else np.pi for j in movable]
    names = [j.name for j in movable]
    extras: dict = {
        "joint_names": names,
        "urdf": {
            "base_link": base,
            "tip_link": tip,
            "links": [j.child for j in movable],
            "parallel_joints": [names[k] for k in dh["parallel"]],
            # which joints turn freely (RobotModel.full_turn): a revolute joint limited to [-pi, pi] (a UR elbow)
            # spans a turn as well, and is no continuous joint
            "continuous_joints": [j.name for j in movable if j.type == "continuous"],
        },
    }
    for key in ("effort", "velocity"):  # every joint's, or none: the defaults of a standalone URDF export
        values = [getattr(j, key) for j in movable]
        if all(v is not None for v in values):
            extras["urdf"][key] = values
    model = RobotModel(
        name=tree.name or os.path.basename(tree.source), convention="modified", a=dh["a"], alpha=dh["alpha"],
        d=dh["d"], theta=dh["theta"], beta=dh["beta"], hayati=tuple(dh["parallel"]), lower=lower, upper=upper,
        tool=dh["tool"],
        base_xyz=dh["base"][:3, 3], base_rpy=matrix_rpy(dh["base"][:3, :3]), extras=extras,
    )
    if tree.inertials:
        frames = link_frames(model, np.zeros(model.n_joints))[1:]
        inertials, payload = _inertials(tree, base, joints, list(frames), poses)
        extras["inertials"], extras["payload"] = inertials, payload
    skew = [names[k] for k in dh["parallel"] if max(abs(dh["beta"][k]), abs(np.sin(dh["alpha"][k]))) > 1e-12]
    if skew:
        warnings.warn(
            f"{tree.source}: "
            + (f"joints {', '.join(skew)} turn about axes" if len(skew) > 1 else f"joint {skew[0]} turns about an axis")
            + " nearly parallel to the previous joint's: "
            "described with a Hayati beta (d of the joint before held at zero)",
            NearlyParallelAxesWarning, stacklevel=2,
        )
    return convert(model, convention) if convention != "modified" else model


def load_urdf(path: str | os.PathLike, tip_link: str | None = None, base_link: str | None = None,
              convention: str = "modified") -> RobotModel:
    """Read a URDF file and convert its chain from ``base_link`` to ``tip_link``.

    Args:
        path: the URDF file (meshes need not exist; visuals and collisions are ignored).
        tip_link: the link whose origin is the tool point (default: the one end of the serial chain).
        base_link: the model's world frame (default: the root link).
        convention: ``"modified"`` (default) or ``"standard"``.

    Raises:
        RobotFileError: one line naming the file and the element.
    """
    if convention not in ("modified", "standard"):
        raise RobotFileError(f"{path}: unknown convention {convention!r} (expected 'modified' or 'standard')")
    model = urdf_model(read_urdf(path), tip_link, base_link, convention)
    check_robot(model, str(path))  # the robot file's ranges: lengths, angles, joint limits
    return replace(model, extras={**model.extras, "source": str(path)})
