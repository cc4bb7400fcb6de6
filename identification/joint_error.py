"""The arm's unmodelled joint-angle error: a smooth error of each joint's angle over joint space.

What no kinematic parameter describes on a revolute arm is mostly an error of its joint angles that varies
with the configuration (backlash that follows the load, gear transmission error, compliance the model
lacks). Each joint's angle error is modelled as a Gaussian process over joint space, prior std ``std`` [rad]
and squared-exponential kernel of length :data:`LENGTH` [rad], independent between joints; the tool point
sees it through the joint Jacobian::

    e(q) = sum_j  dp/dq_j (q) eps_j(q),     eps_j = L z_j,  L L^T = k(q, q),  z_j ~ N(0, I)

A calibration absorbs part of it into its parameters at the training configurations (a bias that does not
hold elsewhere) and leaves the rest in its residuals; at a socket it did not see, a fresh draw of it adds to
the spread, amplified by the lever arms there (:mod:`.prediction`). How much of a fit's residual is this error and how
much white noise, :func:`split` estimates by maximum likelihood.
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


def seen_fields(model: RobotModel, q: np.ndarray, data_jac: np.ndarray, length: float = LENGTH,
                rng: np.random.Generator | None = None):
    """Per joint, what a fit sees of the unit joint-angle error process at its samples, without forming the field.

    With ``F_j`` the (3 K, r) field of :func:`tool_fields` (same root, same ``rng`` draws) and ``J`` the samples'
    rows of the fit's Jacobian: ``J^T F_j = (sum_i J_ki dp_i/dq_j) L`` and ``|F_j|^2 = sum_k |dp_k/dq_j|^2
    |L_k|^2``, a (K, U) by (K, r) product instead of a (3 K, U) by (3 K, r) one on a (3 K, r) array.

    Args:
        model: the robot (the joint Jacobian).
        q: (K, n) the samples' joint angles [rad].
        data_jac: (3 K, U) the samples' rows of the fit's Jacobian, stacked ``x0 y0 z0 x1 ...``.
        length, rng: as :func:`tool_fields`.

    Yields:
        ``(J^T F_j, |F_j|^2, F_j rows)``: (U, r), a float, and a function of (S,) sample indices giving their
        (3 S, r) rows of ``F_j``, one joint at a time.
    """
    root = field_root(q, length, rng)
    jac = joint_jacobian(model, q)  # (K, 3, n)
    per_sample = data_jac.reshape(len(q), 3, -1)
    weight = np.einsum("kr,kr->k", root, root)
    for j in range(jac.shape[2]):
        gain = jac[:, :, j]  # (K, 3)
        seen = np.einsum("kiu,ki->ku", per_sample, gain).T @ root

        def rows(keep: np.ndarray, gain: np.ndarray = gain) -> np.ndarray:
            return (gain[keep, :, None] * root[keep, None, :]).reshape(3 * len(keep), -1)

        yield seen, float(np.einsum("ki,ki,k->", gain, gain, weight)), rows


def draw(model: RobotModel, q: np.ndarray, std: float, draws: int, rng: np.random.Generator,
         length: float = LENGTH) -> np.ndarray:
    """(K, 3, draws) tool-point errors [m] of fresh draws of the joint-angle error (std ``std`` [rad]) at ``q``."""
    out = np.zeros((len(q), 3, draws))
    for field in tool_fields(model, q, length, rng):
        out += std * np.einsum("kir,rd->kid", field, rng.standard_normal((field.shape[2], draws)))
    return out


#: :func:`split` takes the joint-angle error's std from the directions where the fit leaves at least this share of the
#: process's energy it leaves in the most visible one; in the others (the fit absorbs it nearly whole) any energy
#: above the white noise is no evidence of it. A 2 s MuJoCo recording (compliance noise 0.3 mm correlated over
#: 0.05 s, no joint-angle error) has its time-correlated noise's low frequencies there: counted, they read 85 mrad
#: per joint (1.0-2.4 mrad under the nominal's bound) and validate over-predicted its held-out sockets 2-3x; here
#: 0.32 mrad (median of 6), 1.30 mrad where the truth is 1 mrad (bench/prediction_sim.py). 0.1 also cuts it, but
#: moves MUKCa's panda_2 mid-high (trained alone) from 1.90x to 2.01x measured / predicted.
VISIBLE = 0.03
#: At most this many samples enter :func:`split` (a seeded random subset above it: the likelihood is cubic in them).
SPLIT_SAMPLES = 150


def split(
    model: RobotModel, q: np.ndarray, residual: np.ndarray, data_jac: np.ndarray, inverse: np.ndarray,
    length: float = LENGTH, rng: np.random.Generator | None = None,
) -> tuple[float, float]:
    """Maximum-likelihood split of a fit's sample residuals into white noise and the joint-angle error.

    The samples' errors ``e = n + sum_j dp/dq_j eps_j`` (white ``n``, std ``noise`` per coordinate; the process of
    the module docstring, std ``std``) leave ``r = M e`` in the residuals, ``M = I - J_d (J^T J)^-1 J_d^T`` (what the
    fit absorbs; ``J`` with every row of the problem, prior included). Both stds maximise the Gaussian likelihood
    of ``r`` over the space the fit leaves it (restricted maximum likelihood; the eigenvectors of ``M M^T`` above
    1/2): white noise spreads evenly over it, the process's smooth error concentrates in few directions. Its std is
    taken from the directions where the fit leaves it visibly (:data:`VISIBLE`), the white noise then from every
    direction at that std. Above :data:`SPLIT_SAMPLES` samples, a seeded random subset of them (their residuals'
    covariance still through the whole fit).

    Args:
        model: the robot (the joint Jacobian of the process's tool-point field).
        q: (K, n) the samples' joint angles [rad].
        residual: (3 K,) their residuals at the solution [m], stacked ``x0 y0 z0 x1 ...``.
        data_jac: (3 K, U) their rows of the fit's Jacobian [m per unknown].
        inverse: (U, U) ``(J^T J)^-1`` of the fit's whole Jacobian.
        length: the process's correlation length [rad].
        rng: seeds the subset and the process's features (default seed 0).

    Returns:
        ``(noise, std)``: the white noise std per coordinate [m] and the joint-angle error's std [rad] (0: none).
    """
    rng = np.random.default_rng(0) if rng is None else rng
    count = len(q)
    keep = np.sort(rng.choice(count, SPLIT_SAMPLES, replace=False)) if count > SPLIT_SAMPLES else np.arange(count)
    rows = (3 * keep[:, None] + np.arange(3)).ravel()
    sub = data_jac[rows] @ inverse  # (3 S, U)
    white = np.eye(len(rows)) - 2.0 * sub @ data_jac[rows].T + sub @ (data_jac.T @ data_jac) @ sub.T  # M_S M_S^T
    smooth = np.zeros_like(white)
    for seen, _, field_rows in seen_fields(model, q, data_jac, length, rng):
        absorbed = field_rows(keep) - sub @ seen  # M_S F
        smooth += absorbed @ absorbed.T
    values, vectors = np.linalg.eigh(0.5 * (white + white.T))
    # the space the fit leaves the residual (M's eigenvalues are 1 there, 0 along what it fits): without the directions
    # the fit half absorbs, where the prior's pull on an arm off nominal leaves a smooth residual that is no noise
    space = values > 0.5
    if not space.any():  # the fit leaves its residual no room: nothing to split
        return float(np.sqrt(np.mean(residual[rows] ** 2))), 0.0
    whiten = vectors[:, space] / np.sqrt(values[space])
    mu, turn = np.linalg.eigh(whiten.T @ smooth @ whiten)
    y2 = (turn.T @ (whiten.T @ residual[rows])) ** 2
    mu = np.clip(mu, 0.0, None)
    if mu[-1] <= 0 or not y2.any():
        return float(np.sqrt(y2.mean())), 0.0
    # the std where the fit leaves the process visibly (elsewhere its mu taken as 0: white noise alone), then the
    # white noise with every direction's share of that std (a process the fit leaves visibly also puts energy where
    # it barely does: 3 mrad moves the tool ~1.5 mm, which would read as 0.3 mm of white noise there)
    visible = np.where(mu >= VISIBLE * mu[-1], mu, 0.0)
    # cov = a (I + t diag(mu)) in the whitened basis: for each t the likelihood's a is mean(y^2 / (1 + t mu))
    ratios = np.concatenate([[0.0], np.geomspace(1e-4, 1e6, 241) / mu[-1]])
    scaled = 1.0 + ratios[:, None] * visible[None, :]
    a = (y2[None, :] / scaled).mean(axis=1)
    loglik = -0.5 * (len(y2) * np.log(a) + np.log(scaled).sum(axis=1))
    best = int(np.argmax(loglik))
    std2 = ratios[best] * a[best]
    # cov = a I + std^2 diag(mu) at that std: the likelihood over a on a grid about the first estimate
    noise2 = a[best] * np.geomspace(1e-4, 1e1, 201)
    total = noise2[:, None] + std2 * mu[None, :]
    loglik = -0.5 * (np.log(total) + y2[None, :] / total).sum(axis=1)
    return float(np.sqrt(noise2[int(np.argmax(loglik))])), float(np.sqrt(std2))
