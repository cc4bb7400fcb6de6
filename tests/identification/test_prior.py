"""The prior toward the nominal model (MAP): rows, Jacobian, effective unknowns, and its pull."""

import numpy as np

from spherecal.correction import load_robot, perturb
from spherecal.identification.build import build_problem
from spherecal.identification.calibrate import calibrate
from spherecal.identification.identifiability import normal_inverse
from spherecal.identification.synthetic import make_dataset


def _data(seed=21, per_fixture=60):
    panda = load_robot("panda")
    truth = perturb(panda, np.random.default_rng(seed))
    dataset, spec = make_dataset(truth, per_fixture=per_fixture, rng=np.random.default_rng(seed + 1), noise=3e-4)
    return panda, dataset, spec


def test_prior_rows_jacobian_and_effective_unknowns():
    panda, dataset, spec = _data()
    problem = build_problem(panda, dataset, spec, prior_weight=0.5)
    plain = build_problem(panda, dataset, spec)
    assert problem.n_prior == problem.n_free_params and problem.n_residuals == plain.n_residuals + problem.n_prior
    x = problem.x0 + np.random.default_rng(0).normal(0, 1e-4, problem.n_unknowns)
    jac, h = problem.jacobian(x), 1e-7
    rows = problem.prior_rows()
    for k in range(problem.n_free_params):  # the prior rows against central differences of the residuals
        e = np.zeros_like(x)
        e[k] = h
        fd = (problem.residuals(x + e) - problem.residuals(x - e)) / (2 * h)
        np.testing.assert_allclose(jac[rows, k], fd[rows], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(problem.residuals(x)[~rows], plain.residuals(x), atol=1e-15)
    data = jac[~rows]
    hat = data @ normal_inverse(jac) @ data.T  # explicit hat matrix of the data rows
    assert abs(problem.effective_unknowns(jac) - np.trace(hat)) < 1e-8
    assert problem.effective_unknowns(jac) < problem.n_unknowns == plain.effective_unknowns(plain.jacobian(x))


def test_weight_zero_is_least_squares_and_a_heavy_prior_holds_nominal():
    panda, dataset, spec = _data()
    plain = calibrate(panda, dataset, spec, check=False)
    zero = calibrate(panda, dataset, spec, check=False, prior=0.0)
    np.testing.assert_array_equal(plain.model.params, zero.model.params)
    light = calibrate(panda, dataset, spec, check=False, prior=0.5)
    heavy = calibrate(panda, dataset, spec, check=False, prior=1e6)
    spread = panda.layout.spread()
    free = [panda.param_index(n) for n in heavy.identified]
    moved = lambda r: np.abs((r.model.params - panda.params)[free] / spread[free]).max()  # noqa: E731
    assert moved(heavy) < 0.05 < moved(plain)  # in prior spreads
    for name in light.identified:  # the posterior is narrower than the likelihood alone
        assert light.std[name] <= plain.std.get(name, np.inf) * (1 + 1e-9)
    assert light.block()["prior_weight"] == 0.5 and plain.block()["prior_weight"] == 0.0
