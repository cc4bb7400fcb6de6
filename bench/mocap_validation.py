"""Cost of a validation: simulated mocap, comparison, recording (one core).

Prints medians over repeats and writes ``bench/mocap_validation.json`` (not named ``validation.py``:
it would shadow the package). The baseline is the plant's kinematics alone (``Plant.site_positions``
for the markers and tool), measured in the same process: the cluster fit and the registration should
stay a small multiple of it.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.correction import load_robot, perturb  # noqa: E402
from spherecal.validation.mocap import SimulatedMocap, random_mocap_transform  # noqa: E402
from spherecal.validation.pipeline import validate_models  # noqa: E402


def main() -> None:
    from spherecal.validation.viewer.recording import Recording

    panda = load_robot("panda")
    rng = np.random.default_rng(0)
    truth = perturb(panda, rng)
    count = 5000
    q = panda.random_configurations(count, rng)
    mocap = SimulatedMocap(truth, random_mocap_transform(rng))
    mocap.plant_points(q[:1])  # build the plant once
    folder = Path(tempfile.mkdtemp())

    def record():
        report = validate_models(panda, truth, np.random.default_rng(1), truth=truth, configurations=count)
        recording = Recording(folder / "bench.rrd")
        from spherecal.validation.pipeline import record_validation

        record_validation(recording, report, {"nominal": panda, "calibrated": truth})
        recording.close()

    cases = {
        "plant kinematics (baseline)": lambda: mocap.plant_points(q),
        "mocap measure (plant + noise + cluster fit)": lambda: mocap.measure(q, np.random.default_rng(2)),
        "validate_models (build plant, measure, compare)": lambda: validate_models(
            panda, truth, np.random.default_rng(1), truth=truth, configurations=count
        ),
        "validate + record .rrd": record,
    }
    results = {name: {"median_s": bench_common.median_time(function)} for name, function in cases.items()}
    base = results["plant kinematics (baseline)"]["median_s"]
    print(f"{count} configurations, median of 5, one thread")
    for name, r in results.items():
        print(f"  {name:50s} {r['median_s'] * 1e3:8.1f} ms  ({r['median_s'] / base:5.1f} x baseline)")
    out = Path(__file__).with_suffix(".json")
    bench_common.write_json(out, {"configurations": count, "results": results}, seed=0)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
