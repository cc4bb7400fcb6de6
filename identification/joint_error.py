"""The arm's unmodelled joint-angle error: a smooth error of each joint's angle over joint space.

What no kinematic parameter describes on a revolute arm is mostly an error of its joint angles that varies
with the configuration (backlash that follows the load, gear transmission error, compliance the model
lacks). Each joint's angle error is modelled as a Gaussian process over joint space, prior std ``std`` [rad]
and squared-exponential kernel of length :data:`LENGTH` [rad], independent between joints; the tool point
sees it through the joint Jacobian::

    e(q) = sum_j  dp/dq_j (q) eps_j(q),     eps_j = L z_j,  L L^T = k(q, q),  z_j ~ N(0, I)

A calibration absorbs part of it into its parameters at the training configurations (a bias that does not
hold elsewhere) and leaves the rest in its residuals; at a socket it did not see, a fresh draw of it adds to
the spread, amplified by the lever arms there (:mod:`.prediction`).
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian

#: Correlation length of the joint-angle error over joint space [rad] (the recording plan's; 1 and 2 rank alike
#: on real data).
LENGTH = 1.0
#: Up to this many configurations the kernel's root is exact (its eigen-decomposition is cubic in them); above,
#: :data:`FEATURES` random Fourier features of the kernel.
EXACT = 400
FEATURES = 300


def kernel(a: np.ndarray, b: np.ndarray, length: float = LENGTH) -> np.ndarray:
    """(A, B) squared-exponential correlation of configurations ``a`` (A, n) and ``b`` (B, n) [rad]."""
    d2 = np.einsum("ij,ij->i", a, a)[:, None] + np.einsum("ij,ij->i", b, b)[None, :] - 2.0 * a @ b.T
    return np.exp(-np.clip(d2, 0.0, None) / (2.0 * length**2))


def field_root(q: np.ndarray, length: float = LENGTH, rng: np.random.Generator | None = None) -> np.ndarray:
    """A root ``L`` (K, r) of the unit-variance process at configurations ``q`` (K, n) [rad]: ``L L^T = k(q, q)``.

    Exact up to :data:`EXACT` configurations, else :data:`FEATURES` random Fourier features (seeded by ``rng``,
    default seed 0; ``L L^T`` then approximates the kernel).
    """
    if len(q) <= EXACT:
        values, vectors = np.linalg.eigh(kernel(q, q, length))
        keep = values > 1e-9 * values[-1]
        return vectors[:, keep] * np.sqrt(values[keep])
    rng = np.random.default_rng(0) if rng is None else rng
    w = rng.standard_normal((q.shape[1], FEATURES)) / length
    b = rng.uniform(0.0, 2.0 * np.pi, FEATURES)
    return np.sqrt(2.0 / FEATURES) * np.cos(q @ w + b)


def tool_fields(model: RobotModel, q: np.ndarray, length: float = LENGTH, rng: np.random.Generator | None = None):
    """Per joint, the tool-point field of a unit joint-angle error process at configurations ``q`` (K, n) [rad].

    Yields:
        (K, 3, r) ``dp/dq_j (q) L`` [m per rad of std], one array per joint ``j`` (one at a time: bounded memory).
    """
    root = field_root(q, length, rng)
    jac = joint_jacobian(model, q)  # (K, 3, n)
    for j in range(jac.shape[2]):
        yield jac[:, :, j, None] * root[:, None, :]


def draw(model: RobotModel, q: np.ndarray, std: float, draws: int, rng: np.random.Generator,
         length: float = LENGTH) -> np.ndarray:
    """(K, 3, draws) tool-point errors [m] of fresh draws of the joint-angle error (std ``std`` [rad]) at ``q``."""
    out = np.zeros((len(q), 3, draws))
    for field in tool_fields(model, q, length, rng):
        out += std * np.einsum("kir,rd->kid", field, rng.standard_normal((field.shape[2], draws)))
    return out
