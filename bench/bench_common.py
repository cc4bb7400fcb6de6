"""Shared by the bench scripts; import it first.

One BLAS thread, as the command-line tools use, and no Rerun analytics.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
os.environ.setdefault("RERUN_ANALYTICS", "0")


def median_time(function, repeats: int = 9) -> float:
    """Median wall time [s] of ``function()`` over ``repeats`` runs, after one warm-up run."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return sorted(times)[len(times) // 2]


def write_json(path: str | os.PathLike, results: dict, seed: int | None = None, inputs: dict[str, Any] | None = None,
               indent: int = 2) -> Path:
    """Write ``results`` as JSON under the provenance block every spherecal output carries (command,
    time, versions, ``seed``, ``inputs`` with the digests of file inputs given as paths)."""
    from spherecal.correction.files.provenance import provenance

    path = Path(path)
    path.write_text(json.dumps({"provenance": provenance(seed, inputs or {}), **results}, indent=indent) + "\n")
    return path


def run_cli(argv: list[str]) -> str:
    """Run ``spherecal argv`` in this process and return what it printed; stop the script if it fails."""
    import contextlib
    import io

    from spherecal.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"failed ({code}): spherecal {' '.join(argv)}\n{out.getvalue()}")
    return out.getvalue()


# ----------------------------------------------------------------------------- MUKCa real data
def socket_mae(model, sockets) -> float:
    """MUKCa's test MAE [m]: the mean over ``sockets`` ((K, n) joint angles each) of the mean distance of
    ``model``'s tool points from their mean (:func:`points_mae`)."""
    from spherecal.correction import tool_point

    return points_mae(tool_point(model, q) for q in sockets)


def points_mae(points) -> float:
    """:func:`socket_mae`'s formula on tool points already computed (another tool's): the mean over sockets ((K, 3)
    each [m]) of the mean distance from their mean [m]."""
    import numpy as np

    return float(np.mean([np.linalg.norm(p - p.mean(axis=0), axis=1).mean() for p in map(np.asarray, points)]))


def find_mukca() -> Path:
    """``shared/data/mukca`` beside this checkout or one of its parents (the full recordings)."""
    for base in Path(__file__).resolve().parents:
        if (base / "shared" / "data" / "mukca" / "data").is_dir():
            return base / "shared" / "data" / "mukca"
    return Path("../shared/data/mukca")


#: MUKCa robot folders by arm family (name prefix): (MUKCa's URDF under ``urdf/``, our robot file to the ball or
#: None for the URDF itself). MUKCa's repository holds panda_1 ... panda_6, dinova_1/2 and kuka_14.
MUKCA_FAMILIES = {
    "panda": ("panda.urdf", "tests/data/mukca/panda_ball.yaml"),
    "dinova": ("gen3lite.urdf", None),
    "kuka": ("iiwa14.urdf", None),
}
#: The robots of ``shared/data/mukca``.
MUKCA_SHARED = ("panda_2_clean", "panda_4_clean", "dinova_1")


def mukca_family(robot: str) -> str:
    """The family key of ``MUKCA_FAMILIES`` a MUKCa robot folder belongs to (by its name's prefix)."""
    for prefix in MUKCA_FAMILIES:
        if robot.startswith(prefix):
            return prefix
    raise SystemExit(f"{robot}: unknown arm family (a name starting with one of {sorted(MUKCA_FAMILIES)})")


def mukca_nominal(root: Path, robot: str):
    """The nominal model of a MUKCa robot folder to its ball: our robot file, or MUKCa's URDF to ``ball_link``."""
    from spherecal.correction import load_robot

    urdf, robot_file = MUKCA_FAMILIES[mukca_family(robot)]
    if robot_file is None:
        return load_robot(Path(root) / "urdf" / urdf, tip_link="ball_link")
    return load_robot(Path(__file__).resolve().parents[1] / robot_file)


def mukca_panda():
    """The embedded nominal Panda (with its inertials) and its tool point at MUKCa's ball centre, taken from
    ``tests/data/mukca/panda_ball.yaml`` (the fixed joints of MUKCa's ``panda.urdf`` after ``panda_link7``)."""
    from dataclasses import replace

    from spherecal.correction import load_robot

    ball = load_robot(Path(__file__).resolve().parents[1] / "tests" / "data" / "mukca" / "panda_ball.yaml")
    return replace(load_robot("panda"), tool=ball.tool)


def mukca_dataset(root: Path, robot: str, model, chosen: list[str] | None = None):
    """(Dataset, FixtureSpec) of the placements ``chosen`` (all when None) of ``robot`` under ``root``,
    read by the importer: fixtures ``<placement>_h<k>``, each placement's two sockets 50 mm apart."""
    from dataclasses import replace

    import numpy as np

    from spherecal.correction import Dataset
    from spherecal.identification.ingest.importers import read_mukca

    recording, spec = read_mukca(Path(root) / "data" / robot, model)
    keep = np.ones(len(recording.labels), dtype=bool)
    names = spec.names
    if chosen is not None:
        names = tuple(n for n in spec.names if n.rpartition("_h")[0] in chosen)
        keep = np.isin(recording.labels, names)
    dataset = Dataset(labels=recording.labels[keep], q=recording.q[keep], fixture_names=names, source=robot)
    spec = replace(spec, names=names, distances=[d for d in spec.distances if d[0] in names and d[1] in names])
    return dataset, spec
