"""Model selection from one placement on real Pandas: which criterion picks the model that predicts other placements.

For every placement of every robot (MUKCa recordings; panda_2_clean has 8, panda_4_clean 3), train on that
placement alone (MUKCa's protocol: two sockets, 50 mm apart) and fit every candidate of
``identification.selection`` as ``auto`` fits them (``select_model``'s one-placement path: the workflow's
``lm`` fit, prior :data:`PRIOR`, after the workflow's deduplication); score each fit on the other placements
(test MAE [mm], ``bench/mukca.py``'s metric) and by every criterion below; report what each criterion
would have chosen, as mean ratios to dh and to the per-placement best model. Criteria (lower is better):

* ``bic``: the library's choice (``selection.information_criterion``: ``M ln(RSS/M) + ln(M) k_eff``) over the
  candidates it weighs from one placement (dh, scale, elastic: ``selection.COMBINED`` is left out);
* ``bic_all``: the same BIC over every candidate, elastic+scale included (the library's rule before stop 9);
* ``bic_rigid_elastic``: the same BIC over the candidates without a scale (dh, elastic);
* ``aic``: ``M ln(RSS/M) + 2 k_eff``;
* ``evidence``: minus twice the Laplace log evidence of the MAP fit. The prior rows are read as a Gaussian
  prior relative to the noise (std ``sigma s_i / (sqrt(W) noise)``, so the MAP is the fit's), centres flat,
  and ``sigma`` profiled out::

      (M - Fc) ln |R|^2 + ln det(J^T J) - 2 sum_i ln(sqrt(W) noise / s_i)

  ``R`` every residual at the solution (data and prior rows), ``J`` their Jacobian, ``Fc`` the centre unknowns;
* ``risk``: the posterior predictive error of the held-out metric: the fit's noise per axis
  ``RSS / (M - k_eff)`` plus the posterior variance (covariance ``sigma^2 (J^T J)^-1``) of the tool points'
  deviations from their mean, per axis, averaged over 8 virtual sockets at random reachable points of the
  nominal model (30 configurations each, ``identification.synthetic.fixture_samples``, seed 0);
* ``richest``: always elastic+scale.

With ``--simulated`` also the simulated arms of ``tests/identification/test_selection.py`` (one placement,
10 rigid and 10 elastic seeds): how often each rule chooses right (dh, elastic).

Then the mechanism of the scale term's failures: joint 4's offset ``theta4`` of the dh fit in prior spreads
(0.2 deg), and, for elastic+scale against dh, how far ``theta4`` moved and how much ``s4 q4 + c4 tau4`` adds to
joint 4's angle on the training samples (mean and spread over them, mdeg).

    .venv/bin/python bench/selection_real.py --data ../shared/data/mukca [--robots panda_2_clean panda_4_clean]
        (any MUKCa robot folder under DATA/data: panda*, kuka* (MUKCa's iiwa14.urdf to its ball), dinova*)
        [--prior 0.5] [--out bench/selection_real.json]

``--prior`` changes every fit's prior weight (the library's default :data:`PRIOR` otherwise): how robust
each rule's choice is to it. ``--tail K`` gives the prior a heavy tail beyond ``K`` prior spreads
(``identification.problem``; the library's default is the Gaussian prior).

Prints a table and writes ``bench/selection_real.json`` (versions, seed, inputs, every figure).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from mukca import _placement, held_out

from spherecal.correction import param_jacobian, tool_point
from spherecal.correction.files.samples import DEDUP_TOL
from spherecal.correction.gravity import gravity_torques
from spherecal.identification.calibrate import calibrate
from spherecal.identification.identifiability import normal_inverse
from spherecal.identification.problem import PRIOR, prior_std
from spherecal.identification.selection import (
    CANDIDATES,
    candidates_for,
    information_criterion,
    select_model,
    start_for,
)
from spherecal.identification.synthetic import fixture_samples

HERE = Path(__file__).resolve().parent
CRITERIA = ("bic", "bic_all", "bic_rigid_elastic", "aic", "evidence", "risk", "richest")
#: Virtual sockets of the ``risk`` criterion and configurations per socket.
SOCKETS, PER_SOCKET = 8, 30


def fitter(prior: float, tail: float | None = None):
    """The candidates' fit as ``identification.workflow`` runs it, at prior weight ``prior`` (and the prior's
    heavy tail at ``tail`` spreads; None: the library's default)."""
    def fit(start, data, spec, warm=None):
        return calibrate(start, data, spec, start=warm, check=False, prior=prior, prior_tail=tail)
    return fit


def _data_rows(result) -> tuple[np.ndarray, np.ndarray]:
    """(data residuals, all residuals) [m] of a fit at its solution."""
    r = result.problem.residuals(result.x)
    return r[~result.problem.prior_rows()], r


def aic(result) -> float:
    data, _ = _data_rows(result)
    return float(data.size * np.log(data @ data / data.size) + 2 * result.effective_unknowns)


def evidence(result) -> float:
    """Minus twice the Laplace log evidence, sigma profiled out (module docstring), up to a shared constant."""
    problem = result.problem
    data, every = _data_rows(result)
    jac = problem.jacobian(result.x)
    centres = 3 * len(problem.free_centres)
    _, logdet = np.linalg.slogdet(jac.T @ jac)
    return float((data.size - centres) * np.log(every @ every) + logdet - 2 * np.log(problem._prior_scale()).sum())


def virtual_sockets(model) -> list[np.ndarray]:
    """(SOCKETS,) arrays (PER_SOCKET, n) of configurations at random reachable points of ``model`` (seed 0)."""
    rng = np.random.default_rng(0)
    centres = tool_point(model, model.random_configurations(SOCKETS, rng))
    return [fixture_samples(model, c, PER_SOCKET, rng) for c in centres]


def risk(result, sockets: list[np.ndarray]) -> float:
    """Posterior predictive squared error per axis [m^2] of the held-out metric (module docstring)."""
    problem = result.problem
    data, _ = _data_rows(result)
    noise = float(data @ data) / (data.size - result.effective_unknowns)
    fp = problem.n_free_params
    cov = noise * normal_inverse(problem.jacobian(result.x))[:fp, :fp]
    variance = []
    for q in sockets:
        jac = param_jacobian(result.model, q)[:, :, problem.free]
        jac = jac - jac.mean(axis=0)
        variance.append(np.einsum("nij,jk,nik->n", jac, cov, jac).mean() / 3)
    return noise + float(np.mean(variance))


def joint4(fits: dict) -> dict:
    """The scale/compliance against offset trade at joint 4 (module docstring) [prior spreads, mdeg]."""
    dh, rich = fits["dh"], fits.get("elastic+scale")
    layout = dh.model.layout
    theta = layout.field("theta")[3]
    out = {"theta4_dh_prior_spreads": float((dh.model.params[theta] - dh.nominal.params[theta])
                                            / prior_std(dh.model)[theta])}
    if rich is not None:
        lay, q = rich.model.layout, rich.problem.dataset.q
        extra = rich.model.params[lay.scale][3] * q[:, 3]
        extra = extra + rich.model.params[lay.compliance][3] * gravity_torques(rich.model, q)[:, 3]
        out.update({
            "s4_prior_spreads": float(rich.model.params[lay.scale][3] / prior_std(rich.model)[lay.scale][3]),
            "q4_mean_rad": float(q[:, 3].mean()), "q4_std_rad": float(q[:, 3].std()),
            "theta4_moved_mdeg": float(np.rad2deg(rich.model.params[lay.field("theta")[3]] - dh.model.params[theta]))
            * 1e3,
            "s4q4_c4tau4_mean_mdeg": float(np.rad2deg(extra.mean())) * 1e3,
            "s4q4_c4tau4_std_mdeg": float(np.rad2deg(extra.std())) * 1e3,
        })
    return out


def run_robot(root: Path, robot: str, prior: float, tail: float | None = None) -> dict:
    nominal = (bench_common.mukca_panda() if bench_common.mukca_family(robot) == "panda"
               else bench_common.mukca_nominal(root, robot))
    dataset, _ = bench_common.mukca_dataset(root, robot, nominal)
    sockets = virtual_sockets(nominal)
    out = {}
    for place in dict.fromkeys(_placement(n) for n in dataset.fixture_names):
        train, spec = bench_common.mukca_dataset(root, robot, nominal, [place])
        train = train.deduplicated(DEDUP_TOL)
        test = dataset.select(np.array([_placement(label) != place for label in dataset.labels]))
        selection = select_model("auto", fitter(prior, tail), nominal, train, spec)
        fits = dict(selection.fits)
        weighed = tuple(fits)  # what the library weighs from one placement
        for name in candidates_for(nominal):  # and what it leaves out (selection.COMBINED), fitted alike
            if name not in fits:
                fits[name] = fitter(prior, tail)(start_for(name, nominal), train, spec)
        fits = {k: fits[k] for k in candidates_for(nominal)}
        mae = {k: held_out(f.model, test)[0] * 1e3 for k, f in fits.items()}
        scores = {"bic": {k: information_criterion(f) for k, f in fits.items()},
                  "aic": {k: aic(f) for k, f in fits.items()},
                  "evidence": {k: evidence(f) for k, f in fits.items()},
                  "risk": {k: risk(f, sockets) for k, f in fits.items()}}
        names = tuple(fits)
        chosen = {c: min(names, key=lambda k, s=s: (s[k], names.index(k))) for c, s in scores.items()}
        chosen["bic_all"], chosen["bic"] = chosen["bic"], min(weighed, key=lambda k: (scores["bic"][k], names.index(k)))
        chosen["richest"] = names[-1]
        plain = tuple(k for k in names if "scale" not in k)
        chosen["bic_rigid_elastic"] = min(plain, key=lambda k: (scores["bic"][k], plain.index(k)))
        assert chosen["bic"] == selection.chosen
        out[place] = {"test_mae_mm": mae, "scores": scores, "chosen": chosen, "joint4": joint4(fits)}
        j4 = {k: 0.0 for k in ("s4_prior_spreads", "theta4_moved_mdeg", "s4q4_c4tau4_mean_mdeg",
                               "s4q4_c4tau4_std_mdeg")} | out[place]["joint4"]
        print(f"{robot:<14} {place:<13} " + "  ".join(f"{k} {v:.3f}" for k, v in mae.items())
              + "  | " + " ".join(f"{c}:{chosen[c]}" for c in CRITERIA)
              + f"  | theta4(dh) {j4['theta4_dh_prior_spreads']:+.1f} sd, e+s: s4 {j4['s4_prior_spreads']:+.1f} sd,"
              f" theta4 {j4['theta4_moved_mdeg']:+.0f} mdeg, s4q4+c4tau4 {j4['s4q4_c4tau4_mean_mdeg']:+.0f}"
              f" +- {j4['s4q4_c4tau4_std_mdeg']:.0f} mdeg", flush=True)
    return out


#: The simulated single placement of ``tests/identification/test_selection.py`` (two sockets 50 mm apart).
PLATE = {"front_h0": (0.5, -0.025, 0.15), "front_h1": (0.5, 0.025, 0.15)}
#: The elastic plant of that test [rad/Nm].
C_TRUE = np.array([0.0, 1 / 3e4, 1 / 3e4, 1 / 3e4, 0.0, 0.0, 0.0])


def simulated(prior: float, seeds: int = 10, tail: float | None = None) -> dict:
    """Each rule's choice on the test's simulated arms (kinematic, 2 x 250 samples, 0.1 mm noise): rigid
    (seeds 0..) and elastic (seeds 100..), as ``test_bic_from_one_placement_keeps_dh_on_a_rigid_arm_...``."""
    from spherecal.correction import load_robot, perturb
    from spherecal.correction.elastic import with_compliance
    from spherecal.identification.synthetic import make_dataset

    panda = load_robot("panda")
    sockets = virtual_sockets(panda)
    out = {}
    for plant, compliance, base in (("rigid", None, 0), ("elastic", C_TRUE, 100)):
        choices = []
        for seed in range(base, base + seeds):
            rng = np.random.default_rng(seed)
            truth = perturb(panda, rng)
            truth = truth if compliance is None else with_compliance(truth, compliance)
            dataset, spec = make_dataset(truth, PLATE, per_fixture=250, rng=rng, noise=1e-4)
            fits = select_model("auto", fitter(prior, tail), panda, dataset, spec).fits
            names = tuple(fits)
            scores = {"bic": information_criterion, "aic": aic, "evidence": evidence,
                      "risk": lambda f: risk(f, sockets)}
            choices.append({c: min(names, key=lambda k, s=s: (s(fits[k]), names.index(k))) for c, s in scores.items()})
        out[plant] = choices
        print(f"simulated {plant:<8} " + "  ".join(
            f"{c}: {sum(ch[c] == ('dh' if compliance is None else 'elastic') for ch in choices)}/{seeds} right"
            for c in choices[0]), flush=True)
    return out


def summary(results: dict) -> tuple[list[str], dict]:
    rows = [r for out in results.values() for r in out.values()]
    dh = np.array([r["test_mae_mm"]["dh"] for r in rows])
    best = np.array([min(r["test_mae_mm"].values()) for r in rows])
    lines = ["", f"over {len(rows)} training placements: test MAE [mm] of the model each rule takes",
             f"{'rule':<14} {'mean':>7} {'/dh':>7} {'/best':>7} {'worst/dh':>9}"]
    figures = {}
    for rule in (*CANDIDATES, *CRITERIA, "best"):
        if rule in CANDIDATES:
            mae = np.array([r["test_mae_mm"][rule] for r in rows])
        elif rule == "best":
            mae = best
        else:
            mae = np.array([r["test_mae_mm"][r["chosen"][rule]] for r in rows])
        figures[rule] = {"mean_mm": float(mae.mean()), "ratio_dh": float(np.mean(mae / dh)),
                         "ratio_best": float(np.mean(mae / best)), "worst_ratio_dh": float(np.max(mae / dh))}
        f = figures[rule]
        lines.append(f"{rule:<14} {f['mean_mm']:7.3f} {f['ratio_dh']:7.3f} {f['ratio_best']:7.3f} "
                     f"{f['worst_ratio_dh']:9.3f}")
    return lines, figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None,
                        help="MUKCa root (data/, urdf/); default: shared/data/mukca beside the checkout")
    parser.add_argument("--robots", nargs="+", default=["panda_2_clean", "panda_4_clean"])
    parser.add_argument("--prior", type=float, default=PRIOR,
                        help=f"prior weight W of every fit [1] (default the library's {PRIOR})")
    parser.add_argument("--tail", type=float, default=None,
                        help="where the prior's heavy tail starts [prior spreads] (default: the library's)")
    parser.add_argument("--simulated", action="store_true",
                        help="also the test's simulated rigid and elastic arms, 10 seeds each (about a minute)")
    parser.add_argument("--out", default=str(HERE / "selection_real.json"), help="result file (JSON)")
    args = parser.parse_args()
    root = Path(args.data) if args.data else bench_common.find_mukca()
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    clock = time.perf_counter()
    results = {robot: run_robot(root, robot, args.prior, args.tail) for robot in args.robots}
    lines, figures = summary(results)
    print("\n".join(lines))
    if args.simulated:
        figures["simulated"] = simulated(args.prior, tail=args.tail)
    out = bench_common.write_json(args.out, {
        "uptime": uptime, "prior": args.prior, "tail": args.tail, "seconds": time.perf_counter() - clock,
        "summary": figures, "results": results},
        seed=0, inputs={"data": Path(root)}, indent=1)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
