"""Recording guidance against real recordings (no simulation): does the plan pick a placement that helps?

For each robot of MUKCa's data (``panda_2_clean``: 8 placements, ``panda_4_clean``: 3, ``dinova_1``: 4) and
each *first* placement: the plan (:func:`validation.planning.guidance.rank_placements`) ranks the other
placements as candidates, knowing only what a user knows: the recording of the first placement, and where
each candidate's sockets are (the first calibration's tool point at the mean of the configurations recorded
there: where the user would put the plate). Its configurations at a candidate are made kinematically (the first
placement's postures carried over, or random walks: ``--postures``); the recorded configurations of the candidates
are never used by the prediction. Then what adding each candidate
actually does: calibrate on first + candidate (``--actual workflow``, default: as `spherecal calibrate` does it,
the one workflow's model choice and prior, forced, as the plan calibrates the first placement; ``plain``: the
library's :func:`calibrate` defaults, plain least squares on the nominal layout, as before), test
MAE (MUKCa's metric: mean distance of the predicted ball centres from their mean, per socket) on the
remaining placements, and its change against the first placement's calibration on the same sockets.

The plan's configurations are random (walks; the carried-over postures' order and any walk that fills them), so
its pick may depend on the seed: the whole is repeated for ``--seeds`` seeds (the actual outcomes do not depend
on it) and the summary is over every (seed, first) pair.
Printed per robot: Spearman rank correlation of the plan's order (best first) against the actual test MAE and
against the actual change, how often the plan's pick is in the better half of the candidates (its change
below the median; with 2 or 3 candidates: the best one), and the mean change of the plan's picks against a
random pick (the candidates' mean) and the best pick. ``--judged-on``, ``--unmodelled``, ``--postures`` and
``--smooth`` set the plan's rules (:mod:`validation.planning.guidance`). Writes
``bench/plan_real_<judged on>_<unmodelled>_<postures>_<smooth>_<actual>.json``.

    .venv/bin/python bench/plan_real.py [--data ../shared/data/mukca] [--judged-on whole --postures walk]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np

from spherecal.correction import tool_point
from spherecal.identification.calibrate import calibrate
from spherecal.validation.planning import guidance as guidance_module
from spherecal.validation.planning.guidance import calibrate_recording, rank_placements
from spherecal.validation.planning.placements import Placement
from spherecal.validation.sockets import socket_validation

HERE = Path(__file__).resolve().parent
SEEDS = 5


def _mean_defined(values: list[float]) -> float:
    """Mean of the defined values; nan when none is (2 candidates: no rank correlation)."""
    defined = [v for v in values if np.isfinite(v)]
    return float(np.mean(defined)) if defined else float("nan")


def spearman(a: list[float], b: list[float]) -> float:
    """Spearman rank correlation (no ties expected in continuous figures); nan below 3 pairs."""
    if len(a) < 3:
        return float("nan")
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1])


def robot_rows(root: Path, robot: str, seeds: int, how: str = "workflow") -> dict:
    model = bench_common.mukca_nominal(root, robot)
    everything, _ = bench_common.mukca_dataset(root, robot, model)
    placements = sorted({n.rpartition("_h")[0] for n in everything.fixture_names})
    data = {p: bench_common.mukca_dataset(root, robot, model, [p]) for p in placements}

    def test_mae(calibrated, left_out: list[str]) -> float:
        rest = [p for p in placements if p not in left_out]
        dataset, spec = bench_common.mukca_dataset(root, robot, model, rest)
        report = socket_validation({"c": calibrated}, dataset, spec)
        return float(np.mean([f.mean["c"] for f in report.fixtures]))

    rows, actual = {}, {}
    for seed, first in ((s, f) for s in range(seeds) for f in placements):
        clock = time.perf_counter()
        recorded = calibrate_recording(model, *data[first], seed=seed)
        others = [p for p in placements if p != first]
        candidates = []
        for p in others:
            dataset, spec = data[p]
            sockets = {n: tool_point(recorded.model, dataset.for_fixture(n)).mean(axis=0)
                       for n in dataset.fixture_names}
            candidates.append(Placement(p, sockets, tuple(spec.distances)))
        guidance = rank_placements(recorded, candidates, np.random.default_rng(seed))
        planned = time.perf_counter() - clock
        predicted = {j.placement.name: j.error for j in guidance.ranking}
        position = {j.placement.name: k for k, j in enumerate(guidance.ranking)}  # the plan's order, best first
        mae, change = {}, {}
        for p in others:
            if (first, p) not in actual:  # no seed in it: once per pair
                dataset, spec = bench_common.mukca_dataset(root, robot, model, [first, p])
                fitted = (calibrate_recording(model, dataset, spec).model if how == "workflow"
                          else calibrate(model, dataset, spec, check=False).model)
                after = test_mae(fitted, [first, p])
                actual[first, p] = (after, after - test_mae(recorded.model, [first, p]))
            mae[p], change[p] = actual[first, p]
        pick = guidance.ranking[0].placement.name
        values = sorted(change.values())
        better = change[pick] < np.median(values) if len(values) > 3 else change[pick] == values[0]
        ranked = [j.placement.name for j in guidance.ranking]
        rows[f"{first} seed {seed}"] = {
            "pick": pick,
            "pick_rank_by_change": sorted(change, key=change.get).index(pick) + 1,
            "better_half": bool(better),
            "spearman_test_mae": spearman([position[p] for p in ranked], [mae[p] for p in ranked]),
            "spearman_change": spearman([position[p] for p in ranked], [change[p] for p in ranked]),
            "predicted_gain_mm": {j.placement.name: j.gain * 1e3 for j in guidance.ranking},
            "pick_change_mm": change[pick] * 1e3,
            "random_change_mm": float(np.mean(values)) * 1e3,
            "best_change_mm": values[0] * 1e3,
            "predicted_error_mm": {p: predicted[p] * 1e3 for p in ranked},
            "test_mae_mm": {p: v * 1e3 for p, v in mae.items()},
            "change_mm": {p: v * 1e3 for p, v in change.items()},
            "noise_mm": recorded.noise * 1e3,
            "stop_line": guidance.stop_line(),
            "plan_seconds": planned,
        }
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="MUKCa data folder (default: shared/data/mukca found upward)")
    parser.add_argument("--smooth", choices=("variogram", "residual"), default=guidance_module.SMOOTH,
                        help="scales of the unexplained error (validation.planning.guidance.SMOOTH)")
    parser.add_argument("--judged-on", choices=("sockets", "held-out", "whole"), default=guidance_module.JUDGED_ON,
                        help="where a candidate is judged (validation.planning.guidance.JUDGED_ON)")
    parser.add_argument("--unmodelled", choices=("declared", "variogram"), default=guidance_module.UNMODELLED,
                        help="how the recording's residual splits into socket noise and the arm's unmodelled error "
                             "(validation.planning.guidance.UNMODELLED; judged on sockets only)")
    parser.add_argument("--postures", choices=("recorded", "walk"), default=guidance_module.POSTURES,
                        help="configurations at a candidate: the recorded postures carried over, or random walks "
                             "(validation.planning.guidance.POSTURES)")
    parser.add_argument("--actual", choices=("workflow", "plain"), default="workflow",
                        help="how first + candidate is calibrated for the actual outcome (see the module docstring)")
    parser.add_argument("--seeds", type=int, default=SEEDS, help=f"plan seeds 0..N-1 (default {SEEDS})")
    parser.add_argument("--robots", nargs="+", default=list(bench_common.MUKCA_SHARED),
                        help="robot folders under DATA/data (family by name: panda*, dinova*, kuka*)")
    parser.add_argument("--out", type=Path, default=None, help="result file (default: named by the rules, in bench/)")
    args = parser.parse_args()
    guidance_module.SMOOTH = args.smooth
    guidance_module.JUDGED_ON = args.judged_on
    guidance_module.UNMODELLED = args.unmodelled
    guidance_module.POSTURES = args.postures
    root = Path(args.data) if args.data else bench_common.find_mukca()
    print(subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    results = {}
    print(f"{'robot':<14} {'first, seed':<21} {'pick':<14} {'rank':>4} {'better':>6} {'rho MAE':>7} {'rho chg':>7} "
          f"{'pick chg':>8} {'random':>8} {'best':>8}  [mm]")
    for robot in args.robots:
        if not (root / "data" / robot).is_dir():
            print(f"{robot}: not found under {root}, skipped")
            continue
        rows = robot_rows(root, robot, args.seeds, args.actual)
        for first, r in rows.items():
            print(f"{robot:<14} {first:<21} {r['pick']:<14} {r['pick_rank_by_change']:>4} {str(r['better_half']):>6} "
                  f"{r['spearman_test_mae']:7.2f} {r['spearman_change']:7.2f} {r['pick_change_mm']:8.3f} "
                  f"{r['random_change_mm']:8.3f} {r['best_change_mm']:8.3f}")
        summary = {
            "better_half": f"{sum(r['better_half'] for r in rows.values())}/{len(rows)}",
            "mean_spearman_test_mae": _mean_defined([r["spearman_test_mae"] for r in rows.values()]),
            "mean_spearman_change": _mean_defined([r["spearman_change"] for r in rows.values()]),
            "mean_pick_change_mm": float(np.mean([r["pick_change_mm"] for r in rows.values()])),
            "mean_random_change_mm": float(np.mean([r["random_change_mm"] for r in rows.values()])),
            "mean_best_change_mm": float(np.mean([r["best_change_mm"] for r in rows.values()])),
        }
        print(f"{robot:<14} summary: pick in the better half {summary['better_half']}, mean Spearman vs test MAE "
              f"{summary['mean_spearman_test_mae']:.2f}, vs change {summary['mean_spearman_change']:.2f}; mean change "
              f"[mm] pick {summary['mean_pick_change_mm']:.3f}, random {summary['mean_random_change_mm']:.3f}, "
              f"best {summary['mean_best_change_mm']:.3f}")
        results[robot] = {"rows": rows, "summary": summary}
    rules = f"{args.judged_on}_{args.unmodelled}_{args.postures}_{args.smooth}_{args.actual}"
    out = args.out or HERE / f"plan_real_{rules}.json"
    bench_common.write_json(out, {"plan_real": results, "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS")},
                            inputs={"seeds": args.seeds, "smooth": args.smooth, "judged_on": args.judged_on,
                                    "unmodelled": args.unmodelled, "postures": args.postures,
                                    "actual": args.actual, "data": root})
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
