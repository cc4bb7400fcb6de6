"""Throughput of the batched tool point and parameter Jacobian (one core), and the cost of an elastic model.

Prints medians over repeats and writes ``bench/kinematics.json``. Targets (issue 3):
>= 1 000 000 tool points / s and >= 100 000 parameter-Jacobian rows-of-3 / s, batch 100 000.

Elastic part: gravity torques and the tool point of an elastic, scaled Panda (3e4 Nm/rad, scales 1e-3), one
configuration (a controller's period) and a batch of 500, against :func:`gravity_torques_before` (the implementation
on world frames that ``correction.gravity`` had before, kept here as the baseline: the "before" tool point is today's
with that function in ``correction.elastic``), measured in the same process; the largest difference between the two
is printed beside.
"""

from __future__ import annotations

import os
import platform
from contextlib import contextmanager
from pathlib import Path

import bench_common  # first: import path, BLAS threads
import numpy as np  # noqa: E402

from spherecal.correction import elastic, joint_jacobian, load_robot, param_jacobian, tool_point  # noqa: E402
from spherecal.correction.chain import as_batch, frames  # noqa: E402
from spherecal.correction.gravity import GRAVITY, gravity_torques, inertials_of  # noqa: E402
from spherecal.correction.scale import with_scale  # noqa: E402

#: Calls timed for one configuration, and for a batch of ELASTIC_BATCH (the median per call of each).
SINGLE_REPEATS, BATCH_REPEATS, ELASTIC_BATCH = 2001, 201, 500


def gravity_torques_before(model, q, masses=None, coms=None, g=GRAVITY):
    """``correction.gravity.gravity_torques`` as it was before the joint-frame recursion (the baseline): every world
    frame from ``chain.frames``, then the centres of mass, first moments and axes as (N, n+1, 3) arrays."""
    if masses is None or coms is None:
        masses, coms = inertials_of(model)
    q, single = as_batch(model, q)
    f = frames(model, q)
    rotations = np.stack([f.x, f.y, f.z], axis=-1).transpose(2, 0, 1, 3)
    origins = f.origin.transpose(2, 0, 1)
    n = model.n_joints
    rot, origin = rotations[:, 1:], origins[:, 1:]
    body_frame = np.minimum(np.arange(n + 1), n - 1)
    centres = np.einsum("nbij,bj->nbi", rot[:, body_frame], coms) + origin[:, body_frame]
    weighted = masses[None, :, None] * centres
    first_moment = np.cumsum(weighted[:, ::-1], axis=1)[:, ::-1][:, :n]
    carried = np.cumsum(masses[::-1])[::-1][:n]
    if model.convention == "modified":
        axis, point = rot[:, :, :, 2], origin
    else:
        axis, point = rotations[:, :-1, :, 2], origins[:, :-1]
    lever = first_moment - carried[None, :, None] * point
    tau = -np.einsum("nij,j->ni", np.cross(axis, lever), np.asarray(g, dtype=float))
    return tau[0] if single else tau


@contextmanager
def gravity_before():
    """``correction.elastic`` (the tool point's link angles) on :func:`gravity_torques_before` for the block."""
    elastic.gravity_torques = gravity_torques_before
    try:
        yield
    finally:
        elastic.gravity_torques = gravity_torques


def _timed(call, model, one: np.ndarray, batch: np.ndarray) -> dict:
    """Median seconds per call of ``call(model, one)`` and ``call(model, batch)``, and the batch's values."""
    return {"single_s": bench_common.median_time(lambda: call(model, one), SINGLE_REPEATS),
            "batch_s": bench_common.median_time(lambda: call(model, batch), BATCH_REPEATS),
            "values": call(model, batch)}


def elastic_figures() -> dict:
    """Median seconds per call, before and after, of the elastic Panda's torques and tool point (one and a batch)."""
    model = with_scale(elastic.with_stiffness(load_robot("panda"), [3e4] * 7), [1e-3] * 7)
    rng = np.random.default_rng(1)
    one, batch = model.random_configurations(1, rng)[0], model.random_configurations(ELASTIC_BATCH, rng)
    rigid = _timed(tool_point, load_robot("panda"), one, batch)
    with gravity_before():
        before = {"gravity_torques": _timed(gravity_torques_before, model, one, batch),
                  "elastic tool_point": _timed(tool_point, model, one, batch)}
    after = {"gravity_torques": _timed(gravity_torques, model, one, batch),
             "elastic tool_point": _timed(tool_point, model, one, batch)}
    out = {"rigid tool_point": {"single_s": rigid["single_s"], "batch_s": rigid["batch_s"]}}
    for name in before:
        out[name] = {"before_single_s": before[name]["single_s"], "after_single_s": after[name]["single_s"],
                     "before_batch_s": before[name]["batch_s"], "after_batch_s": after[name]["batch_s"],
                     "max_difference": float(np.abs(before[name]["values"] - after[name]["values"]).max())}
    return out


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
    load = os.getloadavg()
    elastic_results = elastic_figures()
    print(f"elastic Panda (3e4 Nm/rad, scales 1e-3): median per call, one configuration ({SINGLE_REPEATS} calls) "
          f"and a batch of {ELASTIC_BATCH} ({BATCH_REPEATS} calls); load average {load[0]:.2f} {load[1]:.2f} "
          f"{load[2]:.2f}")
    rigid = elastic_results["rigid tool_point"]
    print(f"  {'rigid tool_point (reference)':30s} {rigid['single_s'] * 1e3:7.3f} ms {rigid['batch_s'] * 1e3:7.3f} ms")
    for name in ("gravity_torques", "elastic tool_point"):
        r = elastic_results[name]
        print(f"  {name:30s} one: {r['before_single_s'] * 1e3:7.3f} -> {r['after_single_s'] * 1e3:7.3f} ms "
              f"({r['before_single_s'] / r['after_single_s']:4.1f} x)   {ELASTIC_BATCH}: "
              f"{r['before_batch_s'] * 1e3:7.3f} -> {r['after_batch_s'] * 1e3:7.3f} ms "
              f"({r['before_batch_s'] / r['after_batch_s']:4.1f} x)   largest difference {r['max_difference']:.2g}")
    out = Path(__file__).with_suffix(".json")
    bench_common.write_json(out, {"batch": batch, "results": results, "elastic": elastic_results,
                                  "load_average": load}, seed=0)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
