"""Column-scaled trust-region Levenberg-Marquardt for small dense least squares: ``min 0.5 |r(x)|^2``.

Built for calibration problems (a few thousand residuals, a few dozen unknowns, an analytic
Jacobian that costs several residual evaluations): every Jacobian is used as far as it goes.

Each iteration scales the Jacobian's columns (``D = max(D, |J_i|)``, MINPACK's rule, so the
unknowns' units do not matter) and diagonalises the scaled normal matrix ``G = Js^T Js = V L V^T``
(an F x F ``eigh``; from the SVD of the R of a thin QR of ``Js`` instead when ``G`` is too
ill-conditioned for normal equations, condition above :data:`NORMAL_LIMIT`); a direction whose
singular value is at rounding level (lstsq's ``rcond``: ``eps max(M, F)`` of the largest) takes no
step, so a start on an exactly degenerate design gets lstsq's minimum-norm step. The step is the
Gauss-Newton step ``-G^-1 g`` when it fits the trust region ``|h| <= radius`` (scaled), else the
damped step ``-(G + mu I)^-1 g`` of length ``radius`` (``mu`` from the eigenvalues, no further
factorisation). From the trial point, chord steps (the same damped system, the trial point's
residual) remove most of the curvature error for one residual evaluation each. A step is
accepted only when it lowers the cost, so the cost never rises; a rejected one shrinks the
radius and is retried on the same Jacobian. Near the minimum the iteration is Gauss-Newton.

Stops (converged) when

* the Gauss-Newton decrement at the current point, ``0.5 g^T G^-1 g`` (the most the linear model
  could still gain), is at most ``ftol`` times the cost (after one last step along it);
* an accepted step changed the cost by at most ``ftol`` relative (a damped one only where the
  Gauss-Newton decrement was at most ``sqrt(ftol)`` of the cost), or a Gauss-Newton step by at most
  ``sqrt(ftol)`` after one before it at a linear rate that leaves at most ``ftol`` of the cost to gain;
* an accepted step is at most ``xtol`` relative to the scaled unknowns (``|D h| <= xtol (|D x| + xtol)``);
* the cosine between the residual and every scaled Jacobian column is at most ``gtol``;
* the residual is zero, or no step lowers the cost and the trust radius has shrunk below ``xtol``
  (MINPACK's ``xtol`` test: the message gives the gain the linear model still predicts; large
  against the cost means the Jacobian is approximate there).

Stops unconverged, and says so, when ``max_jacobians`` is used up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: Above this condition number of the scaled normal matrix the eigen-decomposition comes from a thin
#: QR of the scaled Jacobian (normal equations lose about ``cond * eps`` relative accuracy).
NORMAL_LIMIT = 1e10
#: Initial trust radius, relative to ``|D x0|`` (MINPACK's factor: in effect unbounded).
INITIAL_RADIUS = 100.0
#: Chord steps (same Jacobian) after each trial step. 3 x 500 Panda samples, Jacobians / residuals of the
#: dh calibration (two solves): none 17 / 27, one 6 / 12, two 6 / 15; from a start 30x a real arm's
#: errors: one 27 / 86, two 5 / 13, three 4 / 14; the elastic calibration: 8 Jacobians whatever the number.
MAX_CHORDS = 2
#: Rejected steps in a row (on one Jacobian) before giving up.
MAX_REJECTIONS = 60


@dataclass(frozen=True)
class LeastSquaresResult:
    """Where the iteration ended.

    Attributes:
        x: (F,) unknowns.
        cost: ``0.5 |r(x)|^2``.
        residuals: (M,) ``r(x)``.
        jacobians: Jacobian evaluations.
        evaluations: residual evaluations (the start included).
        converged: a stopping test was met (not the budget).
        message: which test stopped it.
    """

    x: np.ndarray
    cost: float
    residuals: np.ndarray
    jacobians: int
    evaluations: int
    converged: bool
    message: str


class _Linearisation:
    """The scaled linear model at one point: ``r + Js h`` with ``Js = J / D``, in the eigenbasis of
    ``G = Js^T Js``."""

    def __init__(self, scaled: np.ndarray, r: np.ndarray) -> None:
        self.scaled = scaled
        self.values, self.vectors = np.linalg.eigh(scaled.T @ scaled)
        top = max(float(self.values[-1]), 0.0)
        if self.values[0] <= top / NORMAL_LIMIT:
            singular, self.vectors = np.linalg.svd(np.linalg.qr(scaled, mode="r"))[1:]
            self.vectors = self.vectors.T
            self.values = singular**2
        # directions the Jacobian does not see (singular value at rounding level, lstsq's rcond) take no step
        self.blind = self.values <= max(top, 1e-300) * (np.finfo(float).eps * max(scaled.shape)) ** 2
        self.b = self.project(r)

    def project(self, r: np.ndarray) -> np.ndarray:
        """(F,) ``V^T Js^T r``: the gradient of ``0.5 |r + Js h|^2`` in the eigenbasis."""
        return self.vectors.T @ (self.scaled.T @ r)

    def step(self, mu: float, b: np.ndarray | None = None) -> np.ndarray:
        """(F,) scaled step ``-(G + mu I)^-1 g`` (``g`` of this point, or given as ``b = V^T g``)."""
        b = self.b if b is None else b
        z = np.where(self.blind, 0.0, -b / np.where(self.blind, 1.0, self.values + mu))
        return self.vectors @ z

    def within(self, radius: float) -> tuple[np.ndarray, float]:
        """The Gauss-Newton step if it is no longer than ``radius``, else the damped step of that
        length, and its damping ``mu`` (Newton's method on ``1/|h(mu)| = 1/radius``)."""
        h = self.step(0.0)
        if np.linalg.norm(h) <= radius:
            return h, 0.0
        values, b = np.where(self.blind, np.inf, self.values), np.where(self.blind, 0.0, self.b)
        mu = max(float(np.linalg.norm(b)) / radius - float(values.min()), 0.0) * 1e-3
        for _ in range(50):
            z = b / (values + mu)
            norm = float(np.linalg.norm(z))
            derivative = -float(z @ (z / (values + mu))) / norm
            update = (norm - radius) / radius * norm / -derivative
            mu = max(mu + update, 0.0)
            if abs(norm - radius) <= 1e-3 * radius:
                break
        return self.step(mu), mu

    def predicted(self, h: np.ndarray) -> float:
        """Cost reduction the linear model predicts for the scaled step ``h``."""
        z = self.vectors.T @ h
        return float(-(self.b @ z) - 0.5 * (self.values * z) @ z)


def levenberg_marquardt(
    residuals: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    ftol: float = 1e-12,
    xtol: float = 1e-12,
    gtol: float = 1e-12,
    max_jacobians: int = 100,
) -> LeastSquaresResult:
    """Minimise ``0.5 |residuals(x)|^2`` from ``x0``.

    Args:
        residuals: x (F,) -> (M,) residual vector.
        jacobian: x (F,) -> (M, F) its Jacobian.
        x0: (F,) start.
        ftol: relative cost change (and Gauss-Newton decrement) taken as converged.
        xtol: relative scaled step size taken as converged.
        gtol: largest cosine between the residual and a Jacobian column taken as converged.
        max_jacobians: Jacobian evaluations before giving up (``converged`` False).

    Returns:
        The :class:`LeastSquaresResult`.
    """
    x = np.array(x0, dtype=float)
    r = np.asarray(residuals(x), float)
    cost = 0.5 * float(r @ r)
    evaluations, jacobians = 1, 0
    scale: np.ndarray | None = None
    radius = np.inf
    previous = np.inf  # cost change of the last step when it was a Gauss-Newton step

    def result(converged: bool, message: str) -> LeastSquaresResult:
        return LeastSquaresResult(x, cost, r, jacobians, evaluations, converged, message)

    def small(h: np.ndarray) -> bool:
        return bool(np.linalg.norm(h) <= xtol * (np.linalg.norm(scale * x) + xtol))

    def trial(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        nonlocal evaluations
        evaluations += 1
        x_new = x + h / scale
        r_new = np.asarray(residuals(x_new), float)
        return x_new, r_new, 0.5 * float(r_new @ r_new)

    while jacobians < max_jacobians:
        if cost == 0.0:
            return result(True, "the residual is zero")
        jac = np.asarray(jacobian(x), float)
        jacobians += 1
        norms = np.linalg.norm(jac, axis=0)
        scale = np.where(norms > 0, norms, 1.0) if scale is None else np.maximum(scale, norms)
        if not np.isfinite(radius):
            radius = INITIAL_RADIUS * max(float(np.linalg.norm(scale * x)), 1.0)
        model = _Linearisation(jac / scale, r)
        column = norms / scale
        cosine = np.abs(model.scaled.T @ r) / (np.sqrt(2.0 * cost) * np.where(column > 0, column, 1.0))
        if cosine.max() <= gtol:
            return result(True, f"the gradient is orthogonal to the residual (cosine {cosine.max():.2g} <= gtol)")
        decrement = model.predicted(model.step(0.0))
        final = decrement <= ftol * cost  # at the minimum already: one Gauss-Newton step, then stop
        for _ in range(MAX_REJECTIONS):
            h, mu = model.within(np.inf if final else radius)
            predicted = model.predicted(h)
            x_new, r_new, cost_new = trial(h)
            if not final:
                x_new, r_new, cost_new, h = _chord(model, mu, trial, x_new, r_new, cost_new, h, ftol)
            if cost_new < cost:
                break
            if final:
                return result(True, f"at the minimum: Gauss-Newton decrement {decrement:.3g} <= ftol x cost")
            if small(h):
                # MINPACK's xtol test: the trust radius is below xtol (the Jacobian and the residuals
                # disagree at this scale, e.g. an approximate Jacobian): stop, saying how much they disagree
                return result(True, f"no step above xtol lowers the cost (the linear model predicts {predicted:.3g})")
            # shrink to the minimum of the parabola through the cost, its slope (-2 x the predicted gain
            # of a Gauss-Newton step) and the trial's cost: by 10x after a wild step, 2x after a near miss
            shrink = predicted / max(cost_new - cost + 2.0 * predicted, 1e-300)
            radius = float(np.clip(shrink, 0.1, 0.5)) * min(radius, float(np.linalg.norm(h)))
        else:
            return result(False, f"{MAX_REJECTIONS} steps in a row raised the cost")
        change = cost - cost_new
        rho = change / predicted if predicted > 0 else 0.0
        if rho < 0.25:
            radius = 0.5 * float(np.linalg.norm(h))
        elif rho > 0.75:
            radius = max(radius, 2.0 * float(np.linalg.norm(h)))
        x, r, cost = x_new, r_new, cost_new
        if final:
            return result(True, f"Gauss-Newton decrement {decrement:.3g} <= ftol x cost")
        undamped = mu == 0.0
        # a damped step counts when even the undamped one could not have gained sqrt(ftol) (MINPACK
        # stops on any step's change; an approximate Jacobian keeps damping near the minimum)
        if change <= ftol * (cost + change) and (undamped or decrement <= np.sqrt(ftol) * (cost + change)):
            return result(True, f"relative cost change {change / (cost + change):.3g} <= ftol")
        rate = change / previous if undamped and np.isfinite(previous) else np.inf
        # extrapolated only once the change itself is small (sqrt(ftol)): the rate of two early steps misleads
        if rate < 0.5 and change <= np.sqrt(ftol) * cost and change * rate / (1.0 - rate) <= ftol * cost:
            return result(True, f"Gauss-Newton steps converge linearly (rate {rate:.2g}): what is left <= ftol x cost")
        previous = change if undamped else np.inf
        if small(h):
            return result(True, "step below xtol")
    return result(False, f"did not converge in {max_jacobians} Jacobian evaluations")


def _chord(model, mu, trial, x_new, r_new, cost_new, h, ftol):
    """Chord steps from the trial point ``x + h``: the step of the same damped system (Jacobian at
    ``x``) for the trial point's residual. Each costs one residual evaluation and removes most of the
    trial point's curvature error. One is taken when the linear model predicts it gains more than
    ``ftol`` of the cost; another (at most :data:`MAX_CHORDS`) only while the last gained at least
    half of what was predicted (beyond that a fresh Jacobian does better). Returns the best point,
    its residual, cost and total scaled step."""
    best = (x_new, r_new, cost_new, h)
    r_from = r_new
    for _ in range(MAX_CHORDS):
        b = model.project(r_from)
        correction = model.step(mu, b)
        predicted = -0.5 * float(b @ (model.vectors.T @ correction))  # the decrement of the chord step
        if predicted <= ftol * best[2]:
            break
        step = h + correction
        x_try, r_try, cost_try = trial(step)
        if not cost_try < best[2]:
            break
        gain = best[2] - cost_try
        best = (x_try, r_try, cost_try, step)
        h, r_from = step, r_try
        if gain < 0.5 * predicted:
            break
    return best


def gauss_newton(
    residuals: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    ftol: float = 1e-12,
    max_jacobians: int = 100,
) -> LeastSquaresResult:
    """Plain column-scaled Gauss-Newton (full steps, no safeguard): the floor a solver is measured
    against; stops when a step changes the cost by at most ``ftol`` relative.

    Args:
        residuals, jacobian, x0, ftol, max_jacobians: as :func:`levenberg_marquardt`.
    """
    x = np.array(x0, dtype=float)
    r = np.asarray(residuals(x), float)
    cost = 0.5 * float(r @ r)
    for count in range(1, max_jacobians + 1):
        jac = np.asarray(jacobian(x), float)
        norms = np.linalg.norm(jac, axis=0)
        norms = np.where(norms > 0, norms, 1.0)
        h = np.linalg.lstsq(jac / norms, -r, rcond=None)[0]
        x = x + h / norms
        r = np.asarray(residuals(x), float)
        cost, before = 0.5 * float(r @ r), cost
        if abs(before - cost) <= ftol * before:
            return LeastSquaresResult(x, cost, r, count, count + 1, True, "relative cost change <= ftol")
    return LeastSquaresResult(x, cost, r, max_jacobians, max_jacobians + 1, False, "budget used up")
