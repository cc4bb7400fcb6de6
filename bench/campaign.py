"""Campaign throughput: 1 -> 2 workers, and Dask against the built-in process pool on the same tasks.

Runs the same small campaign (real tasks: simulate, calibrate, validate) in this process (the
baseline, ``--workers 1``), on the built-in pool of 2 processes (what ``spherecal campaign`` does,
pool start-up included) and on a running 2-worker Dask LocalCluster (processes, 127.0.0.1; started
once, its start-up reported apart), interleaved, ``--repeats`` times; prints medians and ratios
against the in-process run of the same repeat, the load (``uptime``) before and after, and checks
that every run gives the same results bit for bit. Then the bare per-task overhead of each executor
on no-op tasks. Writes ``bench/campaign.json``.

Goals (issue 23): 1 -> 2 workers >= 1.7x; Dask overhead <= 5 % of a campaign task.

    .venv/bin/python bench/campaign.py [--repeats 5] [--sets 2] [--samples 300] [--configurations 2000]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import subprocess
import time
from pathlib import Path

import bench_common  # noqa: F401  first: BLAS threads, no Rerun analytics

from spherecal.validation.experiments.campaign import CampaignConfig, run_campaign, tasks  # noqa: E402
from spherecal.validation.parallel import executor, run_tasks  # noqa: E402


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def _cpu() -> float:
    """CPU seconds of this process and of its children that have ended (a pool's, after its shutdown)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _makespan(seconds: list[float], workers: int) -> float:
    """Wall time of tasks of these durations taken in order by ``workers`` free workers (each takes the
    next task when it is done, as the executors do)."""
    free = [0.0] * workers
    for duration in seconds:
        free[free.index(min(free))] += duration
    return max(free)


def _noop(x: int) -> int:
    return x


def _noop_overhead(where, count: int) -> float:
    """Median over 3 runs of the wall time per no-op task [s] (thread cap and worker record included)."""
    run_tasks(_noop, [0, 1], where)  # the workers started
    times = []
    for _ in range(3):
        clock = time.perf_counter()
        run_tasks(_noop, list(range(count)), where)
        times.append(time.perf_counter() - clock)
    return statistics.median(times) / count


def _key(results) -> list:
    """The results without their wall time (what must be the same wherever the tasks ran)."""
    return [dataclasses.replace(r, seconds=0.0) for r in results]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--sets", type=int, default=2)
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--configurations", type=int, default=2000)
    parser.add_argument("--noop", type=int, default=200, help="no-op tasks for the bare overhead")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    config = CampaignConfig(sets=args.sets, samples=args.samples, configurations=args.configurations,
                            fixture_sets=("P1", "Pall"), seed=args.seed)
    n_tasks = len(tasks(config))
    before = _uptime()
    print(f"load before: {before}")
    print(f"{n_tasks} tasks (rows P1, Pall x noise 0, 0.3 mm; {args.sets} sets, {args.samples} samples per fixture, "
          f"{args.configurations} validation configurations), {args.repeats} repeats, interleaved")

    clock = time.perf_counter()
    with executor(2, "local") as dask:
        dask_start = time.perf_counter() - clock
        reference = _key(run_campaign(config, workers=1, progress=False).results)
        run_campaign(config, progress=False, executor=dask)  # warm-up: the workers' imports
        runs = {"1 process": [], "pool 2": [], "dask 2": []}
        cpu = {"1 process": [], "pool 2": []}  # CPU seconds of this process and its reaped children
        task_seconds: list[float] = []
        identical = True
        for _ in range(args.repeats):
            for mode in runs:
                start_cpu = _cpu()
                clock = time.perf_counter()
                if mode == "1 process":
                    run = run_campaign(config, workers=1, progress=False)
                elif mode == "pool 2":
                    run = run_campaign(config, workers=2, progress=False)
                else:
                    run = run_campaign(config, progress=False, executor=dask)
                runs[mode].append(time.perf_counter() - clock)
                if mode in cpu:
                    cpu[mode].append(_cpu() - start_cpu)
                identical &= _key(run.results) == reference and not run.failures
                if mode == "1 process":
                    task_seconds += [r.seconds for r in run.results]
        with executor(2) as pool:
            noop = {"1 process": _noop_overhead(None, args.noop), "pool 2": _noop_overhead(pool, args.noop),
                    "dask 2": _noop_overhead(dask, args.noop)}
    after = _uptime()

    median = {mode: statistics.median(t) for mode, t in runs.items()}
    speedup = {mode: statistics.median(a / b for a, b in zip(runs["1 process"], t, strict=True))
               for mode, t in runs.items()}
    task = statistics.median(task_seconds)
    # a fixed extra time d per task on each of 2 workers lengthens the run by d * tasks / 2
    dask_extra = statistics.median(d - p for d, p in zip(runs["dask 2"], runs["pool 2"], strict=True)) * 2 / n_tasks
    print(f"median task (in one process) {task:.2f} s; Dask LocalCluster start {dask_start:.1f} s (once, not below)")
    print(f"{'':10s} {'median wall [s]':>16s} {'speed-up vs 1 process':>22s}")
    for mode in runs:
        print(f"{mode:10s} {median[mode]:16.2f} {speedup[mode]:21.2f}x")
    cpu_ratio = statistics.median(a / b for a, b in zip(cpu["1 process"], cpu["pool 2"], strict=True))
    per_run = [task_seconds[i:i + n_tasks] for i in range(0, len(task_seconds), n_tasks)]
    schedule = statistics.median(sum(t) / _makespan(t, 2) for t in per_run)
    print(f"CPU time, 1 process / pool 2 (all processes): {cpu_ratio:.2f}; schedule bound of 2 workers on these "
          f"task durations: {schedule:.2f}x; model for 2 idle cores, min(2 x CPU ratio, schedule bound): "
          f"{min(2 * cpu_ratio, schedule):.2f}x (not a measurement)")
    print(f"Dask vs pool, extra per task: {dask_extra * 1e3:+.0f} ms = {dask_extra / task:+.1%} of a task "
          f"(goal <= 5 %)")
    print(f"bare overhead per no-op task ({args.noop}, median of 3): in process {noop['1 process'] * 1e3:.2f} ms, "
          f"pool {noop['pool 2'] * 1e3:.2f} ms, Dask {noop['dask 2'] * 1e3:.2f} ms = {noop['dask 2'] / task:.2%} "
          "of a task")
    print(f"results identical in every run (bit for bit, wall time aside): {identical}")
    print(f"goals: 1 -> 2 workers >= 1.7x: {'met' if speedup['pool 2'] >= 1.7 else 'MISSED'} "
          f"({speedup['pool 2']:.2f}x); Dask overhead <= 5 %: "
          f"{'met' if max(dask_extra, noop['dask 2']) <= 0.05 * task else 'MISSED'}")
    print(f"load after: {after}")
    out = bench_common.write_json(Path(__file__).with_suffix(".json"), {
        "load_before": before,
        "load_after": after, "wall_s": runs, "median_wall_s": median, "speedup_vs_one_process": speedup,
        "median_task_s": task, "cpu_s": cpu, "cpu_ratio_one_over_pool": cpu_ratio, "schedule_bound": schedule,
        "dask_start_s": dask_start, "dask_extra_per_task_s": dask_extra,
        "noop_overhead_per_task_s": noop, "identical": identical,
    }, inputs={**vars(args), "tasks": n_tasks})
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
