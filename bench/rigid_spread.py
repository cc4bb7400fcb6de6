"""What-if: the URDF export's workspace spread around the recorded configurations, against held-out error on real arms.

``export --format urdf`` writes the best rigid fit to a model with joint-side terms (compliance, joint-angle scale)
over the recorded configurations and a sample around them, each joint N(0, ``SPREAD``) [rad] off a recorded one
(:mod:`spherecal.controller.rigid_fit`, 0.3 rad, measured at stop 6 on two Pandas' elastic models). This script
re-measures it on every MUKCa arm set of ``--data``: each placement with both sockets is the training one,
``run_workflow`` with its defaults (``auto``, forced so every row has a figure), and where the chosen model has
joint-side terms, the rigid fit at each ``--spreads`` value is scored on every socket of the other placements
(single-socket placements included): test MAE [mm], MUKCa's metric. The rigid model is scored directly, as the URDF
read back gives it (to 1e-9 m: ``tests/controller/test_export_rigid_fit.py``).

    .venv/bin/python bench/rigid_spread.py [--data ../shared/data/mukca] [--robots panda_2_clean ...]
        [--spreads 0.1 0.2 0.3 0.5 0.8]

Prints one line per training and, per kind of the chosen model, the mean ratio of each spread's error to the
shipped spread's (mean over trainings, mean over arms, worst); writes ``bench/rigid_spread.json`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from mukca import _nominal, _placement, held_out

import spherecal.controller.rigid_fit as rigid_fit
from spherecal.correction import SpherecalError
from spherecal.identification.workflow import WorkflowOptions, run_workflow

HERE = Path(__file__).resolve().parent


def run_robot(root: Path, robot: str, spreads: list[float]) -> list[dict]:
    """One row per two-socket training placement of ``robot``: auto's choice, the file's test MAE [mm] and, for a
    model with joint-side terms, the rigid fit's at each spread [mm]."""
    nominal = _nominal(robot, root)
    data, _ = bench_common.mukca_dataset(root, robot, nominal)
    places = list(dict.fromkeys(_placement(n) for n in data.fixture_names))
    sockets = {p: sum(_placement(n) == p for n in data.fixture_names) for p in places}
    rows = []
    for place in [p for p in places if sockets[p] == 2]:
        train, spec = bench_common.mukca_dataset(root, robot, nominal, [place])
        test = data.select(np.array([_placement(label) != place for label in data.labels]))
        try:
            done = run_workflow(nominal, train, spec, WorkflowOptions(force=True))
        except SpherecalError as error:
            print(f"{robot:<20} {place:<20} not calibrated: {error}", flush=True)
            continue
        row = {"robot": robot, "placement": place, "chosen": done.selection.chosen,
               "file_mm": held_out(done.model, test)[0] * 1e3, "rigid_mm": {}}
        if rigid_fit.joint_side_terms(done.model):
            shipped = rigid_fit.SPREAD
            try:
                for spread in spreads:
                    rigid_fit.SPREAD = spread
                    fit = rigid_fit.rigid_approximation(done.model, train.q, seed=0)
                    row["rigid_mm"][str(spread)] = held_out(fit.model, test)[0] * 1e3
            finally:
                rigid_fit.SPREAD = shipped
        rows.append(row)
        print(f"{robot:<20} {place:<20} {row['chosen']:<14} file {row['file_mm']:.3f}  "
              + "  ".join(f"{s}: {v:.3f}" for s, v in row["rigid_mm"].items()), flush=True)
    return rows


def summary(rows: list[dict], spreads: list[float]) -> list[str]:
    """Per kind of the chosen model: each spread's error over the shipped spread's (mean, mean of the arms' means,
    worst)."""
    shipped = str(rigid_fit.SPREAD)
    lines = [f"rigid fit's test MAE / at the shipped spread {shipped} rad (mean, mean over arms, worst)"]
    fitted = [r for r in rows if shipped in r["rigid_mm"]]
    for kind in sorted({r["chosen"] for r in fitted}) + ["every"]:
        chosen = [r for r in fitted if kind in ("every", r["chosen"])]
        robots = sorted({r["robot"] for r in chosen})
        cells = []
        for spread in map(str, spreads):
            ratio = [r["rigid_mm"][spread] / r["rigid_mm"][shipped] for r in chosen]
            per_arm = [np.mean([r["rigid_mm"][spread] / r["rigid_mm"][shipped] for r in chosen if r["robot"] == b])
                       for b in robots]
            cells.append(f"{spread}: {np.mean(ratio):.3f} {np.mean(per_arm):.3f} {max(ratio):.3f}")
        lines.append(f"{kind:<14} {len(chosen):>2} trainings, {len(robots):>2} arms   " + "   ".join(cells))
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=None, help="MUKCa root (data/, urdf/)")
    parser.add_argument("--robots", nargs="+", default=list(bench_common.MUKCA_SHARED),
                        help="robot folders under DATA/data")
    parser.add_argument("--spreads", nargs="+", type=float, default=[0.1, 0.2, 0.3, 0.5, 0.8],
                        help="workspace spreads to try [rad]")
    parser.add_argument("--out", type=Path, default=HERE / "rigid_spread.json", help="JSON written")
    args = parser.parse_args()
    root = args.data or bench_common.find_mukca()
    spreads = sorted(set(args.spreads) | {rigid_fit.SPREAD})
    warnings.simplefilter("ignore")  # the importer's joint-limit and parallel-axes warnings, known here
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    clock = time.perf_counter()
    rows = [row for robot in args.robots for row in run_robot(root, robot, spreads)]
    lines = summary(rows, spreads)
    print("\n".join(["", *lines]))
    out = bench_common.write_json(args.out, {"uptime": uptime, "seconds": time.perf_counter() - clock, "rows": rows,
                                             "summary": lines}, seed=0,
                                  inputs={"data": str(root), "robots": args.robots, "spreads": spreads})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
