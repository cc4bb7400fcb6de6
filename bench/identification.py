"""Speed of `lm` on 3 x 500 noise-free samples (goal: <= 0.3 s wall, median), and the comparison table.

Usage: python bench/identification.py [--table]

Prints medians and writes bench/identification.json. ``--table`` also runs lm, pso and pso+lm on
noise-free and 0.3 mm noisy data, from the nominal model and from a far start (10x the
perturbation), and prints accuracy (mean / max position error over 5000 random configurations
after the best rigid fit, and raw), final residual and wall time.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.correction import load_robot, perturb, registered_errors, tool_point  # noqa: E402
from spherecal.identification.calibrate import calibrate
from spherecal.identification.problem import ImplausibleCalibrationError  # noqa: E402
from spherecal.identification.selfcheck import InconsistentDataError  # noqa: E402
from spherecal.identification.synthetic import make_dataset  # noqa: E402


def main() -> None:
    panda = load_robot("panda")
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, rng=np.random.default_rng(2))
    calibrate(panda, dataset, spec)  # warm-up (imports)
    walls = []
    for _ in range(7):
        start = time.perf_counter()
        calibrate(panda, dataset, spec)
        walls.append(time.perf_counter() - start)
    median = float(np.median(walls))
    print(f"lm on 3 x 500 samples: median {median:.3f} s (p90 {np.percentile(walls, 90):.3f} s) goal <= 0.3 s")
    results: dict = {"lm_3x500_median_s": median, "lm_3x500_runs_s": walls}
    if "--table" in sys.argv:
        results["table"] = table(panda, true)
    bench_common.write_json(Path(__file__).with_suffix(".json"), results, inputs={"true_robot_seed": 1, "data_seed": 2})


def table(panda, true) -> list[dict]:
    q = true.random_configurations(5000, np.random.default_rng(5))
    reference = tool_point(true, q)
    far = perturb(panda, np.random.default_rng(9), 1e-2, np.deg2rad(2.0), 1e-2)
    rows = []
    for name, model in (("nominal", panda), ("far", far)):
        points = tool_point(model, q)
        errors = registered_errors(points, reference)
        raw = np.linalg.norm(points - reference, axis=1).mean()
        print(
            f"start {name}: mean {errors.mean() * 1e3:.3f} mm, max {errors.max() * 1e3:.3f} mm, "
            f"raw mean {raw * 1e3:.3f} mm"
        )
    print(
        f"{'data':<10} {'start':<8} {'method':<7} {'mean mm':>9} {'max mm':>9} {'raw mm':>8} "
        f"{'rms mm':>9} {'wall s':>7}"
    )
    for noise in (0.0, 3e-4):
        dataset, spec = make_dataset(true, rng=np.random.default_rng(3), noise=noise)
        for start_name, start in (("nominal", panda), ("far", far)):
            for method in ("lm", "pso", "pso+lm"):
                label = "noise-free" if noise == 0 else f"{noise * 1e3:.1f} mm"
                clock = time.perf_counter()
                try:
                    result = calibrate(panda, dataset, spec, method=method, start=start)
                except (ImplausibleCalibrationError, InconsistentDataError) as error:  # refused: say why, go on
                    wall = time.perf_counter() - clock
                    rows.append({"noise_mm": noise * 1e3, "start": start_name, "method": method, "refused": str(error)})
                    text = str(error)
                    why = text.split(": the fit ")[1].split(":")[0] if ": the fit " in text else text.split(": ", 1)[1]
                    print(f"{label:<10} {start_name:<8} {method:<7} {'refused':>9} {'':>9} {'':>8} {'':>9} {wall:7.2f}"
                          f"  ({why[:110]})")
                    continue
                wall = time.perf_counter() - clock
                points = tool_point(result.model, q)
                errors = registered_errors(points, reference)
                raw = np.linalg.norm(points - reference, axis=1)
                row = {
                    "noise_mm": noise * 1e3,
                    "start": start_name,
                    "method": method,
                    "mean_mm": errors.mean() * 1e3,
                    "max_mm": errors.max() * 1e3,
                    "raw_mean_mm": raw.mean() * 1e3,
                    "rms_mm": result.rms_after * 1e3,
                    "wall_s": wall,
                }
                rows.append(row)
                print(
                    f"{label:<10} {start_name:<8} {method:<7} {row['mean_mm']:9.3g} {row['max_mm']:9.3g} "
                    f"{row['raw_mean_mm']:8.3f} {row['rms_mm']:9.3g} {wall:7.2f}"
                )
    return rows


if __name__ == "__main__":
    main()
