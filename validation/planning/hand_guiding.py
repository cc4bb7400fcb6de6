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
from dataclasses import dataclass

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
    walk = _Walk.drawn(model, centres, count, rng, walkers, step, seeds, noise)
    return walk.samples(walk.reachable), walk.reachable


@dataclass(frozen=True)
class _Walk:
    """A hand-guided walk with every random number drawn (from the generator, in the order the walk takes them) but
    not yet walked: :meth:`samples` walks only the sockets asked for, and each walker's steps depend on its own
    draws alone, so a socket's samples are the same whichever others are walked beside it."""

    model: RobotModel
    start: np.ndarray  # (S * walkers, n) the most comfortable reach configurations
    reachable: np.ndarray  # (S,) bool
    moves: list[np.ndarray]  # per step: (S * walkers, n) random joint step before the null-space projection
    targets: list[np.ndarray]  # per step: (S * walkers, 3) where the step projects to (the socket, plus noise)
    count: int
    walkers: int

    @classmethod
    def drawn(cls, model, centres, count, rng, walkers, step, seeds, noise) -> _Walk:
        centres = np.atleast_2d(np.asarray(centres, float))
        s, n = centres.shape[0], model.n_joints
        targets = np.repeat(centres, seeds, axis=0)
        q, ok = project_to_point(model, model.random_configurations(s * seeds, rng), targets, freeze=True)
        share = np.minimum(q - model.lower, model.upper - q) / (model.upper - model.lower)
        margin = np.where(ok, share.min(axis=1), -np.inf).reshape(s, seeds)
        reachable = np.isfinite(margin).any(axis=1)
        best = np.argsort(-margin, axis=1)[:, :walkers]  # the most comfortable postures (an unreached one repeats)
        best = np.where(np.isfinite(np.take_along_axis(margin, best, axis=1)), best, best[:, :1])
        start = q.reshape(s, seeds, n)[np.arange(s)[:, None], best].reshape(s * walkers, n)
        goal = np.repeat(centres, walkers, axis=0)
        moves, goals = [], []
        for _ in range(math.ceil(count / walkers)):
            moves.append(rng.normal(0.0, step, start.shape))
            goals.append(goal + rng.normal(0.0, noise, goal.shape) if noise > 0 else goal)
        return cls(model, start, reachable, moves, goals, count, walkers)

    def samples(self, sockets: np.ndarray) -> np.ndarray:
        """(S, count, n) the walk's configurations at ``sockets`` (S,) bool; zeros at the others."""
        s, n = len(self.reachable), self.model.n_joints
        rows = np.flatnonzero(np.repeat(sockets, self.walkers))
        out = np.zeros((len(self.moves), s * self.walkers, n))
        current = self.start[rows]
        identity = np.eye(n)
        for k, (moves, targets) in enumerate(zip(self.moves, self.targets, strict=True)):
            if not len(rows):
                break
            jac = joint_jacobian(self.model, current)
            null = identity - np.linalg.pinv(jac) @ jac
            move = np.einsum("wij,wj->wi", null, moves[rows])
            trial, done = project_to_point(self.model, current + move, targets[rows], freeze=True)
            current = np.where(done[:, None], trial, current)
            out[k, rows] = current
        steps = len(self.moves)
        return out.reshape(steps, s, self.walkers, n).transpose(1, 0, 2, 3).reshape(s, steps * self.walkers, n)[
            :, : self.count
        ]


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

    Only those sockets are walked, only the reachable ones are carried over to, and a socket takes recorded postures
    (the first ``count``, then a quarter of that at a time) only until ``count`` of them have converged: the walk at
    a socket that is filled from the recording was overwritten (50 plate placements on a 3 x 500 sample recording
    walked 432 walkers through 167 steps of 60 Newton iterations each, all of it thrown away), an unreachable
    socket's rows are zeros, and postures past the first ``count`` that converge are not used (a posture's steps do
    not depend on the others moved with it). The generator is drawn as before (the walk's draws, then the subset),
    so the samples are the same.

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
    walk = _Walk.drawn(model, centres, count, rng, WALKERS, STEP, SEEDS, 0.0)
    reachable = walk.reachable
    chosen = recorded[rng.permutation(len(recorded))[: 2 * count]]
    found: list[list[np.ndarray]] = [[] for _ in centres]  # per socket: the converged postures, in chosen order
    short, start, size = reachable.copy(), 0, count
    while short.any() and start < len(chosen):  # the first ``count`` rows, then quarters, to the sockets still short
        rows, sockets = chosen[start : start + size], np.flatnonzero(short)
        targets = np.repeat(centres[sockets], len(rows), axis=0)
        q, ok = project_to_point(model, np.tile(rows, (len(sockets), 1)), targets, freeze=True)
        q, ok = q.reshape(len(sockets), len(rows), -1), ok.reshape(len(sockets), len(rows))
        for j, i in enumerate(sockets):
            found[i].append(q[j][ok[j]])
        short[sockets] = [sum(map(len, found[i])) < count for i in sockets]
        start, size = start + size, max(count // 4, 1)
    out = walk.samples(short)
    for i in np.flatnonzero(reachable):
        mine = np.concatenate([np.zeros((0, model.n_joints)), *found[i]])[:count]
        out[i, : len(mine)] = mine
    return out, reachable
