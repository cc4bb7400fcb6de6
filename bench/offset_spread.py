"""What-if: the prior spread of the joint zero offsets (theta) against held-out error on the real arms.

The layout gives every angle, joint zero offsets included, a prior spread of 0.2 deg. The Gen3 lite's offsets
sit ~1 deg from its URDF (``bench/gen3lite_diagnosis.py``: a fit of the offsets alone transfers better than the
full default fit). This script measures the trade-off: for each spread, each robot is trained on each placement
with ``run_workflow`` defaults (``--model auto``, forced so every row has a figure) and scored on the other
placements (test MAE [mm]); the Gen3 lite is MUKCa's ``gen3lite.urdf`` to its ball, the Pandas the embedded
Panda with MUKCa's ball (as ``bench/mukca.py``); each spread runs in its own process (the layout is built once
per process).

    .venv/bin/python bench/offset_spread.py [--data ../shared/data/mukca] [--spreads 0.2 1.0]
        [--robots dinova_1 panda_4_clean panda_2_clean]

Prints one line per (robot, spread): mean test MAE, mean ratio to nominal, each placement's figure; writes
``bench/offset_spread.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from mukca import _placement, held_out


def one(root: Path, robot: str, spread_deg: float) -> dict:
    """Every placement of ``robot`` as training, with the offsets' prior spread ``spread_deg`` [deg]."""
    import spherecal.correction.layout as layout

    offset = dataclasses.replace(layout.ANGLE, prior_std=float(np.deg2rad(spread_deg)))
    layout.JOINT_FIELDS = tuple((n, offset if n == "theta" else k) for n, k in layout.JOINT_FIELDS)
    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    warnings.simplefilter("ignore")  # the importer's joint-limit warning, known here
    from spherecal.correction import load_robot

    nominal = (load_robot(root / "urdf" / "gen3lite.urdf", tip_link="ball_link") if robot == "dinova_1"
               else bench_common.mukca_panda())  # the Gen3 lite as a user imports it, the Pandas as bench/mukca.py
    assert nominal.layout.kinds[nominal.layout.names.index("theta2")].prior_std == offset.prior_std
    data, _ = bench_common.mukca_dataset(root, robot, nominal)
    rows = {}
    for place in dict.fromkeys(_placement(n) for n in data.fixture_names):
        train, spec = bench_common.mukca_dataset(root, robot, nominal, [place])
        test = data.select(np.array([_placement(label) != place for label in data.labels]))
        done = run_workflow(nominal, train, spec, WorkflowOptions(force=True))
        rows[place] = {"nominal_mm": held_out(nominal, test)[0] * 1e3,
                       "calibrated_mm": held_out(done.model, test)[0] * 1e3, "chosen": done.selection.chosen}
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=None, help="MUKCa root (data/, urdf/)")
    parser.add_argument("--spreads", type=float, nargs="+", default=[0.2, 1.0], help="offset prior spreads [deg]")
    parser.add_argument("--robots", nargs="+", default=["dinova_1", "panda_4_clean", "panda_2_clean"])
    parser.add_argument("--one", nargs=2, metavar=("ROBOT", "DEG"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    root = args.data or bench_common.find_mukca()
    if args.one:
        print(json.dumps(one(root, args.one[0], float(args.one[1]))))
        return 0
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    results: dict = {}
    for robot in args.robots:
        for spread in args.spreads:
            done = subprocess.run([sys.executable, __file__, "--data", str(root), "--one", robot, str(spread)],
                                  capture_output=True, text=True, check=True)
            rows = json.loads(done.stdout.strip().splitlines()[-1])
            results.setdefault(robot, {})[str(spread)] = rows
            mean = np.mean([r["calibrated_mm"] for r in rows.values()])
            ratio = np.mean([r["calibrated_mm"] / r["nominal_mm"] for r in rows.values()])
            cells = "  ".join(f"{p} {r['calibrated_mm']:.3f}" for p, r in rows.items())
            print(f"{robot:14} offset spread {spread:4.2f} deg: mean test MAE {mean:.3f} mm ({ratio:.3f}x nominal)  "
                  f"{cells}", flush=True)
    out = bench_common.write_json(Path(__file__).with_name("offset_spread.json"), {"uptime": uptime,
                                  "results": results}, seed=0, inputs={"data": Path(root)})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
