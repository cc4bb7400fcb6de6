"""Gravity torques and the elastic tool point against a plain loop over configurations, joints and bodies.

The reference below builds each link frame as a product of 4 x 4 matrices straight from the convention's
definition (:class:`RobotModel`), puts every centre of mass in the world, and sums ``-(z_i x m_j (c_j - o_i)) . g``
over the bodies ``j`` each joint ``i`` carries: no code shared with :mod:`spherecal.correction.gravity`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import RobotModel, gravity, load_robot, rpy_matrix, tool_point
from spherecal.correction.elastic import link_angles, motor_angles, with_compliance
from spherecal.correction.errors import ShapeError
from spherecal.correction.gravity import GRAVITY, gravity_torques, inertials_of
from spherecal.correction.scale import with_scale
from tests.correction.hand_transforms import rot, shift

#: Torques [Nm] and tool points [m] agree with the reference to this (the brief: the rewrite changes no result).
TOL = 1e-12




def _frames(model: RobotModel, q: np.ndarray) -> list[np.ndarray]:
    """World poses of frames 0 (base) .. n at link angles q (n,): one matrix product per elementary step."""
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rpy_matrix(model.base_rpy), model.base_xyz
    out = [base]
    for i in range(model.n_joints):
        turn = model.theta[i] + q[i]
        if model.convention == "modified":  # Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)
            step = (rot(0, model.alpha[i]) @ shift(0, model.a[i]) @ rot(1, model.beta[i]) @ rot(2, turn)
                    @ shift(2, model.d[i]))
        else:  # Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)
            step = (rot(2, turn) @ shift(2, model.d[i]) @ shift(0, model.a[i]) @ rot(0, model.alpha[i])
                    @ rot(1, model.beta[i]))
        out.append(out[-1] @ step)
    return out


def _reference_torques(model: RobotModel, q: np.ndarray, masses=None, coms=None, g=GRAVITY) -> np.ndarray:
    """(N, n) torques holding the arm against gravity, one configuration, joint and body at a time."""
    if masses is None:
        masses, coms = inertials_of(model)
    n, g = model.n_joints, np.asarray(g, dtype=float)
    out = np.zeros((len(q), n))
    for k, qk in enumerate(q):
        f = _frames(model, qk)
        centres = [f[min(j + 1, n)] @ np.append(coms[j], 1.0) for j in range(n + 1)]  # link j in frame j+1
        for i in range(n):
            joint = f[i + 1] if model.convention == "modified" else f[i]  # turns about this frame's z
            axis, origin = joint[:3, 2], joint[:3, 3]
            for j in range(i, n + 1):  # link i onwards, and the payload
                out[k, i] -= np.dot(np.cross(axis, masses[j] * (centres[j][:3] - origin)), g)
    return out


def _reference_tool_point(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """(N, 3) tool points of measured angles: scaled, then deflected by the reference torques."""
    q_joint = q * (1.0 + np.asarray(model.extras.get("scale", np.zeros(model.n_joints))))
    q_link = q_joint - np.asarray(model.extras["compliance"]) * _reference_torques(model, q_joint)
    return np.array([(_frames(model, qk)[-1] @ np.append(model.tool, 1.0))[:3] for qk in q_link])


def _elastic_panda() -> RobotModel:
    """The embedded Panda, elastic (1e4 to 5e4 Nm/rad) and scaled (1e-3)."""
    rng = np.random.default_rng(11)
    panda = with_compliance(load_robot("panda"), 1.0 / rng.uniform(1e4, 5e4, 7))
    return with_scale(panda, rng.normal(0.0, 1e-3, 7))


def _tilted_hayati_panda() -> RobotModel:
    """The elastic, scaled Panda with a Hayati angle on joint 2 and a tilted, shifted base."""
    return replace(_elastic_panda(), beta=[0.0, 0.02, 0, 0, 0, 0, 0], hayati=(1,), base_xyz=[0.1, -0.2, 0.3],
                   base_rpy=[0.3, -0.2, 0.5])


def _arm6() -> RobotModel:
    """A 6-joint standard-DH arm (random geometry, a Hayati angle, a tilted base), elastic, the Panda's first six
    links' inertials and a payload."""
    rng = np.random.default_rng(12)
    extras = {"inertials": load_robot("panda").extras["inertials"][:6],
              "payload": {"mass": 0.8, "com": rng.normal(0, 0.05, 3).tolist()},
              "compliance": (1.0 / rng.uniform(1e4, 5e4, 6)).tolist()}
    return RobotModel(
        name="arm6", convention="standard", a=rng.uniform(-0.3, 0.3, 6), alpha=rng.uniform(-2, 2, 6),
        d=rng.uniform(-0.3, 0.3, 6), theta=rng.uniform(-1, 1, 6), lower=-np.full(6, 3.0), upper=np.full(6, 3.0),
        tool=[0.0, 0.05, 0.1], base_xyz=[0.1, -0.2, 0.3], base_rpy=[0.3, -0.2, 0.5],
        beta=[0.0, 0.0, 0.01, 0.0, 0.0, 0.0], hayati=(2,), extras=extras,
    )


MODELS = {"elastic scaled panda": _elastic_panda, "tilted hayati panda": _tilted_hayati_panda, "arm6": _arm6}


@pytest.mark.parametrize("make", MODELS.values(), ids=MODELS.keys())
def test_torques_match_the_plain_loop_one_and_many(make) -> None:
    model = make()
    q = model.random_configurations(40, np.random.default_rng(13))
    reference = _reference_torques(model, q)
    assert np.abs(reference).max() > 10.0  # real loads, not a trivially zero comparison
    np.testing.assert_allclose(gravity_torques(model, q), reference, rtol=0, atol=TOL)  # the batched path
    for qk, expected in zip(q[:10], reference, strict=False):  # one configuration: the path on Python floats
        np.testing.assert_allclose(gravity_torques(model, qk), expected, rtol=0, atol=TOL)
        np.testing.assert_allclose(gravity_torques(model, qk[None])[0], expected, rtol=0, atol=TOL)


@pytest.mark.parametrize("make", MODELS.values(), ids=MODELS.keys())
def test_elastic_tool_point_matches_the_plain_loop(make) -> None:
    model = make()
    q = model.random_configurations(30, np.random.default_rng(14))
    expected = _reference_tool_point(model, q)
    np.testing.assert_allclose(tool_point(model, q), expected, rtol=0, atol=TOL)
    for qk, point in zip(q[:10], expected, strict=False):
        np.testing.assert_allclose(tool_point(model, qk), point, rtol=0, atol=TOL)
    rigid = replace(model, extras={k: v for k, v in model.extras.items() if k != "compliance"})
    assert np.abs(tool_point(rigid, q) - expected).max() > 1e-4  # the deflection is there, sub-millimetre


def test_a_batch_in_blocks_is_the_batch(monkeypatch) -> None:
    """A batch longer than gravity.BLOCK is computed block by block (here blocks of 7, the last of one row)."""
    model = _tilted_hayati_panda()
    q = model.random_configurations(43, np.random.default_rng(17))
    monkeypatch.setattr(gravity, "BLOCK", 7)
    np.testing.assert_allclose(gravity_torques(model, q), _reference_torques(model, q), rtol=0, atol=TOL)


def test_given_masses_another_gravity_and_motor_angles() -> None:
    model = _arm6()
    q = model.random_configurations(12, np.random.default_rng(15))
    masses, coms = inertials_of(model)
    masses, coms = masses * 1.5, coms + 0.01
    for g in (GRAVITY, (9.81, 0.0, 0.0), (1.0, -2.0, 3.0)):
        expected = _reference_torques(model, q, masses, coms, g)
        np.testing.assert_allclose(gravity_torques(model, q, masses, coms, g), expected, rtol=0, atol=TOL)
        np.testing.assert_allclose(gravity_torques(model, q[3], masses, coms, g), expected[3], rtol=0, atol=TOL)
    np.testing.assert_allclose(gravity_torques(model, q), _reference_torques(model, q), rtol=0, atol=TOL)  # own again
    q_link = link_angles(model, q)
    np.testing.assert_allclose(link_angles(model, motor_angles(model, q_link)), q_link, rtol=0, atol=1e-14)


def test_a_payload_changed_on_the_same_model_is_used() -> None:
    """The fixed parts are kept per model; its loads are checked against its extras at every call."""
    model = _arm6()
    q = model.random_configurations(3, np.random.default_rng(16))
    before = gravity_torques(model, q[0])
    model.extras["payload"] = {"mass": 3.0, "com": [0.0, 0.0, 0.2]}  # a new block in the same (mutable) extras
    after = gravity_torques(model, q[0])
    assert np.abs(after - before).max() > 1.0
    np.testing.assert_allclose(after, _reference_torques(model, q[:1])[0], rtol=0, atol=TOL)
    np.testing.assert_allclose(gravity_torques(model, q), _reference_torques(model, q), rtol=0, atol=TOL)


def test_masses_of_another_shape_are_refused() -> None:
    model = _arm6()
    masses, coms = inertials_of(model)
    with pytest.raises(ShapeError, match=r"masses and coms must have shapes \(7,\) and \(7, 3\).*got \(6,\)"):
        gravity_torques(model, np.zeros(6), masses[:-1], coms)
