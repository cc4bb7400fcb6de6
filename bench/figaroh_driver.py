"""FIGAROH's geometric calibration on ball-in-socket recordings; run in FIGAROH's own venv by ``figaroh_mukca.py``.

Not part of spherecal and imports nothing of it: FIGAROH (``pip install figaroh``, Apache-2.0, with ``pin``) is
not a dependency. Used as FIGAROH's examples use it (``figaroh-examples/examples/ur10``): a unified config file, a
``BaseCalibration`` subclass whose cost is the SE3 log-map residual weighed by ``apply_measurement_weighting``,
``known_baseframe = known_tipframe = False`` set after construction, then ``initialize()`` (data, the structural
base parameters by QR of the random-posture regressor, the frame-absorbed ones dropped on the data) and ``solve()``
(Levenberg-Marquardt from the closed-form frame guess, samples beyond ``outlier_threshold`` excluded and refitted).

Ball-in-socket data as FIGAROH's position measurements: each socket's known centre in a world frame (the plate's:
socket 0 at the origin, socket 1 at (0.05, 0, 0)) is the measured position of the one marker, the ball centre
(position only, ``measurable_dof`` x, y, z), for every row recorded at that socket. The base frame (world to the
arm) and the marker's offset from ``tool_frame`` are estimated.

    python figaroh_driver.py JOB.json OUT.json

JOB: {"urdf", "tip_link", "train": [{"q": (K, n) [rad], "centre": (3,) [m]}, ...], "test": [(K, n) [rad], ...],
"variants": {name: overrides of FIGAROH's ``tasks.calibration.parameters``, e.g. {"estimation": {"method": "map"}}}
(default: one, ``default``, FIGAROH's defaults), "repeats": runs per variant (an int, or {variant: int})}.
OUT: packages (the versions in FIGAROH's venv), and per variant the parameter names and values, the fit's status and
figures, the wall time [s] of each run (``initialize`` and ``solve`` apart), and the calibrated and nominal tool
points at every test socket [m].
"""

from __future__ import annotations

import contextlib
import json
import logging
import re
import sys
import tempfile
import time
import warnings
from importlib.metadata import version
from pathlib import Path

import numpy as np

warnings.simplefilter("ignore")  # pinocchio / ndcurves converter warnings at import
logging.disable(logging.WARNING)

import yaml  # noqa: E402
from figaroh.calibration.base_calibration import BaseCalibration  # noqa: E402
from figaroh.calibration.calibration_tools import calc_updated_fkm  # noqa: E402
from figaroh.tools.load_robot import load_robot  # noqa: E402

MESH = re.compile(r"<(visual|collision)\b.*?</\1>", re.S)


class SocketCalibration(BaseCalibration):
    """FIGAROH's calibration with the cost of its examples (UR10, TIAGo): log-map residuals, measurement weights."""

    def cost_function(self, var: np.ndarray) -> np.ndarray:
        estimated = calc_updated_fkm(self.model, self.data, var, self.q_measured, self.calib_config)
        residuals = self._compute_logmap_residuals(self.PEE_measured, estimated)
        return self.apply_measurement_weighting(residuals, pos_weight=1.0, orient_weight=0.5)


def kinematic_urdf(urdf: Path, work: Path) -> Path:
    """``urdf`` without its visual and collision elements (MUKCa ships no meshes; kinematics unchanged)."""
    out = work / urdf.name
    out.write_text(MESH.sub("", urdf.read_text()))
    return out


def write_inputs(robot, job: dict, parameters: dict, work: Path) -> Path:
    """FIGAROH's CSV (x1, y1, z1, one column per active joint) and its unified config; returns the config."""
    tip = job["tip_link"]
    frame = robot.model.getFrameId(tip)
    supports = [j for j in robot.model.supports[robot.model.frames[frame].parentJoint].tolist() if j > 0]
    joints = [robot.model.names[j] for j in supports]
    rows = [[*sock["centre"], *q] for sock in job["train"] for q in sock["q"]]
    if any(len(r) != 3 + len(joints) for r in rows):
        raise SystemExit(f"train: {len(joints)} joint angles per row expected ({joints})")
    csv = work / "train.csv"
    np.savetxt(csv, np.array(rows), delimiter=",", header=",".join(["x1", "y1", "z1", *joints]), comments="")
    config = {"tasks": {"calibration": {
        "enabled": True,
        "parameters": {"calibration_level": "full_params", "include_non_geometric": False,
                       **parameters},
        "kinematics": {"base_frame": "universe", "tool_frame": tip},
        "measurements": {"markers": [{"name": "ball", "measurable_dof": [True, True, True, False, False, False]}]},
        "data": {"source_file": str(csv), "number_of_samples": len(rows)},
    }}}
    path = work / "socket_config.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def calibrate(robot, config: Path) -> tuple[SocketCalibration, float, float]:
    """One calibration as FIGAROH's examples run it; (calibrator, initialize [s], solve [s])."""
    start = time.perf_counter()
    calib = SocketCalibration(robot, str(config))
    calib.calib_config["known_baseframe"] = False
    calib.calib_config["known_tipframe"] = False
    calib.initialize()
    middle = time.perf_counter()
    with contextlib.redirect_stdout(sys.stderr):  # its quality report
        calib.solve(enable_logging=False)
    return calib, middle - start, time.perf_counter() - middle


def tool_points(calib: SocketCalibration, var: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(K, 3) marker positions [m] in FIGAROH's world frame of (K, n) active-joint angles."""
    cfg = dict(calib.calib_config, NbSample=len(q))
    full = np.tile(np.asarray(cfg["q0"], dtype=float), (len(q), 1))
    full[:, cfg["config_idx"]] = q
    return calc_updated_fkm(calib.model, calib.data, np.asarray(var, dtype=float), full, cfg).reshape(3, -1).T


def fitted(calib: SocketCalibration, runs: list, tests: list[np.ndarray]) -> dict:
    """What one variant's last run found, its times, and its tool points at the test sockets."""
    x = np.asarray(calib.LM_result.x)
    metrics = calib.evaluation_metrics
    return {
        "status": calib.STATUS,
        "message": str(calib.LM_result.message),
        "nfev": int(calib.LM_result.nfev),
        "param_name": list(calib.calib_config["param_name"]),
        "x": x.tolist(),
        "std": [float(s) for s in calib.std_dev],
        "absorbed": list(calib.calib_config.get("absorbed_param_name", [])),
        "excluded_samples": [int(i) for i in metrics.get("excluded_samples", [])],
        "train_rmse_m": float(metrics["rmse"]),
        "condition_number": float(metrics["condition_number"]),
        "samples": int(calib.calib_config["NbSample"]),
        "initialize_s": [r[1] for r in runs],
        "solve_s": [r[2] for r in runs],
        "test_points": [tool_points(calib, x, q).tolist() for q in tests],
        "nominal_test_points": [tool_points(calib, np.zeros_like(x), q).tolist() for q in tests],
    }


def main() -> int:
    job = json.loads(Path(sys.argv[1]).read_text())
    tests = [np.asarray(q, dtype=float) for q in job["test"]]
    # FIGAROH's venv has no spherecal (no provenance()): its own packages, which figaroh_mukca.py records beside its
    # provenance block as figaroh_versions
    out: dict = {"packages": {name: version(name) for name in ("figaroh", "pin", "numpy", "scipy")}, "variants": {}}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        robot = load_robot(str(kinematic_urdf(Path(job["urdf"]), work)), load_by_urdf=True)
        for name, parameters in job.get("variants", {"default": {}}).items():
            config = write_inputs(robot, job, parameters, work)
            repeats = job.get("repeats", 1)
            repeats = repeats.get(name, 1) if isinstance(repeats, dict) else repeats
            runs = [calibrate(robot, config) for _ in range(max(1, int(repeats)))]
            out["variants"][name] = fitted(runs[-1][0], runs, tests)
    Path(sys.argv[2]).write_text(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
