"""Per-joint coverage at the default fixtures, both exploration modes, several seeds.

Noise-free 20 s of self-motion per fixture on a perturbed Panda (a new true robot per seed).
Prints, per mode, the coverage [%] of every joint at every fixture, the smallest, the
constraint violation [mm] and the limit excess, then how many (seed, fixture) runs reach
30% on every joint. Writes ``bench/coverage.json``. Usage: ``python bench/coverage.py [SEEDS]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.controller.self_motion import (  # noqa: E402
    DEFAULT_FIXTURES,  # noqa: E402
    SelfMotionSettings,
    collect_self_motion,
)
from spherecal.correction import load_robot, perturb  # noqa: E402


def main(seeds: int = 5) -> None:
    panda = load_robot("panda")
    fixtures = {k: np.array(v) for k, v in DEFAULT_FIXTURES.items()}
    out = {}
    for mode in ("coverage", "random"):
        ok, total, worst_violation, rows = 0, 0, 0.0, []
        for seed in range(seeds):
            rng = np.random.default_rng(seed)
            true = perturb(panda, rng)
            start = time.perf_counter()
            run = collect_self_motion(true, panda, fixtures, rng, SelfMotionSettings(seconds=20.0, mode=mode))
            print(f"\nmode {mode}, seed {seed} ({time.perf_counter() - start:.1f} s wall)")
            print(run.coverage_table())
            ok += int(np.sum(np.all(run.coverage >= 0.30, axis=1)))
            total += len(fixtures)
            worst_violation = max(worst_violation, float(run.max_violation.max()))
            rows.append({"seed": seed, "coverage": run.coverage.tolist(), "max_violation_m": run.max_violation.tolist(),
                         "limit_excess_rad": run.limit_excess.tolist(), "fallbacks": run.fallbacks})
        print(f"\n{mode}: {ok}/{total} (seed, fixture) runs with every joint >= 30%; "
              f"worst violation {worst_violation * 1e3:.4f} mm")
        out[mode] = {"runs_all_joints_30pct": ok, "runs": total, "worst_violation_m": worst_violation, "rows": rows}
    out["fixtures"] = {k: list(v) for k, v in DEFAULT_FIXTURES.items()}
    bench_common.write_json(Path(__file__).with_suffix(".json"), out, inputs={"seeds": seeds})


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
