"""Each fixture weighed by the noise it shows (``--loss auto``, ``identification.fixture_noise``) against every fixture
weighed alike, on real arms: MUKCa recordings trained on each placement with two sockets in turn (MUKCa's protocol,
``run_workflow`` defaults, forced so that every row has a figure; a refusal is marked ``*``), held-out test MAE [mm]
on the other placements (``bench/mukca.py``'s metric), through the calibrated model.

The reference switches the weights off in the same process (every fixture 1, the same fit otherwise: the Huber
scale is the noise of all samples, as before the weights). Also printed: each training socket's noise and weight.

    .venv/bin/python bench/fixture_weights.py --data <MUKCa layout> --robots panda_2_clean panda_4_clean dinova_1

Writes ``bench/fixture_weights.json`` (versions, inputs, every figure).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from mukca import _nominal, _placement, held_out

from spherecal.identification import calibrate as calibrate_module
from spherecal.identification.fixture_noise import FixtureNoise, fixture_noise
from spherecal.identification.workflow import WorkflowOptions, run_workflow

HERE = Path(__file__).resolve().parent


def _equal(problem, x) -> FixtureNoise:
    """Every fixture weighs 1: the fit before the weights."""
    shown = fixture_noise(problem, x)
    return FixtureNoise(shown.noise, {n: 1.0 for n in shown.weights}, shown.common, shown.common)


def _fit(nominal, train, spec, test, equal: bool) -> dict:
    calibrate_module.fixture_noise = _equal if equal else fixture_noise
    try:
        done = run_workflow(nominal, train, spec, WorkflowOptions(force=True))
    finally:
        calibrate_module.fixture_noise = fixture_noise
    check = done.result.selfcheck
    return {"test_mae_mm": held_out(done.model, test)[0] * 1e3, "chosen": done.selection.chosen,
            "refused": check is not None and not check.consistent,
            "fixture_noise": None if done.result.fixture_noise is None else done.result.fixture_noise.block()}


def run_robot(root: Path, robot: str) -> list[dict]:
    nominal = _nominal(robot, root)
    dataset, _ = bench_common.mukca_dataset(root, robot, nominal)
    places = list(dict.fromkeys(_placement(n) for n in dataset.fixture_names))
    rows = []
    for place in places:
        train, spec = bench_common.mukca_dataset(root, robot, nominal, [place])
        if len(train.fixture_names) < 2:
            continue
        test = dataset.select(np.array([_placement(label) != place for label in dataset.labels]))
        row = {"robot": robot, "train": place, "nominal_mm": held_out(nominal, test)[0] * 1e3,
               "weighted": _fit(nominal, train, spec, test, equal=False),
               "equal": _fit(nominal, train, spec, test, equal=True)}
        rows.append(row)
        w, e = row["weighted"], row["equal"]
        shown = ", ".join(f"{k} {v:.3f} mm x{w['fixture_noise']['weights'][k]:.2f}"
                          for k, v in w["fixture_noise"]["noise_mm"].items())
        print(f"{robot:<14} {place:<20} nominal {row['nominal_mm']:7.3f}  weighted {w['test_mae_mm']:7.3f}"
              f"{'*' if w['refused'] else ' '} ({w['chosen']})  equal {e['test_mae_mm']:7.3f}"
              f"{'*' if e['refused'] else ' '} ({e['chosen']})  {shown}", flush=True)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=None, help="MUKCa root (data/, urdf/); default: shared/data/mukca")
    parser.add_argument("--robots", nargs="+", default=list(bench_common.MUKCA_SHARED),
                        help="robot folders under DATA/data (panda*, dinova*, kuka*)")
    parser.add_argument("--out", type=Path, default=HERE / "fixture_weights.json")
    args = parser.parse_args()
    root = Path(args.data) if args.data else bench_common.find_mukca()
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    rows = [row for robot in args.robots for row in run_robot(root, robot)]
    print("\nmean held-out test MAE [mm] over the trainings: nominal, weighted, equal, weighted / equal")
    for robot in args.robots:
        mine = [r for r in rows if r["robot"] == robot]
        if not mine:
            continue
        nominal, weighted, equal = (float(np.mean([r[k] if k == "nominal_mm" else r[k]["test_mae_mm"] for r in mine]))
                                    for k in ("nominal_mm", "weighted", "equal"))
        print(f"{robot:<14} {nominal:7.3f} {weighted:7.3f} {equal:7.3f}  {weighted / equal:.3f}x")
    out = bench_common.write_json(args.out, {"uptime": uptime, "rows": rows}, seed=0, inputs={"data": Path(root)},
                                  indent=1)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
