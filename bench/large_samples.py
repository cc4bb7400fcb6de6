"""Large recordings: reading a 2 M-row ``samples.csv`` (30 minutes at 1 kHz is 1.8 M rows).

Writes a file of ``--rows`` rows (``fixture,t,q1..q7``, every digit of each float, as ``spherecal
simulate`` writes them) into a temporary folder, then in a fresh subprocess per case reads it with
``correction.samples_csv.read_samples`` and reports the wall time and the peak resident memory
(``resource.getrusage(RUSAGE_SELF).ru_maxrss``, the whole process: Python, numpy and the data) and
the CPU time of the reading (user + system; on a shared machine the wall time is this divided by the
share of a core the process got):

- ``read``: the whole file;
- ``bad row 2``: the same file with a bad value on row 2 (must fail at once, not after reading all);
- ``baseline``: the subprocess importing the reader and loading the robot, reading nothing;
- ``import csv``: the same file through ``identification.importers.read_joint_csv`` (``spherecal
  import --format csv``).

Prints a table, the machine load (``uptime``) and writes ``bench/large_samples.json``. Targets: 2 M
rows in <= 15 s and <= 1 GB peak.

    .venv/bin/python bench/large_samples.py [--rows 2000000] [--reader-root /path/to/another/tree]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # one BLAS thread
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CHILD = r"""
import json, resource, sys, time
sys.path.insert(0, {root!r})
from spherecal.correction import load_robot
from spherecal.correction.files.samples_csv import read_samples
from spherecal.correction.files.samples import DatasetError  # RecordingError is one
model = load_robot("panda")
if {importer!r}:  # `spherecal import --format csv` reads the same file as a joint recording
    from spherecal.identification.ingest.importers import read_joint_csv as read_samples
usage0 = resource.getrusage(resource.RUSAGE_SELF)
cpu0 = usage0.ru_utime + usage0.ru_stime
clock = time.perf_counter()
outcome = "skipped"
if {path!r}:
    try:
        dataset = read_samples({path!r}, model)
        outcome = f"{{len(dataset.q)}} samples"
    except DatasetError as error:
        outcome = f"error: {{error}}"[:160]
seconds = time.perf_counter() - clock
usage = resource.getrusage(resource.RUSAGE_SELF)
peak_mb = usage.ru_maxrss / 1024
print(json.dumps({{"seconds": seconds, "cpu_seconds": usage.ru_utime + usage.ru_stime - cpu0, "peak_mb": peak_mb,
                  "outcome": outcome}}))
"""


def write_file(path: Path, rows: int, seed: int = 0) -> None:
    """``rows`` samples of the Panda at 4 fixtures, every float written with all its digits."""
    rng = np.random.default_rng(seed)
    lower = np.array([-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973])
    upper = -lower
    upper[3], upper[5] = -0.0698, 3.7525
    with open(path, "w") as handle:
        handle.write("fixture,t," + ",".join(f"q{i + 1}" for i in range(7)) + "\n")
        block = 200_000
        for first in range(0, rows, block):
            count = min(block, rows - first)
            q = rng.uniform(lower, upper, size=(count, 7))
            t = (first + np.arange(count)) * 1e-3
            names = np.array(["P1", "P2", "P3", "P4"])[(first + np.arange(count)) * 4 // rows]
            lines = [f"{name},{tt!r},{','.join(map(repr, row))}\n" for name, tt, row in zip(
                names.tolist(), t.tolist(), q.tolist(), strict=True)]
            handle.writelines(lines)


def measure(path: str, root: str, importer: bool = False) -> dict:
    """Run one reading in a fresh interpreter; its JSON line."""
    start = time.perf_counter()
    code = CHILD.format(root=root, path=path, importer=importer)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result["process_seconds"] = time.perf_counter() - start
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=2_000_000)
    parser.add_argument("--reader-root", default=str(ROOT),
                        help="source tree whose reader is measured (default: this one)")
    parser.add_argument("--out", default=str(HERE / "large_samples.json"))
    parser.add_argument("--no-import", action="store_true", help="skip the `import --format csv` reader")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "samples.csv"
        clock = time.perf_counter()
        write_file(path, args.rows)
        written = time.perf_counter() - clock
        size_mb = path.stat().st_size / 1e6
        bad = Path(folder) / "bad.csv"
        with open(path) as source, open(bad, "w") as target:
            target.write(source.readline())
            target.write("P1,0.0,0.1,oops,0.1,-1.0,0.1,1.0,0.1\n")
            source.readline()
            for line in source:
                target.write(line)
        cases = {"baseline": "", "read": str(path), "bad row 2": str(bad)}
        results = {name: measure(file, args.reader_root) for name, file in cases.items()}
        if not args.no_import:
            results["import csv"] = measure(str(path), args.reader_root, importer=True)
    load = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"file: {args.rows} rows, {size_mb:.0f} MB (written in {written:.1f} s); reader: {args.reader_root}")
    print(f"{'case':<10} {'wall [s]':>9} {'CPU [s]':>8} {'peak RSS [MB]':>14}  outcome")
    for name, r in results.items():
        print(f"{name:<10} {r['seconds']:9.2f} {r['cpu_seconds']:8.2f} {r['peak_mb']:14.0f}  {r['outcome']}")
    print(f"load: {load}")
    report = {"rows": args.rows, "file_mb": round(size_mb, 1), "reader_root": args.reader_root, "uptime": load,
              "cases": results, "targets": {"seconds": 15, "peak_mb": 1000}}
    bench_common.write_json(args.out, report, seed=0, inputs={"rows": args.rows, "reader_root": args.reader_root})
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()
