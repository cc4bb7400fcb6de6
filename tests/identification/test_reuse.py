"""What a calibration computes once and reuses is what it would compute afresh."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import perturb, tool_point
from spherecal.correction.elastic import with_compliance
from spherecal.identification.build import build_problem
from spherecal.identification.calibrate import _plausibility_reference, calibrate
from spherecal.identification.identifiability import column_norms, normal_inverse, triangular
from spherecal.identification.prediction import _linearised
from spherecal.identification.pruning import generic_excitation, prune
from spherecal.identification.selfcheck import self_check
from spherecal.identification.synthetic import make_dataset


def test_the_plausibility_reference_follows_the_start_model_s_content(panda) -> None:
    q, points, typical = _plausibility_reference(panda)
    # the same content in another object (every fold of a candidate builds its own start model): reused
    again = _plausibility_reference(with_compliance(panda, None))
    assert again[1] is points
    np.testing.assert_array_equal(points, tool_point(panda, q))
    with pytest.raises(ValueError):
        points[0, 0] = 0.0  # shared: read-only
    # another content (an elastic start: its tool sags under gravity, its compliances add to the typical change)
    elastic = with_compliance(panda, np.full(panda.n_joints, 3e-5))
    q_e, points_e, typical_e = _plausibility_reference(elastic)
    np.testing.assert_array_equal(q_e, q)  # the same seeded configurations
    np.testing.assert_array_equal(points_e, tool_point(elastic, q))
    assert np.abs(points_e - points).max() > 1e-5
    assert typical_e > typical
    # the same parameters with a heavier payload: the same parameter vector, another arm under gravity
    heavier = replace(elastic, extras={**elastic.extras, "payload": {"mass": 3.0, "com": [0.0, 0.0, 0.1]}})
    np.testing.assert_array_equal(heavier.params, elastic.params)
    _, points_h, _ = _plausibility_reference(heavier)
    np.testing.assert_array_equal(points_h, tool_point(heavier, q))
    assert np.abs(points_h - points_e).max() > 1e-6


def test_the_generic_jacobian_kept_for_pruning_is_the_fresh_one(panda) -> None:
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(panda, dataset, spec, prior_weight=0.5)  # its rank test keeps the generic part
    assert "generic_param_jacobian" in problem._cache
    pruned = replace(problem, free=problem.free[:-3])  # as pruning does: fewer columns, the prior rows with them
    moved, x = pruned.generic_point()
    fresh = replace(moved, _cache={}).jacobian(x)  # nothing kept: computed anew
    assert fresh.shape == (pruned.n_residuals, pruned.n_unknowns)
    np.testing.assert_array_equal(pruned.generic_jacobian(), fresh)


def test_a_kept_parameter_jacobian_serves_only_its_own_parameters(panda) -> None:
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(panda, dataset, spec, prior_weight=0.5)
    x = problem.x0 + 1e-4 * np.random.default_rng(3).normal(size=problem.n_unknowns)
    problem.jacobian(x)  # kept, for every problem sharing the cache
    params, centres = problem.unpack(x)
    pruned = replace(problem, free=problem.free[2:])  # shares the cache, other unknowns
    for trial in (pruned.pack(params, centres), pruned.pack(params, centres) + 1e-5):  # the same parameters, others
        np.testing.assert_array_equal(pruned.jacobian(trial), replace(pruned, _cache={}).jacobian(trial))
    eps = 1e-7  # and the kept one is the Jacobian of the residuals there
    numeric = np.stack([(problem.residuals(x + eps * e) - problem.residuals(x - eps * e)) / (2 * eps)
                        for e in np.eye(x.size)], axis=1)
    assert np.abs(problem.jacobian(x) - numeric).max() < 1e-6 * problem.distance_weight


def test_a_problem_s_identifiability_is_computed_when_asked_at_its_start(panda) -> None:
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem, _ = build_problem(panda, dataset, spec).generic_point()  # the nominal design itself is degenerate
    jac = problem.jacobian(problem.x0)
    scaled = jac / np.linalg.norm(jac, axis=0)
    singular = np.linalg.svd(scaled, compute_uv=False)  # apart: the SVD, not the normal matrix's eigenvalues
    np.testing.assert_allclose(problem.identifiability.singular_values, singular, rtol=1e-6)
    assert problem.identifiability.condition_number == pytest.approx(singular[0] / singular[-1], rel=1e-6)


def test_plausibility_references_of_many_models_from_threads_stay_their_own(panda) -> None:
    from concurrent.futures import ThreadPoolExecutor

    models = [perturb(panda, np.random.default_rng(seed)) for seed in range(12)]  # more than are kept
    with ThreadPoolExecutor(4) as pool:
        found = list(pool.map(_plausibility_reference, models * 2))
    for model, (q, points, _) in zip(models * 2, found, strict=True):
        np.testing.assert_array_equal(points, tool_point(model, q))


def test_a_fold_s_fit_without_its_figures_is_the_same_model(panda) -> None:
    """``report=False`` (a cross-validation fold, judged by its model alone) skips the stds and figures, not the
    solve: the same model, pruning and warnings of its own; and no self-check can be asked of it."""
    true = with_compliance(perturb(panda, np.random.default_rng(1)), np.full(panda.n_joints, 2e-5))
    dataset, spec = make_dataset(true, per_fixture=60, rng=np.random.default_rng(2), noise=2e-4)
    start = with_compliance(panda, np.zeros(panda.n_joints))
    for loss in ("linear", "auto"):
        full = calibrate(start, dataset, spec, loss=loss, check=False, prior=0.5)
        fold = calibrate(start, dataset, spec, loss=loss, check=False, prior=0.5, report=False)
        np.testing.assert_array_equal(fold.model.params, full.model.params)
        np.testing.assert_array_equal(fold.residual_after, full.residual_after)
        assert fold.identified == full.identified and fold.fixed == full.fixed
        assert fold.std == {} and fold.effective_unknowns is None and np.isnan(fold.condition_number)
    with pytest.raises(ValueError, match="check=False"):
        calibrate(start, dataset, spec, report=False)


def test_the_self_check_given_the_fit_s_normal_inverse_finds_what_it_finds_alone(panda) -> None:
    """calibrate hands the self-check the ``(J^T J)^-1`` of the same Jacobian at the same solution."""
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=60, rng=np.random.default_rng(2), noise=2e-4)
    result = calibrate(panda, dataset, spec, prior=0.5, check=False)
    problem, x = result.problem, result.x
    inverse = normal_inverse(problem.jacobian(x))
    given = self_check(problem, x, panda, loss="linear", inverse=inverse)
    alone = self_check(problem, x, panda, loss="linear")
    assert given.block() == alone.block()


def test_the_generic_excitation_is_kept_for_its_own_problem_only(panda) -> None:
    """The calibration's pruning and the self-check's prediction factorise the built problem's generic Jacobian
    once; a problem sharing the cache with other unknowns, weights or prior gets its own."""
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(panda, dataset, spec, prior_weight=0.5)
    norms, tri = generic_excitation(problem)
    assert generic_excitation(problem)[1] is tri  # kept
    jac = problem.generic_jacobian()
    np.testing.assert_array_equal(norms, column_norms(jac))
    np.testing.assert_array_equal(tri, triangular(jac))
    others = (replace(problem, free=problem.free[:-3]), problem.weighted({dataset.fixture_names[0]: 2.0}),
              replace(problem, prior_weight=1.0))
    for other in others:  # each shares the cache
        fresh = replace(other, _cache={}).generic_jacobian()
        np.testing.assert_array_equal(generic_excitation(other)[1], triangular(fresh))
    x = problem.x0
    by_jac, x_jac = prune(problem, x, 3e-3, jac=jac)
    by_factor, x_factor = prune(problem, x, 3e-3, excitation=(norms, tri))
    assert by_factor.fixed == by_jac.fixed and by_factor.fixed != problem.fixed  # something pruned, alike
    np.testing.assert_array_equal(x_factor, x_jac)


def test_two_linearisations_with_the_same_unknowns_share_one_jacobian(panda) -> None:
    """The self-check linearises at the calibration's free parameters and at those pruned at its noise: where they
    agree, one Jacobian and inverse serve both (the same unknowns at the same point); where not, each its own."""
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(panda, dataset, spec, prior_weight=0.5)
    *_, pruned, x, rows, jac, inverse = _linearised(problem, 3e-4)
    again = _linearised(problem, 3e-4, free=pruned.free)
    assert again[5] is jac and again[6] is inverse
    np.testing.assert_array_equal(again[3], x)
    fresh = replace(pruned, _cache={}).jacobian(x) * rows
    np.testing.assert_array_equal(jac, fresh)
    np.testing.assert_array_equal(inverse, normal_inverse(fresh))
    fewer = _linearised(problem, 3e-4, free=pruned.free[:-2])
    assert fewer[5].shape[1] == jac.shape[1] - 2
