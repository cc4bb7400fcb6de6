"""The default loss against least squares when a few presses were taken before the ball sat in its socket.

Simulated Panda (the embedded one off by the generic spread, seeds 1..N), three sockets of the default layout
with their distances known, ``--per-fixture`` presses each at ``--noise`` per axis; the first ``--unseated``
presses of each socket sit ``--offset`` from it in a random direction. Each recording is calibrated through
``run_workflow`` twice, with the default ``--loss auto`` (least squares, then Huber at 2.5x the noise the
residuals show) and ``--loss linear``; the error is the calibrated tool point against the true arm's over 2000
random configurations after the best rigid alignment (the world frame of a calibration from unknown sockets is
free), RMS [mm].

    .venv/bin/python bench/unseated_presses.py [--seeds 8] [--per-fixture 60] [--noise 0.15] [--unseated 3]
        [--offset 1.5] [--out bench/unseated_presses.json]

Prints one line per seed and the means, and writes the JSON (versions, seeds, inputs, every figure).
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import bench_common  # first: one BLAS thread
import numpy as np

from spherecal.correction import load_robot, perturb, registered_errors, tool_point
from spherecal.identification.synthetic import PANDA_FIXTURES, make_dataset, unseated
from spherecal.identification.workflow import WorkflowOptions, run_workflow

LOSSES = ("auto", "linear")


def aligned_error(model, true, q: np.ndarray) -> float:
    """RMS distance [m] of ``model``'s tool points from ``true``'s at ``q`` (N, n) after the best rigid fit."""
    return float(np.sqrt(np.mean(registered_errors(tool_point(model, q), tool_point(true, q)) ** 2)))


def recording(panda, seed: int, per_fixture: int, noise: float, count: int, offset: float):
    """(true arm, samples, spec): ``count`` presses per socket ``offset`` [m] off (``synthetic.unseated``)."""
    rng = np.random.default_rng(seed)
    true = perturb(panda, rng)
    data, spec = make_dataset(true, per_fixture=per_fixture, rng=rng, noise=noise)
    return true, unseated(true, data, PANDA_FIXTURES, count, offset, rng), spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="seeds 1..N (default 8)")
    parser.add_argument("--per-fixture", type=int, default=60, help="presses per socket (default 60)")
    parser.add_argument("--noise", type=float, default=0.15, help="socket noise std per axis [mm] (default 0.15)")
    parser.add_argument("--unseated", type=int, default=3, help="unseated presses per socket (default 3)")
    parser.add_argument("--offset", type=float, default=1.5, help="how far an unseated press sits [mm] (default 1.5)")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the calibrations' warnings: the figures are the point here
    panda = load_robot("panda")
    q = panda.random_configurations(2000, np.random.default_rng(7))
    rows, clock = [], time.perf_counter()
    for seed in range(1, args.seeds + 1):
        true, data, spec = recording(panda, seed, args.per_fixture, args.noise * 1e-3, args.unseated,
                                     args.offset * 1e-3)
        row = {"seed": seed}
        for loss in LOSSES:
            done = run_workflow(panda, data, spec, WorkflowOptions(loss=loss))
            row[f"{loss}_mm"] = aligned_error(done.model, true, q) * 1e3
        rows.append(row)
        print(f"seed {seed}: auto {row['auto_mm']:.4f} mm, linear {row['linear_mm']:.4f} mm", flush=True)
    auto, linear = (np.array([r[f"{loss}_mm"] for r in rows]) for loss in LOSSES)
    summary = {"auto_mean_mm": float(auto.mean()), "linear_mean_mm": float(linear.mean()),
               "ratio": float(auto.mean() / linear.mean()), "auto_better": int((auto < linear).sum()),
               "seeds": len(rows), "seconds": time.perf_counter() - clock}
    print(f"{args.unseated} unseated presses per socket, {args.offset} mm off, of {args.per_fixture} at "
          f"{args.noise} mm: auto {summary['auto_mean_mm']:.4f} mm, linear {summary['linear_mean_mm']:.4f} mm, "
          f"ratio {summary['ratio']:.3f}, auto better on {summary['auto_better']} of {len(rows)} seeds")
    bench_common.write_json(args.out, {"rows": rows, "summary": summary}, seed=1,
                            inputs={k: v for k, v in vars(args).items() if k != "out"})
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
