"""The best rigid approximation of a calibrated model: what a URDF (kinematics only) can carry.

A URDF has joint origins and nothing else: no joint compliance, no other joint-side term of the
calibrated model (:attr:`correction.RobotModel.layout` blocks after the base). Dropping those terms from
the model loses what they correct. Instead the geometric parameters (DH, Hayati, tool, base) are refitted
so that the rigid chain's tool points match the FULL model's over the recorded configurations and a
workspace sample (uniform inside the joint limits)::

    min_g  sum_k |tool_point(rigid(g), q_k) - tool_point(full, q_k)|^2

by Gauss-Newton on :func:`correction.param_jacobian` (columns scaled by the layout's prior spread, minimum-
norm steps: the DH redundancies stay at the calibrated values). The loss is then measured on a second,
independent workspace sample. The rigid fit is never worse than the dropped model on the fitted
configurations (it starts there and only accepts steps that lower the cost).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import RobotModel, param_jacobian, tool_point

#: Workspace configurations drawn for the fit, and as many again to measure the loss.
WORKSPACE_SAMPLES = 2000
#: Gauss-Newton iterations at most, and the relative cost decrease below which it stops.
ITERATIONS = 30
RELATIVE_TOL = 1e-10


@dataclass(frozen=True)
class RigidFit:
    """Outcome of :func:`rigid_approximation`.

    Attributes:
        model: the rigid model (the geometric part of the full model, refitted; no joint-side terms).
        dropped: the full model with its joint-side terms simply removed (what a URDF held before).
        terms: names of the joint-side parameters the URDF cannot express (``c2``, ...); empty: exact.
        fit_rms, dropped_fit_rms: rms tool-point distance to the full model over the fitted configurations [m].
        workspace_rms, workspace_max: rms and largest distance over an independent workspace sample [m].
        dropped_workspace_rms: the same for the dropped model [m].
        recorded: number of recorded configurations in the fit.
        workspace: number of workspace configurations in the fit (and in the loss sample).
        seed: seed of both workspace samples.
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

    def summary(self) -> str:
        """One line: what the rigid approximation loses against the full model, in mm."""
        if not self.terms:
            return "the model is rigid: the URDF carries all of it"
        names = ", ".join(self.terms)
        return (f"a URDF cannot carry {names}: wrote the best rigid fit to the full model "
                f"({self.recorded} recorded + {self.workspace} workspace configurations, seed {self.seed}); "
                f"it differs from the full model by {self.workspace_rms * 1e3:.3f} mm rms "
                f"(max {self.workspace_max * 1e3:.3f} mm) over {self.workspace} other workspace configurations, "
                f"where dropping the terms would differ by {self.dropped_workspace_rms * 1e3:.3f} mm rms")


def geometric_part(model: RobotModel) -> RobotModel:
    """``model`` without its joint-side parameter blocks: every ``extras`` key whose removal shortens the
    parameter vector (compliance today, any block added to the layout the same way tomorrow)."""
    extras = dict(model.extras)
    size = model.layout.size
    for key in list(extras):
        trial = replace(model, extras={k: v for k, v in extras.items() if k != key})
        if trial.layout.size < size:
            extras.pop(key)
            size = trial.layout.size
    return replace(model, extras=extras)


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def rigid_approximation(model: RobotModel, recorded: np.ndarray | None = None,
                        workspace: int = WORKSPACE_SAMPLES, seed: int = 0) -> RigidFit:
    """The geometric model whose tool points best match ``model``'s (see the module docstring).

    Args:
        model: the full (calibrated) model.
        recorded: (K, n) recorded joint angles [rad] to include in the fit (the calibration's samples), or None.
        workspace: configurations drawn uniformly inside the joint limits for the fit, and again for the loss.
        seed: seed of the workspace samples.

    Returns:
        :class:`RigidFit`; for a model without joint-side terms, the model itself and zero loss.
    """
    dropped = geometric_part(model)
    terms = tuple(name for name in model.layout.names if name not in dropped.layout.names)
    if not terms:
        return RigidFit(model, model, ())
    rng = np.random.default_rng(seed)
    fit_q = model.random_configurations(workspace, rng)
    check_q = model.random_configurations(workspace, rng)
    count = 0
    if recorded is not None and len(recorded):
        recorded = np.asarray(recorded, dtype=float).reshape(-1, model.n_joints)
        fit_q, count = np.vstack([recorded, fit_q]), len(recorded)
    target = tool_point(model, fit_q)
    scale = dropped.layout.spread()
    scale = np.where(scale > 0, scale, 1.0)
    rigid, cost = dropped, float(np.sum((tool_point(dropped, fit_q) - target) ** 2))
    start = cost
    for _ in range(ITERATIONS):
        jac, point = param_jacobian(rigid, fit_q, return_point=True)
        residual = (target - point).reshape(-1)
        step = np.linalg.lstsq(jac.reshape(-1, rigid.n_params) * scale, residual, rcond=1e-9)[0] * scale
        for _halving in range(8):
            trial = rigid.with_params(rigid.params + step)
            trial_cost = float(np.sum((tool_point(trial, fit_q) - target) ** 2))
            if trial_cost < cost:
                break
            step = step / 2
        else:
            break
        improvement = cost - trial_cost
        rigid, cost = trial, trial_cost
        if improvement <= RELATIVE_TOL * start:
            break
    check = tool_point(model, check_q)
    distance = np.linalg.norm(tool_point(rigid, check_q) - check, axis=1)
    return RigidFit(
        model=rigid, dropped=dropped, terms=terms,
        fit_rms=float(np.sqrt(cost / len(fit_q))), dropped_fit_rms=float(np.sqrt(start / len(fit_q))),
        workspace_rms=float(np.sqrt(np.mean(distance**2))), workspace_max=float(distance.max()),
        dropped_workspace_rms=_rms(tool_point(dropped, check_q), check),
        recorded=count, workspace=workspace, seed=seed,
    )
