"""The best rigid approximation of a calibrated model: what a URDF (kinematics only) can carry.

A URDF has joint origins and nothing else: no joint compliance, no other joint-side term of the
calibrated model (:attr:`correction.RobotModel.layout` blocks after the base). Dropping those terms from
the model loses what they correct. Instead the geometric parameters (DH, Hayati, tool, base) are refitted
so that the rigid chain's tool points match the FULL model's over the recorded configurations and a
workspace sample around them (a recorded configuration plus N(0, :data:`SPREAD`) per joint, clipped to the
limits; uniform inside the limits when there are no recorded configurations)::

    min_g  sum_k |tool_point(rigid(g), q_k) - tool_point(full, q_k)|^2

by Gauss-Newton on :func:`correction.param_jacobian` (columns scaled by the layout's prior spread, minimum-
norm steps: the DH redundancies stay at the calibrated values), with a weak pull toward the calibrated geometry:
moving a parameter by one prior spread costs as much as :data:`ANCHOR` of tool-point rms over the fitted
configurations. Nearly redundant directions stay put that way: a chain with two nearly parallel consecutive axes
described without a Hayati ``beta`` (a hand-written robot file; ``alpha = -pi`` 2 mrad off after calibration)
trades ``d`` of the two joints along their common normal, and the plain fit moved both by 17.7 m, a URDF no
reader accepts, to gain micrometres. The loss is then measured on a second,
independent draw of the same workspace, and over the whole joint range. The rigid fit is never worse than the
dropped model on the fitted configurations (it starts there and only accepts steps that lower the cost).

Why around the recorded configurations, not the whole joint range: a rigid chain cannot follow gravity
sag everywhere, so it has to choose where to be right. Measured on MUKCa's real Pandas (``bench/
export_rigid.py``, elastic model trained on one placement, test MAE on the other placements' sockets [mm]):
full model 0.353 / 0.242 (panda_2_clean / panda_4_clean), compliance dropped 0.444 / 0.415, refitted over
the whole joint range 0.499 / 0.521 (worse than dropping), refitted around the recordings with a spread of
0.1 / 0.2 / 0.3 / 0.5 rad 0.366 / 0.358 / 0.361 / 0.376 and 0.259 / 0.254 / 0.251 / 0.261. Re-measured at stop 10
(``bench/rigid_spread.py``: 26 single-placement trainings of 11 real arm sets, MUKCa's Pandas, iiwa14 and Gen3 lite,
``auto``'s model where it has joint-side terms): the held-out error over 0.3 rad's is 1.010 / 1.004 / 1.006 / 1.037
on average for 0.1 / 0.2 / 0.5 / 0.8 rad (worst 1.07 / 1.03 / 1.10 / 1.27). The four joint-angle-scale models alone
do better wider (0.8 rad: 0.952, worst 0.999), too few to give that kind a spread of its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, geometric_part, param_jacobian, tool_point, tool_pose
from spherecal.correction.rigid import rotation_angle

#: Workspace configurations drawn for the fit, and as many again to measure the loss.
WORKSPACE_SAMPLES = 2000
#: Spread of the workspace sample around the recorded configurations, per joint [rad] (17 deg).
SPREAD = 0.3
#: Gauss-Newton iterations at most, and the relative cost decrease below which it stops.
ITERATIONS = 30
RELATIVE_TOL = 1e-10
#: Tool-point rms [m] over the fitted configurations that one prior spread of change in any parameter costs.
ANCHOR = 1e-6


@dataclass(frozen=True)
class RigidFit:
    """Outcome of :func:`rigid_approximation`.

    Attributes:
        model: the rigid model (the geometric part of the full model, refitted; no joint-side terms).
        dropped: the full model with its joint-side terms simply removed (what a URDF held before).
        terms: names of the non-zero joint-side parameters the URDF cannot express (``c2``, ...); empty: exact.
        fit_rms, dropped_fit_rms: rms tool-point distance to the full model over the fitted configurations [m].
        workspace_rms, workspace_max: rms and largest distance over an independent workspace sample [m].
        dropped_workspace_rms: the same for the dropped model [m].
        recorded: number of recorded configurations in the fit.
        workspace: number of workspace configurations in the fit (and in the loss sample).
        seed: seed of both workspace samples.
        full_range_rms, dropped_full_range_rms: rms distance to the full model over configurations uniform in
            the joint limits, of the fit and of the dropped model [m] (where the arm was not calibrated).
        workspace_turn_max: largest angle between the tool frames of the fit and of the full model over the
            independent workspace sample [rad] (the fit matches points, a tool's orientation follows the frame).
    """

    model: RobotModel
    dropped: RobotModel
    terms: tuple[str, ...]
    fit_rms: float = 0.0
    dropped_fit_rms: float = 0.0
    workspace_rms: float = 0.0
    workspace_max: float = 0.0
    dropped_workspace_rms: float = 0.0
    recorded: int = 0
    workspace: int = 0
    seed: int = 0
    full_range_rms: float = 0.0
    dropped_full_range_rms: float = 0.0
    workspace_turn_max: float = 0.0

    def summary(self, output_format: str = "URDF") -> str:
        """One line: what the rigid approximation loses against the full model, in mm (``output_format``: the
        document that cannot carry the terms, named in the line)."""
        if not self.terms:
            return f"the model is rigid: the {output_format} carries all of it"
        names = ", ".join(self.terms)
        where = (f"within {SPREAD:g} rad of the {self.recorded} recorded ones" if self.recorded
                 else "uniform in the joint limits")
        article = "an" if output_format[0] in "AEFHILMNORSX" else "a"  # an MJCF, a URDF
        return (f"{article} {output_format} cannot carry {names}: wrote the best rigid fit to the full model; "
                f"it differs from it by "
                f"{self.workspace_rms * 1e3:.3f} mm rms (max {self.workspace_max * 1e3:.3f} mm) over "
                f"{self.workspace} configurations {where}, where its tool frame turns by up to "
                f"{np.rad2deg(self.workspace_turn_max):.3g} deg (dropping the terms: "
                f"{self.dropped_workspace_rms * 1e3:.3f} mm), {self.full_range_rms * 1e3:.3f} mm over the whole "
                f"joint range (dropping: {self.dropped_full_range_rms * 1e3:.3f} mm); seed {self.seed}")


def joint_side_terms(model: RobotModel) -> tuple[str, ...]:
    """Names of the non-zero parameters of ``model`` that its :func:`geometric_part` has not (``c2``, ...)."""
    kept = set(geometric_part(model).layout.names)
    return tuple(name for name, value in zip(model.layout.names, model.params, strict=True)
                 if name not in kept and value != 0.0)


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def rigid_approximation(model: RobotModel, recorded: np.ndarray | None = None,
                        workspace: int = WORKSPACE_SAMPLES, seed: int = 0) -> RigidFit:
    """The geometric model whose tool points best match ``model``'s (see the module docstring).

    Args:
        model: the full (calibrated) model.
        recorded: (K, n) recorded joint angles [rad] to include in the fit (the calibration's samples), or None.
        workspace: configurations drawn for the fit (around ``recorded``, else uniform in the limits), and as
            many again for the loss.
        seed: seed of the workspace samples.

    Returns:
        :class:`RigidFit`; for a model without joint-side terms, the model itself and zero loss.
    """
    dropped, terms = geometric_part(model), joint_side_terms(model)
    if not terms:
        return RigidFit(model, model, ())
    rng = np.random.default_rng(seed)
    count = 0 if recorded is None else len(recorded)
    if count:
        recorded = np.asarray(recorded, dtype=float).reshape(-1, model.n_joints)

        def draw() -> np.ndarray:
            around = recorded[rng.integers(0, count, workspace)] + rng.normal(0.0, SPREAD, (workspace, model.n_joints))
            return np.clip(around, model.lower, model.upper)

        fit_q = np.vstack([recorded, draw()])
        check_q = draw()
    else:
        fit_q = model.random_configurations(workspace, rng)
        check_q = model.random_configurations(workspace, rng)
    full_q = model.random_configurations(workspace, rng)
    target = tool_point(model, fit_q)
    scale = dropped.layout.spread()
    scale = np.where(scale > 0, scale, 1.0)
    anchor = np.sqrt(len(fit_q)) * ANCHOR  # weight of a parameter's change in prior spreads

    def costs(candidate: RobotModel) -> tuple[float, float]:  # (tool points' squared misfit, plus the anchor's)
        misfit = float(np.sum((tool_point(candidate, fit_q) - target) ** 2))
        moved = (candidate.params - dropped.params) / scale
        return misfit, misfit + float(anchor**2 * moved @ moved)

    rigid, (misfit, cost) = dropped, costs(dropped)
    start = misfit
    eye = anchor * np.eye(dropped.n_params)
    for _ in range(ITERATIONS):
        jac, point = param_jacobian(rigid, fit_q, return_point=True)
        residual = np.concatenate([(target - point).reshape(-1), -anchor * (rigid.params - dropped.params) / scale])
        step = np.linalg.lstsq(np.vstack([jac.reshape(-1, rigid.n_params) * scale, eye]), residual,
                               rcond=1e-9)[0] * scale
        for _halving in range(8):
            trial = rigid.with_params(rigid.params + step)
            trial_misfit, trial_cost = costs(trial)
            if trial_cost < cost:
                break
            step = step / 2
        else:
            break
        improvement = cost - trial_cost
        rigid, misfit, cost = trial, trial_misfit, trial_cost
        if improvement <= RELATIVE_TOL * start:
            break
    check = tool_point(model, check_q)
    distance = np.linalg.norm(tool_point(rigid, check_q) - check, axis=1)
    turn = _largest_turn(tool_pose(rigid, check_q)[:, :3, :3], tool_pose(model, check_q)[:, :3, :3])
    return RigidFit(
        model=rigid, dropped=dropped, terms=terms,
        fit_rms=float(np.sqrt(misfit / len(fit_q))), dropped_fit_rms=float(np.sqrt(start / len(fit_q))),
        workspace_rms=float(np.sqrt(np.mean(distance**2))), workspace_max=float(distance.max()),
        dropped_workspace_rms=_rms(tool_point(dropped, check_q), check),
        recorded=count, workspace=workspace, seed=seed,
        full_range_rms=_rms(tool_point(rigid, full_q), tool_point(model, full_q)),
        dropped_full_range_rms=_rms(tool_point(dropped, full_q), tool_point(model, full_q)),
        workspace_turn_max=turn,
    )


def _largest_turn(a: np.ndarray, b: np.ndarray) -> float:
    """Largest rotation angle [rad] between (N, 3, 3) rotations ``a`` and ``b``, pair by pair
    (:func:`correction.rigid.rotation_angle` of ``a^T b``); 0 for none."""
    return float(np.max(rotation_angle(np.einsum("nji,njk->nik", a, b)))) if len(a) else 0.0
