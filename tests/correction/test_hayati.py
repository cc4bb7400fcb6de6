"""Hayati's beta: FK against a plain matrix product, Jacobian columns against central differences,
nothing changes when every beta is zero, files and conversions keep it."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import (
    link_frames,
    load_robot,
    param_jacobian,
    perturb,
    save_robot,
    to_modified,
    to_standard,
    tool_point,
)
from spherecal.correction.files.urdf_read import parse_urdf
from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning, urdf_model
from spherecal.correction.layout import layout_for
from tests.conftest import perturbed
from tests.correction.hand_transforms import rot as _rot
from tests.correction.hand_transforms import shift as _shift
from tests.correction.test_kinematics import _central_difference
from tests.correction.ur5e_urdf import ur5e_urdf


def _reference_point(model, q: np.ndarray) -> np.ndarray:
    """Tool point as a product of 4x4 matrices, written from the conventions' definitions."""
    pose = model.base_transform
    for i in range(model.n_joints):
        a, alpha, beta, d, turn = model.a[i], model.alpha[i], model.beta[i], model.d[i], model.theta[i] + q[i]
        if model.convention == "modified":
            pose = pose @ _rot(0, alpha) @ _shift(0, a) @ _rot(1, beta) @ _rot(2, turn) @ _shift(2, d)
        else:
            pose = pose @ _rot(2, turn) @ _shift(2, d) @ _shift(0, a) @ _rot(0, alpha) @ _rot(1, beta)
    return (pose @ np.append(model.tool, 1.0))[:3]


def _with_beta(panda, convention, rng, hayati=(1, 3, 6)):
    model = perturbed(panda, rng, scale=20.0)
    model = to_standard(model) if convention == "standard" else model
    beta = np.zeros(model.n_joints)
    beta[list(hayati)] = rng.normal(0.0, 0.3, len(hayati))
    model = replace(model, beta=beta, hayati=hayati)
    params = model.params.copy()
    params[model.layout.base] += rng.normal(0, 0.3, 6)
    params[model.layout.tool] += rng.normal(0, 0.05, 3)
    return model.with_params(params)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_forward_kinematics_equals_matrix_product(panda, convention, rng):
    model = _with_beta(panda, convention, rng)
    q = model.random_configurations(50, rng)
    reference = np.array([_reference_point(model, qk) for qk in q])
    assert np.abs(tool_point(model, q) - reference).max() < 1e-14
    frames = link_frames(model, q)
    assert np.abs(frames[:, -1, :3, :3] @ model.tool + frames[:, -1, :3, 3] - reference).max() < 1e-14


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_beta_jacobian_columns_equal_central_differences(panda, convention, rng):
    for hayati in ((1, 3, 6), (0, 2), (5,)):
        model = _with_beta(panda, convention, rng, hayati)
        assert [model.param_names[i] for i in range(model.layout.beta.start, model.layout.beta.stop)] == [
            f"beta{j + 1}" for j in hayati
        ]
        q = model.random_configurations(20, rng)
        analytic = param_jacobian(model, q)
        numeric = _central_difference(lambda x, m=model, q=q: tool_point(m.with_params(x), q), model.params, 1e-6)
        assert analytic.shape == (20, 3, model.n_params) == numeric.shape
        assert np.abs(analytic - numeric).max() / np.abs(numeric).max() < 1e-6


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_zero_beta_changes_nothing(panda, convention, rng):
    plain = perturbed(panda if convention == "modified" else to_standard(panda), rng)
    hayati = replace(plain, hayati=(2, 3))
    q = plain.random_configurations(100, rng)
    np.testing.assert_array_equal(tool_point(hayati, q), tool_point(plain, q))
    np.testing.assert_array_equal(link_frames(hayati, q), link_frames(plain, q))
    jac_h, jac_p = param_jacobian(hayati, q), param_jacobian(plain, q)
    lay = hayati.layout
    assert lay.size == plain.layout.size + 2
    common = [lay.index(name) for name in plain.param_names]
    np.testing.assert_array_equal(jac_h[:, :, common], jac_p)


def test_conversion_and_robot_file_keep_beta(panda, rng, tmp_path):
    model = _with_beta(panda, "modified", rng, (1, 3, 6))
    q = model.random_configurations(100, rng)
    standard = to_standard(model)
    assert standard.hayati == (0, 2, 5)
    assert np.abs(tool_point(standard, q) - tool_point(model, q)).max() < 1e-12
    assert np.abs(tool_point(to_modified(standard), q) - tool_point(model, q)).max() < 1e-12
    path = save_robot(model, tmp_path / "hayati.yaml")
    loaded = load_robot(path)
    assert loaded.same_as(model) and loaded.hayati == (1, 3, 6)
    assert "beta" not in save_robot(panda, tmp_path / "plain.yaml").read_text()  # plain files unchanged
    assert panda.mismatch(replace(panda, hayati=(2,)))[0] == "beta"


def test_held_d_follows_the_convention():
    lay = layout_for(6, (2, 3))
    assert lay.held("modified") == ("d2", "d3") and lay.held("standard") == ("d3", "d4")
    assert lay.names[lay.beta] == ("beta3", "beta4") and lay.is_angle("beta3")


def test_importer_hayati_keeps_d_small_where_plain_dh_explodes(rng):
    tree = parse_urdf(ur5e_urdf(skew=2e-5), "ur5e")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        hayati = urdf_model(tree)
        plain = urdf_model(tree, parallel_tol=0.0, far_normal=np.inf)  # classical DH: the normal kilometres away
    assert plain.hayati == () and np.abs(plain.d).max() > 1e3
    assert hayati.hayati == (2, 3) and np.abs(hayati.d).max() < 0.2
    assert all(hayati.d[hayati.layout.index(name) // 4] == 0.0 for name in hayati.layout.held("modified"))
    # A perturbed (true) arm keeps the held d at zero, and perturbs beta.
    true = perturb(hayati, rng)
    assert true.d[1] == 0.0 and true.d[2] == 0.0 and np.all(true.beta[[2, 3]] != hayati.beta[[2, 3]])
