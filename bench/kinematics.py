"""Throughput of the batched tool point and parameter Jacobian (one core).

Prints medians over repeats and writes ``bench/kinematics.json``. Targets (issue 3):
>= 1 000 000 tool points / s and >= 100 000 parameter-Jacobian rows-of-3 / s, batch 100 000.
"""

from __future__ import annotations

import platform
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.correction import joint_jacobian, load_robot, param_jacobian, tool_point  # noqa: E402
from spherecal.correction.chain import frames  # noqa: E402


def main() -> None:
    panda = load_robot("panda")
    batch = 100_000
    q = panda.random_configurations(batch, np.random.default_rng(0))
    cases = {
        "tool_point": lambda: tool_point(panda, q),
        "param_jacobian": lambda: param_jacobian(panda, q),
        "joint_jacobian": lambda: joint_jacobian(panda, q),
        "frames (baseline: all link frames)": lambda: frames(panda, q),
    }
    results = {}
    for name, function in cases.items():
        seconds = bench_common.median_time(function)
        results[name] = {"median_s": seconds, "per_second": batch / seconds}
    base = results["frames (baseline: all link frames)"]["median_s"]
    print(f"batch {batch}, median of 9, one thread ({platform.processor() or platform.machine()})")
    for name, r in results.items():
        print(
            f"  {name:36s} {r['median_s'] * 1e3:8.2f} ms  {r['per_second']:12,.0f} /s"
            f"  ({r['median_s'] / base:4.2f} x frames)"
        )
    ok_fk = results["tool_point"]["per_second"] >= 1e6
    ok_jac = results["param_jacobian"]["per_second"] >= 1e5
    print(f"targets: tool points >= 1e6/s {'met' if ok_fk else 'MISSED'}, "
          f"parameter Jacobian >= 1e5/s {'met' if ok_jac else 'MISSED'}")
    out = Path(__file__).with_suffix(".json")
    bench_common.write_json(out, {"batch": batch, "results": results}, seed=0)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
