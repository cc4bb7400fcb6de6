"""Rotational inertia of a rigid body: the six numbers of a URDF ``<inertia>``, checked, rotated and lumped.

A link's tensor [kg m^2] is taken about its centre of mass, with the axes of the frame its centre of mass is
given in (a robot file's DH frame ``i``, a URDF link's frame), and written as URDF orders it::

    inertia: [ixx, ixy, ixz, iyy, iyz, izz]      # I = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]

Pure numbers: no model, no file (the gravity, transfer and export modules build on it).
"""

from __future__ import annotations

import numpy as np

#: URDF's names of the six numbers, in the order a robot file lists them.
FIELDS: tuple[str, ...] = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_ROWS, _COLS = (0, 0, 0, 1, 1, 2), (0, 1, 2, 1, 2, 2)
#: Most any of the six may be [kg m^2]: far more is a file in g mm^2 or another unit, not an arm's link.
MAX_INERTIA = 1e4
#: Radius [m] of the uniform solid sphere that stands for a link whose tensor nobody gave (:func:`sphere`).
ESTIMATE_RADIUS = 0.05


def tensor(six: np.ndarray) -> np.ndarray:
    """(3, 3) symmetric tensor [kg m^2] of the six numbers of a URDF ``<inertia>`` (not checked:
    :func:`checked_tensor`).

    Args:
        six: (6,) ``[ixx, ixy, ixz, iyy, iyz, izz]`` [kg m^2].
    """
    out = np.zeros((3, 3))
    out[_ROWS, _COLS] = six
    out[_COLS, _ROWS] = six
    return out


def six_of(matrix: np.ndarray) -> list[float]:
    """``[ixx, ixy, ixz, iyy, iyz, izz]`` [kg m^2] as plain floats (the inverse of :func:`tensor`).

    Args:
        matrix: (3, 3) tensor [kg m^2]; its symmetric part is taken.
    """
    matrix = 0.5 * (np.asarray(matrix, dtype=float) + np.asarray(matrix, dtype=float).T)
    return [float(v) for v in matrix[_ROWS, _COLS]]


def checked_tensor(values, where: str, error: type[Exception]) -> np.ndarray:
    """(3, 3) tensor [kg m^2] of a file's six numbers, refused (one line naming ``where``) unless they are six
    finite numbers of at most :data:`MAX_INERTIA` with non-negative ``ixx``, ``iyy``, ``izz``.

    The triangle inequality of the principal moments is not required: published descriptions break it by
    rounding, and gravity does not depend on the tensor.

    Args:
        values: the file's value, anything (a list of six numbers is expected) [kg m^2].
        where: the start of the refusal (file and field).
        error: the exception class raised.

    Raises:
        error: anything but six such numbers.
    """
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        array = np.empty(0)
    if array.shape != (6,) or not np.all(np.isfinite(array)):
        raise error(f"{where}: expected 6 finite numbers [ixx, ixy, ixz, iyy, iyz, izz] [kg m^2] about the centre "
                    f"of mass, got {values!r}")
    if np.any(array[[0, 3, 5]] < 0.0) or np.abs(array).max() > MAX_INERTIA:
        raise error(f"{where}: {values!r} is not a link's inertia (ixx, iyy, izz >= 0, each at most "
                    f"{MAX_INERTIA:g} kg m^2; the file is in kg m^2)")
    return tensor(array)


def rotated(matrix: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """(3, 3) tensor ``R I R^T`` [kg m^2]: a tensor given in frame B, expressed in frame A.

    Args:
        matrix: (3, 3) tensor in frame B's axes [kg m^2].
        rotation: (3, 3) rotation of frame B in frame A (dimensionless).
    """
    return rotation @ matrix @ rotation.T


def lumped(masses: np.ndarray, coms: np.ndarray, tensors: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """One rigid body of several, all in one frame (parallel-axis theorem).

    Args:
        masses: (K,) [kg].
        coms: (K, 3) centres of mass [m].
        tensors: (K, 3, 3) each about its own centre [kg m^2].

    Returns:
        ``(mass [kg], centre of mass (3,) [m], tensor (3, 3) about it [kg m^2])``; a massless set gives
        ``(0, origin, zeros)``.
    """
    masses = np.asarray(masses, dtype=float).reshape(-1)
    coms = np.asarray(coms, dtype=float).reshape(-1, 3)
    tensors = np.asarray(tensors, dtype=float).reshape(-1, 3, 3)
    mass = float(masses.sum())
    if mass <= 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = masses @ coms / mass
    total = tensors.sum(axis=0)
    for m, c in zip(masses, coms - com, strict=True):  # I + m (|r|^2 E - r r^T) about the common centre
        total = total + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    return mass, com, total


def sphere(mass: float, radius: float = ESTIMATE_RADIUS) -> np.ndarray:
    """(3, 3) tensor [kg m^2] of a uniform solid sphere of ``mass`` [kg] and ``radius`` [m] (``2/5 m r^2`` on
    the diagonal): the stand-in for an unknown tensor."""
    return 0.4 * mass * radius**2 * np.eye(3)
