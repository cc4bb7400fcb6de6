"""Our Levenberg-Marquardt against scipy's MINPACK (``least_squares(method='lm')``) on simulated
calibrations: the same minimum (cost to 1e-9 relative, every unknown within its std / 100) in fewer
Jacobian evaluations; a hard start converges; an exhausted budget says so."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import least_squares

from spherecal.correction import load_robot, perturb
from spherecal.identification.build import build_problem
from spherecal.identification.identifiability import predicted_std
from spherecal.identification.levenberg import gauss_newton, levenberg_marquardt
from spherecal.identification.solvers import solve_lm
from spherecal.identification.synthetic import make_dataset


@pytest.fixture(scope="module")
def truth():
    panda = load_robot("panda")
    return panda, perturb(panda, np.random.default_rng(1))


def _data(true, noise: float, fixtures: int, per_fixture: int = 150):
    dataset, spec = make_dataset(true, per_fixture=per_fixture, rng=np.random.default_rng(2), noise=noise)
    names = dataset.fixture_names[:fixtures]
    dataset = replace(dataset.select(np.flatnonzero(np.isin(dataset.labels, names))), fixture_names=names)
    return dataset, replace(spec, names=names, distances=[d for d in spec.distances if d[0] in names and d[1] in names])


def _reference(problem, x0):
    """scipy's MINPACK LM at tight tolerances, and the std of every unknown there."""
    ref = least_squares(
        problem.residuals, x0, jac=problem.jacobian, method="lm", x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12
    )
    sigma = np.sqrt(2 * ref.cost / (problem.n_residuals - problem.n_unknowns))
    return ref, predicted_std(problem.jacobian(ref.x), max(sigma, 1e-6))


def _assert_same_minimum(problem, ours, ref, std) -> None:
    assert ours.converged, ours.message
    assert ours.cost <= ref.cost * (1 + 1e-9) + 1e-24  # noise-free: both at the rounding floor (~1e-20)
    assert ref.cost <= ours.cost * (1 + 1e-9) + 1e-24
    assert np.all(np.abs(ours.x - ref.x) <= std / 100), problem.unknown_names[np.argmax(np.abs(ours.x - ref.x) / std)]


@pytest.mark.parametrize(
    ("noise", "fixtures", "distances"),
    [(0.0, 3, True), (3e-4, 3, True), (3e-4, 3, False), (3e-4, 2, True), (3e-4, 1, False), (0.0, 1, False)],
)
def test_same_minimum_as_scipy_in_fewer_jacobians(truth, noise, fixtures, distances) -> None:
    panda, true = truth
    dataset, spec = _data(true, noise, fixtures)
    problem = build_problem(panda, dataset, spec if distances else None)
    ref, std = _reference(problem, problem.x0)
    ours = levenberg_marquardt(problem.residuals, problem.jacobian, problem.x0)
    _assert_same_minimum(problem, ours, ref, std)
    assert ours.jacobians < ref.njev, (ours.jacobians, ref.njev)
    assert ours.cost <= 0.5 * float(problem.residuals(problem.x0) @ problem.residuals(problem.x0))


def test_hayati_model(truth) -> None:
    panda, _ = truth
    nominal = replace(panda, beta=np.zeros(panda.n_joints), hayati=(1, 3))
    true = perturb(nominal, np.random.default_rng(4))
    dataset, spec = make_dataset(true, per_fixture=150, rng=np.random.default_rng(5), noise=3e-4)
    problem = build_problem(nominal, dataset, spec)
    assert any(name.startswith("beta") for name in problem.identified)
    ref, std = _reference(problem, problem.x0)
    # Hayati betas on joints 2 and 4 of the Panda (axes not nearly parallel): a flat, curved valley where
    # scipy's own end point depends on its start (from ours it stays 0.14 std from where it ends from x0).
    # What holds: the same cost, and ours is a minimum (scipy continuing from it moves < std / 100).
    ours = levenberg_marquardt(problem.residuals, problem.jacobian, problem.x0)
    assert ours.converged and abs(ours.cost / ref.cost - 1) <= 1e-9
    again, _ = _reference(problem, ours.x)
    assert np.all(np.abs(again.x - ours.x) <= std / 100)


def test_hard_start_converges_to_the_same_minimum(truth) -> None:
    panda, true = truth
    dataset, spec = _data(true, 3e-4, 3)
    problem = build_problem(panda, dataset, spec)
    far = perturb(panda, np.random.default_rng(9), 3e-2, np.deg2rad(6.0), 3e-2)  # 30x a real arm's errors
    x0 = problem.start_from(far)
    ref, std = _reference(problem, x0)
    ours = levenberg_marquardt(problem.residuals, problem.jacobian, x0)
    _assert_same_minimum(problem, ours, ref, std)
    # plain Gauss-Newton: the floor, no safeguard; ours needs no more Jacobians than it does here
    floor = gauss_newton(problem.residuals, problem.jacobian, x0)
    assert floor.converged and ours.jacobians <= floor.jacobians


def test_budget_used_up_says_not_converged(truth) -> None:
    panda, true = truth
    dataset, spec = _data(true, 3e-4, 3)
    problem = build_problem(panda, dataset, spec)
    x0 = problem.start_from(perturb(panda, np.random.default_rng(9), 3e-2, np.deg2rad(6.0), 3e-2))
    ours = levenberg_marquardt(problem.residuals, problem.jacobian, x0, max_jacobians=1)
    assert not ours.converged and "did not converge in 1 Jacobian" in ours.message
    start = problem.residuals(x0)
    assert ours.cost < 0.5 * float(start @ start)  # the one step it took lowered the cost


def test_cost_never_rises_on_a_wild_start() -> None:
    """Rosenbrock as least squares from its classic start: curved valley, the full Gauss-Newton step
    overshoots; every accepted point lowers the cost and it ends at (1, 1)."""
    costs: list[float] = []

    def residuals(x):
        r = np.array([10 * (x[1] - x[0] ** 2), 1 - x[0]])
        costs.append(0.5 * float(r @ r))
        return r

    def jacobian(x):
        return np.array([[-20 * x[0], 10.0], [-1.0, 0.0]])

    accepted: list[float] = []
    ours = levenberg_marquardt(residuals, lambda x: (accepted.append(costs[-1]), jacobian(x))[1], [-1.2, 1.0])
    assert ours.converged, ours.message
    assert np.allclose(ours.x, [1.0, 1.0], atol=1e-8)
    assert np.all(np.diff(accepted) < 0)  # the cost at every new Jacobian is below the one before


def test_solve_lm_uses_ours_without_scipy_for_the_plain_loss(truth) -> None:
    panda, true = truth
    dataset, spec = _data(true, 3e-4, 3)
    problem = build_problem(panda, dataset, spec)
    solution = solve_lm(problem)
    ref, std = _reference(problem, problem.x0)
    assert solution.converged and solution.jacobians < ref.njev
    assert np.all(np.abs(solution.x - ref.x) <= std / 100)


@pytest.mark.parametrize("loss", ["soft_l1", "huber"])
def test_a_robust_loss_through_ours_reaches_scipys_robust_minimum(truth, loss) -> None:
    """The robust losses as plain least squares on ``f sign(r) sqrt(rho(r^2 / f^2))`` (solvers.robust_residuals):
    the same cost as scipy's with that loss, the slope of the transform against finite differences; on the samples'
    rows of data with outliers, ours reaches MINPACK's minimum of the same objective within std / 100."""
    from scipy.optimize import least_squares

    from spherecal.identification.solvers import robust_residuals, solve_scipy

    panda, true = truth
    dataset, spec = _data(true, 3e-4, 3)
    q = dataset.q.copy()
    q[::25, 3] += 0.02  # every 25th sample 20 mrad off on joint 4: outliers of ~10 mm
    dataset = replace(dataset, q=q)
    problem = build_problem(panda, dataset, spec)
    x = problem.x0 + 1e-4
    r = problem.residuals(x)
    scipy_cost = least_squares(problem.residuals, x, loss=loss, f_scale=problem.noise, max_nfev=1).cost
    t, slope = robust_residuals(r, loss, problem.noise)
    assert np.isclose(0.5 * t @ t, scipy_cost, rtol=1e-12)
    step = 1e-9  # the slope against finite differences of t(r)
    ahead = robust_residuals(r + step, loss, problem.noise)[0]
    assert np.allclose((ahead - t) / step, slope, rtol=1e-4, atol=1e-6)
    ours = solve_lm(problem, loss=loss)
    reference = solve_scipy(problem, problem.x0, loss)
    _, std = _reference(problem, problem.x0)
    assert ours.converged and "scipy" not in ours.message, ours.message
    assert ours.jacobians < reference.jacobians  # scipy alone took them all before
    gap = ours.x - reference.x  # an angle a turn apart is the same arm (MINPACK wanders along a flat one)
    angle = np.array([n in problem.identified and panda.layout.is_angle(n) for n in problem.unknown_names])
    gap[angle] = (gap[angle] + np.pi) % (2 * np.pi) - np.pi
    assert np.all(np.abs(gap) <= std / 100)


def test_elastic_calibration_same_as_with_scipy(truth, monkeypatch) -> None:
    """The whole lm pipeline on the elastic model (joint compliances free; their analytic Jacobian is
    first order, so the first, unpruned solve wanders): ours ends where scipy's MINPACK ends."""
    from spherecal.identification import calibrate as pipeline
    from spherecal.identification.selection import elastic_start
    from spherecal.identification.solvers import solve_scipy

    panda, true = truth
    dataset, spec = _data(true, 3e-4, 3, per_fixture=200)
    ours = pipeline.calibrate(elastic_start(panda), dataset, spec, check=False)
    monkeypatch.setattr(pipeline, "solve_lm",
                        lambda problem, x0, loss, f_scale=None: solve_scipy(problem, x0, loss, f_scale))
    ref = pipeline.calibrate(elastic_start(panda), dataset, spec, check=False)
    assert ours.identified == ref.identified and any(n.startswith("c") for n in ours.identified)
    cost = [float(r @ r) for r in (res.problem.residuals(res.x) for res in (ours, ref))]
    assert abs(cost[0] / cost[1] - 1) <= 1e-9
    std = np.array([ref.std[name] for name in ref.problem.unknown_names])
    assert np.all(np.abs(ours.x - ref.x) <= std / 100)


def test_gauss_newton_step_is_lstsq_on_a_rank_deficient_jacobian() -> None:
    """At the nominal design a calibration Jacobian can be exactly rank deficient (a singular value at
    rounding level): the step is lstsq's minimum-norm solution, not a huge step along the blind direction."""
    from spherecal.identification.levenberg import _Linearisation

    rng = np.random.default_rng(3)
    jac = rng.normal(size=(300, 6))
    jac = np.column_stack([jac, jac[:, 2] - 0.5 * jac[:, 4] + 1e-15 * rng.normal(size=300)])  # rank 6 of 7
    scaled = jac / np.linalg.norm(jac, axis=0)
    r = rng.normal(size=300)
    expected = np.linalg.lstsq(scaled, -r, rcond=None)[0]
    assert np.allclose(_Linearisation(scaled, r).step(0.0), expected, atol=1e-9)
