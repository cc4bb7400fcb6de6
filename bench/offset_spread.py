"""What-if: how wide the joint zeros (theta) are allowed to be, against held-out error on the real arms.

Two places can widen them (``--where``):

* ``prior``: the prior spread of the zeros in the MAP prior, in pruning and everywhere else (the layout's ANGLE
  kind for ``theta``; 0.2 deg by default). Measured at stop 8: 0.2 -> 1.0 deg takes dinova_1 0.768x -> 0.637x
  nominal but panda_2_clean 0.421 -> 0.462 mm: not adopted.
* ``tolerance``: :data:`spherecal.identification.problem.ZERO_TOLERANCE`, what pruning judges a zero's excitation
  against and what the plausibility limit counts as a real arm's error; the MAP prior keeps 0.2 deg (adopted at
  stop 10 with 1 deg).

Each robot is trained on each placement with both sockets, ``run_workflow`` defaults (``--model auto``, forced so
every row has a figure), and scored on the other placements (test MAE [mm]); the Gen3 lites and the iiwa14 are
MUKCa's URDFs to the ball, the Pandas the embedded Panda with MUKCa's ball (as ``bench/mukca.py``); each value runs
in its own process (the layout is built once per process).

    .venv/bin/python bench/offset_spread.py [--data ../shared/data/mukca] [--where tolerance] [--spreads 0.2 1.0]
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


def one(root: Path, robot: str, spread_deg: float, where: str = "prior") -> dict:
    """Every two-socket placement of ``robot`` as training, with the zeros' prior spread (``where="prior"``) or
    their tolerance (``"tolerance"``) at ``spread_deg`` [deg]."""
    import spherecal.correction.layout as layout
    import spherecal.identification.problem as problem

    if where == "prior":
        offset = dataclasses.replace(layout.ANGLE, prior_std=float(np.deg2rad(spread_deg)))
        layout.JOINT_FIELDS = tuple((n, offset if n == "theta" else k) for n, k in layout.JOINT_FIELDS)
    else:
        problem.ZERO_TOLERANCE = float(np.deg2rad(spread_deg))
    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    warnings.simplefilter("ignore")  # the importer's joint-limit warning, known here
    from spherecal.correction import load_robot

    family = bench_common.mukca_family(robot)  # the Gen3 lite and iiwa14 as a user imports them, the Pandas as
    nominal = (bench_common.mukca_panda() if family == "panda"  # bench/mukca.py
               else load_robot(root / "urdf" / bench_common.MUKCA_FAMILIES[family][0], tip_link="ball_link"))
    data, _ = bench_common.mukca_dataset(root, robot, nominal)
    rows = {}
    places = [_placement(n) for n in data.fixture_names]
    for place in dict.fromkeys(p for p in places if places.count(p) > 1):
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
    parser.add_argument("--where", choices=("prior", "tolerance"), default="prior",
                        help="widen the zeros' prior spread (everywhere) or their tolerance (pruning, plausibility)")
    parser.add_argument("--one", nargs=2, metavar=("ROBOT", "DEG"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    root = args.data or bench_common.find_mukca()
    if args.one:
        print(json.dumps(one(root, args.one[0], float(args.one[1]), args.where)))
        return 0
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    results: dict = {}
    for robot in args.robots:
        for spread in args.spreads:
            done = subprocess.run([sys.executable, __file__, "--data", str(root), "--where", args.where, "--one", robot,
                                   str(spread)],
                                  capture_output=True, text=True, check=True)
            rows = json.loads(done.stdout.strip().splitlines()[-1])
            results.setdefault(robot, {})[str(spread)] = rows
            mean = np.mean([r["calibrated_mm"] for r in rows.values()])
            ratio = np.mean([r["calibrated_mm"] / r["nominal_mm"] for r in rows.values()])
            cells = "  ".join(f"{p} {r['calibrated_mm']:.3f}" for p, r in rows.items())
            print(f"{robot:14} zeros' {args.where} {spread:4.2f} deg: mean test MAE {mean:.3f} mm "
                  f"({ratio:.3f}x nominal)  {cells}", flush=True)
    out = bench_common.write_json(Path(__file__).with_name("offset_spread.json"), {"uptime": uptime,
                                  "where": args.where, "results": results}, seed=0, inputs={"data": Path(root)})
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
