"""Spherical-joint samples made purely kinematically (no simulator): test data for identification.

Each sample is a random configuration inside the joint limits projected onto ``p_true(q) = c_j``
(plus optional Gaussian fixture noise on ``c_j``, drawn per sample) by damped Newton steps on the
true model's joint Jacobian. Random seeds spread the samples over the self-motion manifold.
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset

#: Fixture centres for the Panda [m] in its base frame: three points spread around the robot (low in
#: front, to the side, high on the other side) with a wide self-motion, in the spirit of the paper's
#: P1-P3. Spread matters: at 0.3 mm noise over six true robots this layout gives 0.036-0.051 mm mean
#: and <= 0.131 mm max workspace error; three points 0.35-0.45 m in front give about twice that.
PANDA_FIXTURES: dict[str, tuple[float, float, float]] = {
    "P1": (0.5, 0.1, 0.0),
    "P2": (-0.1, 0.5, 0.4),
    "P3": (0.35, -0.35, 0.75),
}


def project_to_point(
    model: RobotModel,
    q: np.ndarray,
    targets: np.ndarray,
    iterations: int = 60,
    damping: float = 1e-4,
    tol: float = 1e-12,
    freeze: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Move every configuration so that its tool point reaches its target.

    Damped Newton (Levenberg) steps ``dq = J^T (J J^T + damping^2 I)^-1 (target - p)``, clipped
    to the joint limits after every step.

    Args:
        model: the robot.
        q: (N, n) start configurations [rad].
        targets: (N, 3) or (3,) target points [m].
        iterations: maximum number of steps.
        damping: damping [m].
        tol: a configuration has converged when its tool point is this close [m].
        freeze: a configuration that has converged takes no more steps, and only the others iterate (a batch with an
            unreachable target otherwise steps every row to the last iteration: plan --plate-grid auto, 28 -> 15 s).
            False: every row steps until all have converged, as the seeded simulations' samples were drawn.

    Returns:
        (N, n) configurations [rad] and (N,) bool: converged inside the joint limits.
    """
    q = np.array(q, dtype=float)
    targets = np.broadcast_to(np.asarray(targets, float), (q.shape[0], 3))
    active = np.arange(q.shape[0])
    for _ in range(iterations):
        error = targets[active] - tool_point(model, q[active])
        moving = np.einsum("ij,ij->i", error, error) >= tol**2
        if not moving.any():
            break
        if freeze:
            active, error = active[moving], error[moving]
        jac = joint_jacobian(model, q[active])
        gram = jac @ jac.transpose(0, 2, 1) + damping**2 * np.eye(3)
        step = np.einsum("nij,ni->nj", jac, np.linalg.solve(gram, error[..., None])[..., 0])
        q[active] = np.clip(q[active] + step, model.lower, model.upper)
    converged = np.linalg.norm(targets - tool_point(model, q), axis=1) < max(tol, 1e-10)
    return q, converged


def fixture_samples(
    model: RobotModel,
    centre: np.ndarray,
    count: int,
    rng: np.random.Generator,
    noise: float = 0.0,
    max_rounds: int = 20,
) -> np.ndarray:
    """Configurations whose tool point sits at ``centre`` (+ noise) on the true model.

    Args:
        model: the true robot.
        centre: (3,) fixture centre [m].
        count: number of samples.
        rng: seeded generator.
        noise: std of the Gaussian fixture noise added to the centre per sample [m].
        max_rounds: rounds of random seeds before giving up.

    Returns:
        (count, n) joint angles [rad] inside the joint limits.

    Raises:
        ValueError: the centre is not reachable often enough from random seeds.
    """
    kept: list[np.ndarray] = []
    have = 0
    for _ in range(max_rounds):
        seeds = model.random_configurations(2 * count, rng)
        targets = np.asarray(centre, float) + rng.normal(0.0, noise, (seeds.shape[0], 3))
        q, ok = project_to_point(model, seeds, targets)
        kept.append(q[ok])
        have += int(ok.sum())
        if have >= count:
            return np.concatenate(kept)[:count]
    raise ValueError(f"fixture at {np.asarray(centre).tolist()}: only {have} of {count} samples reached")


def make_dataset(
    model: RobotModel,
    centres: dict[str, np.ndarray] | None = None,
    per_fixture: int = 500,
    rng: np.random.Generator | None = None,
    noise: float = 0.0,
) -> tuple[Dataset, FixtureSpec]:
    """Samples at every fixture and the spec with all centre-to-centre distances known.

    Args:
        model: the true robot.
        centres: name -> (3,) centre [m]; the Panda layout :data:`PANDA_FIXTURES` by default.
        per_fixture: samples per fixture.
        rng: seeded generator (default seed 0).
        noise: fixture noise std [m].

    Returns:
        The dataset (fixtures in the order given) and a :class:`FixtureSpec` with unknown
        positions and every pairwise distance (exact, from the true centres).
    """
    rng = np.random.default_rng(0) if rng is None else rng
    centres = {k: np.asarray(v, float) for k, v in (centres or PANDA_FIXTURES).items()}
    names = tuple(centres)
    q = [fixture_samples(model, centres[name], per_fixture, rng, noise) for name in names]
    labels = np.repeat(np.array(names), per_fixture)
    dataset = Dataset(labels=labels, q=np.concatenate(q), fixture_names=names)
    distances = [
        (a, b, float(np.linalg.norm(centres[a] - centres[b]))) for i, a in enumerate(names) for b in names[i + 1 :]
    ]
    return dataset, FixtureSpec(names=names, distances=distances)


def unseated(model: RobotModel, dataset: Dataset, centres: dict[str, np.ndarray], count: int, offset: float,
             rng: np.random.Generator) -> Dataset:
    """``dataset`` with the first ``count`` presses of every fixture taken before the ball sat in its socket:
    their tool point (on the true ``model``) ``offset`` [m] from the centre, in a random direction.

    Args:
        model: the true robot.
        dataset: the samples (from :func:`make_dataset` on ``model``).
        centres: name -> (3,) fixture centre [m], every fixture of ``dataset``.
        count: presses per fixture to move.
        offset: how far [m].
        rng: seeded generator.
    """
    q = dataset.q.copy()
    for name in dataset.fixture_names:
        for row in np.flatnonzero(dataset.labels == name)[:count]:
            direction = rng.normal(size=3)
            q[row] = fixture_samples(model, np.asarray(centres[name]) + offset * direction / np.linalg.norm(direction),
                                     1, rng)[0]
    return Dataset(labels=dataset.labels, q=q, fixture_names=dataset.fixture_names, source=dataset.source)
