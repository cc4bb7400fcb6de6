"""Tasks over executors: this process, the built-in pool and a 2-worker Dask LocalCluster give the
same results (a tiny real campaign and a plan, bit for bit); failures are reported and the others
kept; workers run capped to one BLAS thread and report their versions."""

from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from spherecal.correction.files.provenance import versions
from spherecal.validation.experiments.campaign import CampaignConfig, TaskResult, run_campaign, tasks
from spherecal.validation.parallel import SchedulerError, TaskFailedWarning, executor, run_tasks
from spherecal.validation.planning.candidates import grid_candidates
from spherecal.validation.planning.plan import plan, survey
from spherecal.validation.threads import VARIABLES, blas_threads

#: A tiny real campaign: two rows, one noise-free set each (~1 s a task).
TINY = CampaignConfig(sets=1, samples=60, configurations=100, fixture_sets=("P1", "Pall"), noise_levels=(0.0,))
#: Four candidates the Panda reaches (a 2 x 2 x 1 grid).
GRID = "0.4,0.55,2;-0.2,0.2,2;0.45,0.45,1"


def _square(x: int) -> int:
    if x == 3:
        raise ValueError("three is\nnot welcome")  # a two-line message: reported on one line
    return x * x


def _threads(_: int) -> dict[str, int]:
    return blas_threads()


def _malloc_trim(_: int) -> str | None:
    import os

    return os.environ.get("MALLOC_TRIM_THRESHOLD_")


def _failing_task(task) -> TaskResult:
    """A stand-in for a calibration (errors from the task's own seed) that crashes on Pall."""
    if task.row == "Pall":
        raise RuntimeError("solver exploded")
    mean = np.random.default_rng(task.seed).uniform(1e-5, 1e-4)
    return TaskResult(task.row, task.index, mean, 3 * mean, mean, 5e-3, 0.0)


def _without_time(results):
    return [dataclasses.replace(r, seconds=0.0) for r in results]  # wall time per task is not a result


@pytest.fixture(scope="module")
def dask():
    """A 2-worker LocalCluster (processes, 127.0.0.1), closed at the end of the module."""
    pytest.importorskip("distributed")
    with executor(2, "local") as dask_executor:
        yield dask_executor


@pytest.mark.parametrize("workers", [1, 2])
def test_results_keep_task_order_and_one_failure_is_reported_not_fatal(workers) -> None:
    done = []
    with executor(workers) as pool, pytest.warns(TaskFailedWarning, match="task three failed: ValueError: three is"):
        outcome = run_tasks(_square, [1, 2, 3, 4], pool, ["one", "two", "three", "four"], lambda: done.append(1))
    assert outcome.results == [1, 4, None, 16] and len(done) == 4
    assert [(f.name, f.error) for f in outcome.failures] == [("three", "ValueError: three is not welcome")]
    assert 1 <= len(outcome.workers) <= workers and all(v == versions() for v in outcome.workers.values())


def test_pool_workers_run_on_one_blas_thread(monkeypatch) -> None:
    for variable in VARIABLES:
        monkeypatch.delenv(variable, raising=False)
    with threadpool_limits(limits=2), executor(2) as pool:  # forked from a process with 2 BLAS threads each
        outcome = run_tasks(_threads, [0, 1, 2, 3], pool)
    assert all(set(seen.values()) == {1} for seen in outcome.results)


def test_a_scheduler_without_dask_is_refused_in_one_line(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if the extra were not installed
    with pytest.raises(SchedulerError, match=r"pip install 'spherecal\[dask\]'"), executor(2, "local"):
        pass


def test_tiny_campaign_on_dask_is_the_pools_bit_for_bit(dask) -> None:
    pool = run_campaign(TINY, workers=2, progress=False)
    on_dask = run_campaign(TINY, progress=False, executor=dask)
    assert len(pool.results) == len(tasks(TINY)) == 2 and not pool.failures and not on_dask.failures
    assert _without_time(on_dask.results) == _without_time(pool.results)
    assert pool.results[1].mean < 1e-5 < pool.results[0].mean  # Pall noise-free: micrometres; P1: not
    assert len(on_dask.workers) == 2 and all(v == versions() for v in on_dask.workers.values())


def test_a_failed_task_on_dask_is_reported_and_the_others_kept(dask) -> None:
    with pytest.warns(TaskFailedWarning, match="task Pall set 0 failed: RuntimeError: solver exploded"):
        run = run_campaign(TINY, progress=False, executor=dask, runner=_failing_task)
    assert [r.row for r in run.results] == ["P1"] and [f.name for f in run.failures] == ["Pall set 0"]
    assert run.results == [_failing_task(tasks(TINY)[0])]


def test_dask_workers_run_on_one_blas_thread(dask) -> None:
    outcome = run_tasks(_threads, [0, 1, 2, 3], dask)
    assert all(seen and set(seen.values()) == {1} for seen in outcome.results)


def test_plan_is_the_same_in_the_pool_and_on_dask(panda, dask) -> None:
    candidates = grid_candidates(GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("error", TaskFailedWarning)
        with executor(2) as pool:
            pooled = plan(panda, candidates, 2, 7, samples=300, executor=pool)
        on_dask = plan(panda, candidates, 2, 7, samples=300, executor=dask)
    assert pooled.best is not None and sum(s.reachable for s in pooled.surveys) >= 2
    assert on_dask.best.names == pooled.best.names and on_dask.best.distances == pooled.best.distances
    assert on_dask.best.prediction.mean == pooled.best.prediction.mean
    for a, b in zip(pooled.surveys, on_dask.surveys, strict=True):
        assert a.reason == b.reason and np.array_equal(a.q, b.q)
    assert len(on_dask.workers) >= 1 and len(pooled.workers) >= 1


def test_each_candidate_has_its_own_seed(panda) -> None:
    """A candidate's samples depend on the plan's seed and its name, not on the others nor on where
    they run."""
    candidates = grid_candidates(GRID)
    whole = survey(panda, candidates, 7)
    alone = survey(panda, candidates[2:3], 7)
    with executor(2) as pool:
        reversed_order = survey(panda, candidates[::-1], 7, executor=pool)
    assert whole[2].reachable and np.array_equal(whole[2].q, alone[0].q)
    assert all(np.array_equal(a.q, b.q) for a, b in zip(whole, reversed_order[::-1], strict=True))
    assert not np.array_equal(alone[0].q, survey(panda, candidates[2:3], 8)[0].q)


def test_campaign_command_without_dask_says_so_in_one_line_and_writes_nothing(tmp_path, monkeypatch, capsys) -> None:
    from spherecal.cli import main

    monkeypatch.setitem(sys.modules, "distributed", None)
    out = tmp_path / "campaign"
    assert main(["campaign", "--sets", "1", "--rows", "P1", "--scheduler", "local", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("spherecal campaign: error: field '--scheduler': local: dask.distributed is not installed "
                       "(pip install 'spherecal[dask]')")
    assert not out.exists()


def test_the_provenance_records_the_workers_grouped_by_versions() -> None:
    from spherecal.correction.files.provenance import comment_block, provenance

    own = versions()
    old = {**own, "numpy": "1.0.0"}
    info = provenance(0, {}, ["x"], workers={"b pid 2": own, "a pid 1": own, "c pid 3": old})
    line = comment_block(info).splitlines()[-1]
    assert line.startswith("workers: a pid 1, b pid 2: the versions above; c pid 3: ")
    assert "numpy 1.0.0" in line and "workers:" not in comment_block(provenance(0, {}, ["x"]))


def test_campaign_command_records_its_pool_workers(tmp_path, capsys) -> None:
    from spherecal.cli import main

    out = tmp_path / "campaign"
    args = ["campaign", "--sets", "2", "--rows", "P1", "--noise", "0", "--per-fixture", "30", "--configurations", "50"]
    assert main([*args, "--out", str(out)]) == 0
    header = [line for line in (out / "table2.csv").read_text().splitlines() if line.startswith("# workers: ")]
    assert len(header) == 1 and header[0].endswith(": the versions above") and " pid " in header[0]
    assert "worker processes, process pool" in capsys.readouterr().out


def test_plan_analysis_on_a_scheduler_is_refused_before_anything_runs(tmp_path, capsys) -> None:
    from spherecal.cli import main

    out = tmp_path / "analysis.md"
    assert main(["plan", "--analysis", str(out), "--scheduler", "local"]) == 1
    assert capsys.readouterr().err.count("\n") == 1 and not out.exists()


def test_local_dask_workers_keep_glibcs_dynamic_mmap_threshold(dask) -> None:
    """Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 by default, which made every numpy temporary an
    mmap/munmap pair: campaign tasks 2-3x slower than in the pool, two thirds of it kernel time."""
    assert run_tasks(_malloc_trim, [0, 1], dask).results == [None, None]
