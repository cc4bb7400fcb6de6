"""The prior's heavy tail on simulated arms: does it help arms with a few large errors, and leave the others alone?

Simulated Pandas (``correction.perturb``: every parameter off by its prior spread, 1 mm / 0.2 deg), half of them
rigid, half elastic (the compliance of ``tests/identification/test_selection.py``); with ``--large`` (default 1)
one or two of the errors a real arm has are added: a joint zero (``theta2..theta6``) or a tool coordinate off by
4-8 prior spreads, sign at random (MUKCa's panda_2 has ``theta4`` 6 spreads off, panda_4 ``theta5`` and ``tool_x``).
Each arm is trained on one placement (MUKCa's protocol: two sockets 50 mm apart, 2 x 250 samples, 0.1 mm noise)
with ``auto`` (``select_model``: the candidates, BIC), and scored at 8 sockets the fit never saw (random
reachable points of the true arm, 30 noise-free configurations each): the mean spread of the predicted tool
points around their mean (the held-out MAE) [mm], for dh and for the model ``auto`` chose, for every tail
(``--tails``, in prior spreads; ``inf`` is the Gaussian prior, the library's default :data:`PRIOR_TAIL`; by
default ``inf`` and 3, the three-sigma rule).

    .venv/bin/python bench/prior_tail.py [--seeds 10] [--large 1] [--tails inf 3] [--out bench/prior_tail.json]

Prints one line per arm and the summary (mean, mean ratio to the Gaussian prior, worst ratio) and writes the JSON
(versions, seeds, every figure).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import bench_common  # first: one BLAS thread, no Rerun analytics
import numpy as np
from selection_real import C_TRUE, PLATE

from spherecal.correction import load_robot, perturb, tool_point
from spherecal.correction.elastic import with_compliance
from spherecal.identification.calibrate import calibrate
from spherecal.identification.problem import PRIOR
from spherecal.identification.selection import select_model
from spherecal.identification.synthetic import fixture_samples, make_dataset

HERE = Path(__file__).resolve().parent
#: The large errors a real arm has: a joint zero re-homed, the tool mounted off.
LARGE = ("theta2", "theta3", "theta4", "theta5", "theta6", "tool_x", "tool_y", "tool_z")
#: Held-out sockets per arm and configurations per socket.
SOCKETS, PER_SOCKET = 8, 30


def fitter(tail: float):
    """The candidates' fit as the workflow runs it (lm, prior :data:`PRIOR`), with the prior's tail at ``tail``."""
    def fit(start, data, spec, warm=None):
        return calibrate(start, data, spec, start=warm, check=False, prior=PRIOR, prior_tail=tail)
    return fit


def arm(panda, seed: int, elastic: bool, large: bool):
    """(truth, training dataset, spec, held-out sockets, the large errors added) of one simulated arm."""
    rng = np.random.default_rng(seed)
    truth = perturb(panda, rng)
    params, spread, added = truth.params.copy(), panda.layout.spread(), {}
    if large:
        for name in rng.choice(LARGE, size=int(rng.integers(1, 3)), replace=False):
            i = panda.param_index(str(name))
            added[str(name)] = float(rng.choice([-1.0, 1.0]) * rng.uniform(4.0, 8.0))
            params[i] += added[str(name)] * spread[i]
    truth = truth.with_params(params)
    truth = with_compliance(truth, C_TRUE) if elastic else truth
    dataset, spec = make_dataset(truth, PLATE, per_fixture=250, rng=rng, noise=1e-4)
    centres = tool_point(truth, truth.random_configurations(SOCKETS, rng))
    return dataset, spec, [fixture_samples(truth, c, PER_SOCKET, rng) for c in centres], added


def held_out(model, sockets) -> float:
    """Mean spread [mm] of ``model``'s tool points around their mean at each socket."""
    return bench_common.socket_mae(model, sockets) * 1e3


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="arms per plant (rigid, elastic) [1]")
    parser.add_argument("--large", type=int, default=1, help="add one or two large errors per arm (1) or not (0)")
    parser.add_argument("--tails", type=float, nargs="+", default=[np.inf, 3.0],
                        help="tails to compare [prior spreads] (inf: Gaussian; default inf 3)")
    parser.add_argument("--out", default=str(HERE / "prior_tail.json"), help="result file (JSON)")
    args = parser.parse_args()
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"uptime: {uptime}")
    clock = time.perf_counter()
    panda = load_robot("panda")
    rows = []
    for elastic, base in ((False, 1000), (True, 1500)):
        for seed in range(base, base + args.seeds):
            dataset, spec, sockets, added = arm(panda, seed, elastic, bool(args.large))
            row = {"seed": seed, "plant": "elastic" if elastic else "rigid", "large_spreads": added, "tails": {}}
            for tail in args.tails:
                selection = select_model("auto", fitter(tail), panda, dataset, spec)
                row["tails"][str(tail)] = {"dh_mm": held_out(selection.fits["dh"].model, sockets),
                                           "auto_mm": held_out(selection.fits[selection.chosen].model, sockets),
                                           "chosen": selection.chosen}
            rows.append(row)
            print(f"{row['plant']:<8} seed {seed}  large {added}  " + "  ".join(
                f"tail {t}: dh {v['dh_mm']:.4f} auto {v['auto_mm']:.4f} ({v['chosen']})"
                for t, v in row["tails"].items()), flush=True)
    reference = str(args.tails[0])
    summary = {}
    print(f"\nheld-out MAE [mm] over {len(rows)} arms, ratios to tail {reference}")
    for tail in map(str, args.tails):
        for kind in ("dh_mm", "auto_mm"):
            value = np.array([r["tails"][tail][kind] for r in rows])
            ratio = value / np.array([r["tails"][reference][kind] for r in rows])
            summary[f"{tail}/{kind}"] = {"mean_mm": float(value.mean()), "mean_ratio": float(ratio.mean()),
                                         "worst_ratio": float(ratio.max())}
            print(f"tail {tail:<5} {kind[:-3]:<5} mean {value.mean():.4f}  ratio {ratio.mean():.3f}  "
                  f"worst {ratio.max():.3f}")
        chosen = [r["tails"][tail]["chosen"] for r in rows]
        print(f"tail {tail:<5} chosen " + ", ".join(f"{c} {chosen.count(c)}" for c in dict.fromkeys(chosen)))
    out = bench_common.write_json(args.out, {"uptime": uptime, "seconds": time.perf_counter() - clock,
                                             "args": {**vars(args), "tails": [str(t) for t in args.tails]},
                                             "summary": summary, "arms": rows}, seed=1000, indent=1)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
