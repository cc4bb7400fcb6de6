"""Leave-one-out consistency of a calibration's constraints: every known distance, every known position
(freed: three unknowns with a prior row of its stated accuracy) and every fixture's samples, refitted
without them (:func:`.leave_out.leave_out`, linearised), and the one that explains an inconsistency.

A distance or position is judged by its value as the rest of the data predicts it, against its stated
accuracy, the socket play (:data:`SOCKET_STD`) and the fit's covariance; a fixture's samples by
``dSSR / sigma^2 ~ chi2(dof)``, ``sigma`` the larger of the declared noise and the residual std of the
rest. A group fails when its p-value is below :data:`ALPHA` over the number of checkable groups
(Bonferroni) and it disagrees by more than :data:`GROUP_FACTOR` standard deviations per checked row.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .gauge import scale_centre
from .leave_out import LeftOut
from .problem import DISTANCE_STD, CalibrationProblem, prior_std, samples_location
from .selfcheck_result import Finding

#: Stated accuracy of a known fixture position [m] (fixtures.yaml has no field for it yet).
POSITION_STD = DISTANCE_STD
#: Std per axis [m] of where a ball realises its socket's centre (play, printed or machined shape): a
#: known distance or position is compared with the samples within it, besides its stated accuracy. The
#: real MUKCa plate (8 placements, one printed plate) shows 0.11 mm: its 50 mm distances disagree with
#: each other by 0.17 mm rms, of which the fit explains 0.05 mm.
SOCKET_STD = 1e-4
#: Typical refit change of a centre [m], for :func:`.leave_out.leave_out`'s runaway test.
CENTRE_SPREAD = 0.05
#: Family-wise false-alarm probability of the leave-one-out tests (Gaussian noise at the declared level).
ALPHA = 1e-3
#: A left-out group must also disagree by this multiple of the noise (per coordinate, RMS) to be a culprit.
GROUP_FACTOR = 2.0
#: Failed groups explaining within this share of the best one contend for the culprit.
CONTENDERS = 0.1
#: ... and of two contenders of one size, the better must explain this much more (chi-square units).
MARGIN = 10.0


def log10_chi2_sf(statistic: float, dof: int) -> float:
    """log10 of the chi-square survival function (floored at -300: beyond, the data are plainly inconsistent).

    The regularised upper incomplete gamma ``Q(dof / 2, statistic / 2)`` in log space, written here
    (series below ``a + 1``, Lentz's continued fraction above, as in Numerical Recipes' ``gammq``):
    scipy.special would cost ``calibrate`` about 0.3 s of start-up for one call.
    """
    a, x = dof / 2.0, max(statistic, 0.0) / 2.0
    if x <= 0.0:
        return 0.0
    log_prefix = -x + a * math.log(x) - math.lgamma(a)  # log(e^-x x^a / Gamma(a))
    if x < a + 1.0:  # P(a, x) = prefix / a * sum_n x^n / ((a + 1) ... (a + n)); Q = 1 - P
        term = total = 1.0 / a
        n = a
        while abs(term) > abs(total) * 1e-17:
            n += 1.0
            term *= x / n
            total += term
        log_q = math.log1p(-min(math.exp(log_prefix + math.log(total)), 1.0)) if total > 0 else 0.0
    else:  # Q(a, x) = prefix * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - ...)), modified Lentz
        tiny = 1e-300
        b = x + 1.0 - a
        c, d = 1.0 / tiny, 1.0 / b
        h = d
        for i in range(1, 100000):
            an = -i * (i - a)
            b += 2.0
            d = an * d + b
            d = tiny if abs(d) < tiny else d
            c = b + an / c
            c = tiny if abs(c) < tiny else c
            d = 1.0 / d
            delta = d * c
            h *= delta
            if abs(delta - 1.0) < 1e-16:
                break
        log_q = log_prefix + math.log(h)
    return max(log_q / math.log(10.0), -300.0)


# ------------------------------------------------------------------------------- leave one out
def known_positions(problem: CalibrationProblem) -> list[str]:
    """The fixtures whose centre is a known position (neither an unknown nor pinned by the scale anchor)."""
    return [n for n in problem.dataset.fixture_names if n not in problem.free_centres and n not in problem.pinned]


def augmented(problem: CalibrationProblem, x: np.ndarray, r: np.ndarray, jac: np.ndarray):
    """Jacobian and residuals with every known position freed (3 unknowns, a prior row each), and the groups.

    Args:
        problem, x: the solved problem and its solution (F,).
        r, jac: (M,) residuals and (M, F) Jacobian of ``problem`` at ``x``.

    Returns:
        (M', F') Jacobian, (M',) residuals, group name -> rows, group name -> kind, and (F',) the
        typical change of each unknown (prior spread; :data:`CENTRE_SPREAD` for centres).
    """
    dataset, spec = problem.dataset, problem.spec
    names = dataset.fixture_names
    known = known_positions(problem)
    m, f = jac.shape
    count = dataset.n_samples
    weight = problem.noise / POSITION_STD
    extra = np.zeros((m + 3 * len(known), 3 * len(known)))
    _, centres = problem.unpack(x)
    for k, name in enumerate(known):
        j = names.index(name)
        rows = np.flatnonzero(dataset.fixture_index == j)
        for axis in range(3):
            extra[3 * rows + axis, 3 * k + axis] = -1.0
        for d, (a, b, _) in enumerate(spec.distances):
            if name in (a, b):
                delta = centres[names.index(a)] - centres[names.index(b)]
                sign = 1.0 if name == a else -1.0
                extra[3 * count + d, 3 * k : 3 * k + 3] = sign * problem.distance_weight * delta / np.linalg.norm(delta)
        extra[m + 3 * k : m + 3 * k + 3, 3 * k : 3 * k + 3] = weight * np.eye(3)
    full = np.hstack([np.vstack([jac, np.zeros((3 * len(known), f))]), extra])
    res = np.concatenate([r, np.zeros(3 * len(known))])
    groups: dict[str, np.ndarray] = {}
    kinds: dict[str, tuple] = {}
    for d, (a, b, _) in enumerate(spec.distances):
        groups[f"distance {a}-{b}"] = np.array([3 * count + d])
        kinds[f"distance {a}-{b}"] = ("distance", d, problem.distance_weight, DISTANCE_STD)
    for k, name in enumerate(known):
        groups[f"position {name}"] = m + 3 * k + np.arange(3)
        kinds[f"position {name}"] = ("position", name, weight, POSITION_STD)
    if len(names) > 1:
        for j, name in enumerate(names):
            rows = np.flatnonzero(dataset.fixture_index == j)
            groups[f"fixture {name}"] = (3 * rows[:, None] + np.arange(3)).ravel()
            kinds[f"fixture {name}"] = ("fixture", name, name in problem.free_centres, 0.0)
    centres = full.shape[1] - problem.n_free_params
    spread = np.concatenate([prior_std(problem.model)[problem.free], np.full(centres, CENTRE_SPREAD)])
    return full, res, groups, kinds, spread


def sets_scale_alone(problem: CalibrationProblem, kind: tuple) -> bool:
    """True when the constraint of ``kind`` is the only thing that sets the arm's absolute scale: the one known
    distance, or one of the only two known positions. Without it only the prior toward the nominal model holds
    the scale (:func:`unchecked_scale`, :func:`scale_shrink`)."""
    what = kind[0]
    if what not in ("distance", "position"):
        return False
    positions = len(known_positions(problem))
    distances = len(problem.spec.distances) - (what == "distance")
    positions -= what == "position"
    return distances < 1 and positions < 2


def unchecked_scale(problem: CalibrationProblem, kind: tuple) -> bool:
    """True when the constraint of ``kind`` sets the scale alone and nothing else can check it: a known position, or
    the one known distance without a prior toward the nominal model or beside a known position. The one distance
    of a fit with a prior is checked against the nominal model's lengths, the data's share of the refit without it
    taken out (:func:`scale_shrink`)."""
    if not sets_scale_alone(problem, kind):
        return False
    return kind[0] != "distance" or not problem.n_prior or bool(known_positions(problem))


def scale_shrink(problem: CalibrationProblem, x: np.ndarray, jac: np.ndarray, r: np.ndarray) -> float:
    """The share ``t`` by which a refit without the one known distance shrinks the arm for the samples' noise alone
    (``jac`` (M, F) and ``r`` (M,): the problem's Jacobian and residuals at ``x``).

    Spherical-joint data carry no scale: every length and centre scaled about the joint-1 axis point
    (:func:`.gauge.scale_centre`) by ``1 + e`` scales every sample residual by ``1 + e`` (``J_s v = r_s`` along that
    direction ``v``). Without the distance, the only data force along ``v`` is then that shrink, and the prior rows
    (``P = |J_p v|^2``) hold against it: the refit moves by ``t = r_s . J_s v / (|J_s v|^2 + P)`` of the scale, about
    ``3 K / (3 K + W sum (L_i / s_i)^2)`` for ``K`` samples at the declared noise (1.5 % for 1000 Panda samples: 1 mm
    over 50 mm; the leave-one-out read it as a distance 1 mm off). Taken out, what is left of the distance's
    disagreement is the nominal lengths' own, as their prior spread allows (a simulated Panda, 500 samples per socket
    at 0.3 mm: 1.06 mm predicted shrink against 0.94-1.18 mm measured).
    """
    params, centres = problem.unpack(x)
    lengths = np.array([kind.name == "length" for kind in problem.model.layout.kinds])
    lengths[problem.model.layout.base_xyz] = False  # the base stays: the scale acts about the joint-1 axis point
    v = problem.pack(np.where(lengths, params, 0.0), centres - scale_centre(problem.model))
    count = 3 * problem.dataset.n_samples
    along, prior = jac[:count] @ v, jac[problem.prior_rows()] @ v
    return float(r[:count] @ along / max(along @ along + prior @ prior, 1e-300))


def group_finding(problem: CalibrationProblem, name: str, kind: tuple, group: LeftOut, checkable: int,
                  unmodelled: float = 0.0, shrink: float = 0.0) -> Finding:
    """The leave-one-out finding of one group (see the module docstring).

    Args:
        problem, name, kind, group: the solved problem, the group's name and kind (:func:`augmented`) and its
            :class:`.leave_out.LeftOut`.
        checkable: how many groups are tested (the Bonferroni count).
        unmodelled: a fixture's expected variance per axis [m^2] of what the rest's fit cannot carry to its
            configurations: the arm's unmodelled error that the rest's residual shows beyond the declared noise,
            drawn fresh there (``selfcheck``; 0 for an arm within its noise). Added to the noise a fixture's
            samples are judged at: an arm whose model holds to a millimetre does not transfer to a fresh part
            of its workspace at a tenth of one, and that is not a fixture that moved.
    """
    what, key, weight, stated = kind
    spec, dataset = problem.spec, problem.dataset
    where = spec.source or "fixtures"
    if group.dof <= 0 or unchecked_scale(problem, kind):
        text = f"{name}: the data cannot check it (it alone determines what it constrains)"
        return Finding(name, True, text, {"unchecked": True})
    predicted = group.predicted + shrink  # the refit's shrink for noise alone taken out (:func:`scale_shrink`)
    scale = max(problem.noise, group.sigma_rest)
    judged = scale**2 + unmodelled  # variance per axis a fixture's samples are judged at (unmodelled: 0 otherwise)
    if what == "fixture":
        statistic = max(group.delta_ssr, 0.0) / judged
    else:  # the constraint's value as the rest predicts it, against its stated accuracy, socket play and the fit
        play = SOCKET_STD**2 * (2.0 if what == "distance" else 1.0)
        variance = stated**2 + play + group.fit_var * (scale / weight) ** 2
        statistic = float(np.sum((predicted / weight) ** 2 / variance))
    log10_p = log10_chi2_sf(statistic, group.dof)
    excess = float(np.sqrt(statistic / group.dof))  # per checked row, in standard deviations
    figures = {
        "statistic": statistic,
        "dof": group.dof,
        "rows": group.rows,
        "log10_p": log10_p,
        "excess": excess,
        "sigma_rest_mm": group.sigma_rest * 1e3,
        # the chi-square leaving it out removes beyond its degrees of freedom: below 0, no more than noise (a reviewer
        # trial could not read "explained: -74.9")
        "chi2_beyond_dof": max(group.delta_ssr, 0.0) / judged - group.dof,
    }
    if unmodelled > 0:
        figures["unmodelled_mm"] = float(np.sqrt(unmodelled)) * 1e3
    significant = log10_p < np.log10(ALPHA / max(checkable, 1)) and excess > GROUP_FACTOR
    if what == "fixture":
        predicted = predicted.reshape(-1, 3)
        if weight:  # its centre is an unknown: judge the shape of its samples, not where the rest put it
            predicted = predicted - predicted.mean(axis=0)
        size = float(np.sqrt(np.mean(np.sum(predicted**2, axis=1))))
        figures["disagreement_rms_mm"] = size * 1e3
        rows = dataset.select(np.flatnonzero(dataset.labels == key))
        # beside one other fixture, 'the other fixtures' and 'the others alone' read as a miscount (a review, MUKCa's
        # dinova_1 front: two sockets)
        one = len(dataset.fixture_names) == 2
        others, alone = ("the other fixture", "the other alone") if one else ("the other fixtures", "the others alone")
        causes = ["samples of another arm", "a fixture that moved", "a wrong label"]
        linked = [k for k, (a, b, _) in enumerate(spec.distances) if key in (a, b)]
        if linked:  # a wrong known distance moves the fixtures it joins: the fixture is blamed for it
            # one of the causes, in the same sentence: '; or a wrong known distance' was printed as a line of its own
            # starting 'or' (a review)
            causes.append("a wrong known distance (" + ", ".join(
                f"{where}: {spec.distance_field(k)}: {spec.distances[k][0]}-{spec.distances[k][1]} "
                f"{spec.distances[k][2]:.6g} m" for k in linked[:2]) + ")")
        text = (
            f"{samples_location(rows)}, field 'fixture': the samples at fixture {key} disagree with {others} by "
            f"{size * 1e3:.3g} mm rms ({alone}: residual {group.sigma_rest * 1e3:.3g} mm per "
            f"axis{_unmodelled_clause(unmodelled)}): {', '.join(causes[:-1])}, or {causes[-1]}"
        )
    else:
        value = predicted / weight
        size = float(np.linalg.norm(value))
        fit_std = float(np.sqrt(group.fit_var.mean())) * scale / weight
        figures.update({"disagreement_mm": size * 1e3, "stated_accuracy_mm": stated * 1e3, "fit_std_mm": fit_std * 1e3})
        if what == "distance":
            a, b, declared = spec.distances[key]
            against = ("the arm's nominal lengths (the only distance: the samples carry no scale, and the prior "
                       "holds the lengths within their spread)" if sets_scale_alone(problem, kind) else "the samples")
            text = (
                f"{where}: {spec.distance_field(key)}: distance {a}-{b} "
                f"({declared:.6g} m) disagrees with {against} by {size * 1e3:.3f} mm (its stated accuracy "
                f"{stated * 1e3:.3g} mm, socket play {SOCKET_STD * 1e3:.2g} mm, the fit's {fit_std * 1e3:.2g} mm)"
            )
        else:
            text = (
                f"{where}: {spec._row('fixtures.' + key)}field 'fixtures.{key}.position': the samples put {key} "
                f"{size * 1e3:.3f} mm from its known position (its stated accuracy {stated * 1e3:.3g} mm, socket "
                f"play {SOCKET_STD * 1e3:.2g} mm, the fit's {fit_std * 1e3:.2g} mm)"
            )
    return Finding(name, not significant, text, figures)


def _unmodelled_clause(unmodelled: float) -> str:
    """``", and the arm's unmodelled error expected there X mm"`` (per axis) when there is some."""
    if unmodelled <= 0:
        return ""
    return f", and the arm's unmodelled error expected there {np.sqrt(unmodelled) * 1e3:.3g} mm"


def name_culprit(groups: list[Finding], noise: float, level_factor: float) -> list[Finding]:
    """Mark the one failed group that explains the data's inconsistency, if there is one.

    Candidates are the failed groups whose removal leaves the rest at most ``level_factor`` x the
    noise; what removing them explains beyond noise (``dSSR / sigma^2 - dof``) ranks them.
    Those within :data:`CONTENDERS` of the best explain about as much: the smallest of them (a
    distance before a position before a fixture's samples: the simplest explanation) is the culprit,
    unless a second one of its size comes within :data:`MARGIN` of it (then none is).
    """
    failed = [f for f in groups if not f.passed and f.figures["sigma_rest_mm"] <= level_factor * noise * 1e3]
    if not failed:
        return groups

    def excess(f: Finding) -> float:
        return f.figures["chi2_beyond_dof"]

    best = max(excess(f) for f in failed)
    contenders = [f for f in failed if excess(f) >= (1.0 - CONTENDERS) * best]
    smallest = min(f.figures["rows"] for f in contenders)
    same = sorted((f for f in contenders if f.figures["rows"] == smallest), key=excess, reverse=True)
    if len(same) > 1 and excess(same[0]) - excess(same[1]) < MARGIN:
        return groups
    return [replace(f, culprit=True) if f is same[0] else f for f in groups]
