"""The prior toward the nominal model (MAP): rows, Jacobian, effective unknowns, its pull, and its heavy tail."""

from dataclasses import replace

import numpy as np

from spherecal.correction import load_robot, perturb, tool_point
from spherecal.identification.build import build_problem
from spherecal.identification.calibrate import calibrate
from spherecal.identification.identifiability import normal_inverse, predicted_std
from spherecal.identification.problem import PRIOR
from spherecal.identification.selection import start_for
from spherecal.identification.solvers import solve_lm
from spherecal.identification.synthetic import fixture_samples, make_dataset


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
    # the posterior is narrower than the likelihood alone, for the same unknowns (pruning may free another set: a
    # weakly seen parameter the prior holds is kept, one the data alone cannot see is fixed)
    likelihood = replace(light.problem, prior_weight=0.0, prior_centre=None, prior_curvature=None, _cache={})
    x, n = light.x, light.problem.n_free_params
    noise = light.problem.noise
    alone = dict(zip(light.identified, predicted_std(likelihood.jacobian(x), noise)[:n], strict=True))
    posterior = dict(zip(light.identified, predicted_std(light.problem.jacobian(x), noise)[:n], strict=True))
    for name in light.identified:
        assert posterior[name] <= alone[name] * (1 + 1e-9)
    assert any(posterior[name] < 0.5 * alone[name] for name in light.identified)  # and much narrower somewhere
    assert light.block()["prior_weight"] == 0.5 and plain.block()["prior_weight"] == 0.0


#: The tail measured in bench/prior_tail.py [prior spreads] (the library's default is the Gaussian prior).
TAIL = 3.0


def test_tail_rows_match_finite_differences_and_reweighting_keeps_the_solution():
    panda, dataset, spec = _data()
    problem = build_problem(panda, dataset, spec, prior_weight=0.5, prior_tail=TAIL)
    gauss = build_problem(panda, dataset, spec, prior_weight=0.5)
    assert problem.prior_tail == TAIL and gauss.prior_tail == np.inf
    spread = panda.layout.spread()[problem.free]
    z = np.linspace(-8.0, 8.0, problem.n_free_params) + 0.1  # deviations inside and far beyond the core [spreads]
    x = problem.pack(panda.params, problem.centres)
    x[: problem.n_free_params] += z * spread
    rows = problem.prior_rows()
    jac, h = problem.jacobian(x), 1e-9
    for k in range(problem.n_free_params):
        e = np.zeros_like(x)
        e[k] = h
        fd = (problem.residuals(x + e) - problem.residuals(x - e)) / (2 * h)
        np.testing.assert_allclose(jac[rows, k], fd[rows], rtol=1e-5, atol=1e-9)
    inside = np.abs(z) <= TAIL  # the core is the Gaussian prior, the tail costs less
    r, rg = problem.residuals(x)[rows], gauss.residuals(x)[rows]
    np.testing.assert_allclose(r[inside], rg[inside], rtol=1e-12)
    assert np.all(np.abs(r[~inside]) < np.abs(rg[~inside]))
    frozen = problem.reweighted(x)  # IRLS rows: the same gradient, the tail's curvature
    np.testing.assert_allclose(frozen.jacobian(x).T @ frozen.residuals(x), jac.T @ problem.residuals(x),
                               rtol=1e-10, atol=1e-18)
    weights = frozen.prior_curvature[problem.free]
    np.testing.assert_allclose(weights, np.minimum(1.0, TAIL**2 / z**2))
    assert gauss.reweighted(x) is gauss


def test_an_arm_within_the_core_sees_the_gaussian_prior():
    panda, dataset, spec = _data()
    tail = calibrate(panda, dataset, spec, check=False, prior=0.5, prior_tail=TAIL)
    gauss = calibrate(panda, dataset, spec, check=False, prior=0.5)
    z = (tail.model.params - panda.params) / panda.layout.spread()
    assert np.abs(z).max() <= TAIL
    np.testing.assert_allclose(tail.model.params, gauss.model.params, atol=1e-12)
    assert tail.block()["prior_tail_spreads"] == TAIL and gauss.block()["prior_tail_spreads"] is None


def test_a_joint_zero_far_off_is_found_as_an_offset_not_a_scale():
    # one placement (two sockets 50 mm apart, q4 within +-0.3 rad): under a Gaussian prior a joint-4 zero 6 spreads
    # off is partly explained by the joint-4 scale s4 q4 (cheaper than the offset), which is wrong at other q4
    panda = load_robot("panda")
    plate = {"front_h0": (0.5, -0.025, 0.15), "front_h1": (0.5, 0.025, 0.15)}
    i4 = panda.param_index("theta4")
    rng = np.random.default_rng(3)
    truth = perturb(panda, rng)
    params = truth.params.copy()
    params[i4] = panda.params[i4] - 6 * panda.layout.spread()[i4]
    truth = truth.with_params(params)
    dataset, spec = make_dataset(truth, plate, per_fixture=100, rng=rng, noise=1e-4)
    sockets = [fixture_samples(truth, c, 30, rng) for c in tool_point(truth, truth.random_configurations(6, rng))]

    def held_out(model):  # mean spread of the predicted points at sockets the fit never saw [m]
        return np.mean([np.linalg.norm(p - p.mean(axis=0), axis=1).mean() for p in
                        (tool_point(model, q) for q in sockets)])

    fits = {tail: calibrate(start_for("scale", panda), dataset, spec, check=False, prior=PRIOR, prior_tail=tail)
            for tail in (TAIL, np.inf)}
    s4 = {t: abs(f.model.params[f.model.layout.scale][3]) for t, f in fits.items()}
    off = {t: abs(f.model.params[i4] - truth.params[i4]) for t, f in fits.items()}
    assert held_out(fits[TAIL].model) < 0.8 * held_out(fits[np.inf].model)
    assert s4[TAIL] < 0.6 * s4[np.inf] and off[TAIL] < 0.6 * off[np.inf]
    assert "theta4" in fits[TAIL].summary().split("beyond the prior's 3-spread core")[1].splitlines()[0]


def test_data_share_is_how_little_the_estimate_follows_the_prior():
    """Each parameter's data share against an independent reading: move the prior's centre of that parameter by
    ``delta`` and solve again; the estimate follows by ``(1 - share) delta`` (the prior's part of it). A compliance
    gravity does not load (a vertical first joint: ``c1``) has share 0; the shares and one per centre coordinate sum to
    the effective unknowns; the summary names the parameters the prior holds."""
    panda = load_robot("panda")
    truth = perturb(panda, np.random.default_rng(5))  # quiet data, as a real Panda's (0.1 mm): pruning keeps c1
    dataset, spec = make_dataset(truth, per_fixture=40, rng=np.random.default_rng(6), noise=1e-4)
    elastic = start_for("elastic", panda)
    result = calibrate(elastic, dataset, spec, check=False, loss="linear", prior=PRIOR)
    problem, x = result.problem, result.x
    share = problem.data_share(problem.jacobian(x))
    centre_coords = problem.n_unknowns - problem.n_free_params
    assert abs(share.sum() + centre_coords - result.effective_unknowns) < 1e-6
    assert result.data_share == dict(zip(result.identified, share.tolist(), strict=True))
    names = list(result.identified)
    assert result.data_share["c1"] < 1e-6 and result.data_share["c2"] > 0.3 and result.data_share["tool_x"] > 0.99
    spread = elastic.layout.spread()
    for name in ("c1", "c6", "alpha7", "theta6", "d6", "c4", "c2"):  # shares 0 .. 0.99
        i, k = elastic.param_index(name), names.index(name)
        delta = 0.5 * spread[i]
        centre = problem.prior_centre.copy()
        centre[i] += delta
        moved = solve_lm(replace(problem, prior_centre=centre, _cache={}), x).x
        followed = (moved[k] - x[k]) / delta
        assert abs(followed - (1.0 - share[k])) < 0.02, (name, followed, share[k])
    assert "held by the prior (the data gives under 10 % of the estimate): c1" in result.summary()
    # the summary's effective unknowns count the centres too, and says so (a review read them as parameters)
    assert (f"({result.effective_unknowns:.1f} effective unknowns with the {centre_coords} fixture centre "
            "coordinates)") in result.summary()


def _noisy_panda(noise, seed=5, per_fixture=40):
    panda = load_robot("panda")
    truth = perturb(panda, np.random.default_rng(seed))
    dataset, spec = make_dataset(truth, per_fixture=per_fixture, rng=np.random.default_rng(seed + 1), noise=noise)
    return panda, dataset, spec


def test_the_prior_is_weighed_at_the_noise_the_residuals_show_when_above_the_default():
    from spherecal.identification.calibrate import prior_at_shown_noise
    from spherecal.identification.fixture_noise import fixture_noise
    from spherecal.identification.problem import NOISE, ZERO_TOLERANCE, prior_std, zero_indices

    panda, dataset, spec = _noisy_panda(1.2e-3)
    problem = build_problem(panda, dataset, spec, prior_weight=PRIOR)
    x = solve_lm(problem, problem.x0).x
    level = fixture_noise(problem, x).level
    assert level > 2 * NOISE  # 1.2 mm of noise shows as such
    honest = prior_at_shown_noise(problem, level)
    assert honest.prior_noise == level and honest.noise == problem.noise  # the checks keep the default noise
    # the prior rows by hand: sqrt(W) level (p - p0) / s, s the prior spread but 1 deg on the zeros
    params = problem.unpack(x)[0]
    spread = prior_std(panda)
    spread[zero_indices(panda)] = ZERO_TOLERANCE
    free = honest.free
    expected = np.sqrt(PRIOR) * level * (params - panda.params)[free] / spread[free]
    rows = honest.prior_rows()
    np.testing.assert_allclose(honest.residuals(x)[rows], expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(honest.residuals(x)[~rows], problem.residuals(x)[~rows], atol=1e-15)
    jac, h = honest.jacobian(x), 1e-7
    for k in range(honest.n_free_params):  # its Jacobian against central differences
        e = np.zeros_like(x)
        e[k] = h
        fd = (honest.residuals(x + e) - honest.residuals(x - e)) / (2 * h)
        np.testing.assert_allclose(jac[rows, k], fd[rows], rtol=1e-6, atol=1e-9)
    # quiet data keeps the default: the same problem
    panda, quiet, spec = _noisy_panda(1e-4)
    problem = build_problem(panda, quiet, spec, prior_weight=PRIOR)
    assert prior_at_shown_noise(problem, fixture_noise(problem, solve_lm(problem, problem.x0).x).level) is problem


def test_calibrate_switches_the_prior_only_without_a_declared_noise_and_says_so():
    panda, dataset, spec = _noisy_panda(1.2e-3)
    default = calibrate(panda, dataset, spec, check=False, prior=PRIOR, loss="auto", noise_declared=False)
    declared = calibrate(panda, dataset, spec, check=False, prior=PRIOR, loss="auto", noise_declared=True)
    linear = calibrate(panda, dataset, spec, check=False, prior=PRIOR, noise_declared=False)  # a candidate's fit
    assert declared.problem.prior_noise is None and declared.block()["prior_noise_m"] is None
    for result in (default, linear):
        assert result.problem.prior_noise > 2 * result.problem.noise
        assert result.block()["prior_noise_m"] == result.problem.prior_noise
    assert "mm per axis the residuals show" in default.summary() and "zeros at 1 deg" in default.summary()
    assert "mm per axis the residuals show" not in declared.summary()
    assert not np.array_equal(default.model.params, declared.model.params)
    quiet = calibrate(*_noisy_panda(1e-4), check=False, prior=PRIOR, loss="auto", noise_declared=False)
    assert quiet.problem.prior_noise is None
