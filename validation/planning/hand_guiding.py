"""Configurations a person records at a socket by hand guiding, made kinematically (no simulator).

A person puts the ball in the socket in a comfortable posture and pushes the arm through its
self-motion, pressing the button now and then. Here: for each socket, the reach configurations
furthest from the joint limits (random seeds projected onto the socket by damped Newton steps,
:func:`identification.synthetic.project_to_point`) start ``walkers`` random walks; every step moves
each walker by a random joint step projected onto the null space of its tool-point Jacobian
(``dq = (I - J^+ J) z``, ``z ~ N(0, step^2 I)``), then projects it back onto the socket inside the
joint limits (a step that does not converge is not taken). Every socket of every candidate is
walked in one batch.
"""

from __future__ import annotations

import math

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian
from spherecal.identification.synthetic import project_to_point

#: Random seeds per socket for its reach configurations.
SEEDS = 48
#: Walks per socket (postures a person starts from).
WALKERS = 3
#: Standard deviation of a walk's random joint step before the null-space projection [rad].
STEP = 0.35


def hand_guided(
    model: RobotModel,
    centres: np.ndarray,
    count: int,
    rng: np.random.Generator,
    walkers: int = WALKERS,
    step: float = STEP,
    seeds: int = SEEDS,
    noise: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Hand-guided self-motion samples at each socket (see the module docstring).

    Args:
        model: the robot (its current model: where the user's arm really is).
        centres: (S, 3) socket centres in the base frame [m].
        count: samples per socket.
        rng: seeded generator.
        walkers: walks per socket.
        step: random joint step [rad].
        seeds: random start configurations per socket.
        noise: fixture noise [m]: each recorded sample's tool point is off the socket by a Gaussian of this
            std per axis (a simulated recording; 0 for planning).

    Returns:
        (S, count, n) configurations [rad] inside the joint limits, and (S,) bool: the socket is
        reachable (the rows of an unreachable socket are zeros).
    """
    centres = np.atleast_2d(np.asarray(centres, float))
    s, n = centres.shape[0], model.n_joints
    targets = np.repeat(centres, seeds, axis=0)
    q, ok = project_to_point(model, model.random_configurations(s * seeds, rng), targets, freeze=True)
    share = np.minimum(q - model.lower, model.upper - q) / (model.upper - model.lower)
    margin = np.where(ok, share.min(axis=1), -np.inf).reshape(s, seeds)
    reachable = np.isfinite(margin).any(axis=1)
    best = np.argsort(-margin, axis=1)[:, :walkers]  # the most comfortable postures (an unreached one repeats)
    best = np.where(np.isfinite(np.take_along_axis(margin, best, axis=1)), best, best[:, :1])
    current = q.reshape(s, seeds, n)[np.arange(s)[:, None], best].reshape(s * walkers, n)
    goal = np.repeat(centres, walkers, axis=0)
    steps = math.ceil(count / walkers)
    out = np.empty((steps, s * walkers, n))
    identity = np.eye(n)
    for k in range(steps):
        jac = joint_jacobian(model, current)
        null = identity - np.linalg.pinv(jac) @ jac
        move = np.einsum("wij,wj->wi", null, rng.normal(0.0, step, current.shape))
        target = goal + rng.normal(0.0, noise, goal.shape) if noise > 0 else goal
        trial, done = project_to_point(model, current + move, target, freeze=True)
        current = np.where(done[:, None], trial, current)
        out[k] = current
    samples = out.reshape(steps, s, walkers, n).transpose(1, 0, 2, 3).reshape(s, steps * walkers, n)[:, :count]
    samples[~reachable] = 0.0
    return samples, reachable


def carried_over(
    model: RobotModel,
    centres: np.ndarray,
    recorded: np.ndarray,
    count: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """The postures the person has recorded so far, carried over to each new socket: recorded configurations (a
    random subset of at most ``2 count``: a long recording costs no more than twice the walk) moved onto the socket
    by damped Newton steps (the nearest configuration there, inside the joint limits); a socket where fewer than
    ``count`` of them converge is filled up from :func:`hand_guided`'s walk.

    Args:
        model: the robot (its current model).
        centres: (S, 3) socket centres in the base frame [m].
        recorded: (K, n) the recorded configurations [rad].
        count: samples per socket.
        rng: seeded generator (which recorded configurations, in which order; the walk).

    Returns:
        (S, count, n) configurations [rad] inside the joint limits, and (S,) bool: the socket is reachable
        (as :func:`hand_guided`; the rows of an unreachable socket are zeros).
    """
    centres = np.atleast_2d(np.asarray(centres, float))
    walked, reachable = hand_guided(model, centres, count, rng)
    chosen = recorded[rng.permutation(len(recorded))[: 2 * count]]
    s, k = centres.shape[0], len(chosen)
    q, ok = project_to_point(model, np.tile(chosen, (s, 1)), np.repeat(centres, k, axis=0), freeze=True)
    q, ok = q.reshape(s, k, -1), ok.reshape(s, k)
    out = walked.copy()
    for i in np.flatnonzero(reachable):
        mine = q[i][ok[i]][:count]
        out[i, : len(mine)] = mine
    return out, reachable
