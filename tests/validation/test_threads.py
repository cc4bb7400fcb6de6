"""Thread caps: read from inside a running command (a probe subcommand) and inside a pool worker."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest
from threadpoolctl import threadpool_limits

from spherecal.validation.threads import VARIABLES, blas_threads, capped, limits

#: A subcommand that loads numpy and scipy (each wheel has its own OpenBLAS) and prints their thread counts.
PROBE = textwrap.dedent(
    """
    HELP = "print the BLAS thread counts seen from inside a command"


    def add_arguments(parser):
        pass


    def run(args):
        import json

        import numpy
        import scipy.linalg

        from spherecal.validation.threads import blas_threads

        print(json.dumps(blas_threads()))
        return 0
    """
)
#: Runs the probe through the CLI's main (``through_main``) or directly, in a fresh process.
SCRIPT = textwrap.dedent(
    """
    import sys

    import spherecal.cli as cli

    cli.COMMANDS["probe"] = "probe_command"
    if sys.argv[1] == "through_main":
        sys.exit(cli.main(["probe"]))
    import probe_command

    sys.exit(probe_command.run(None))
    """
)


def _probe(tmp_path, how: str, **env: str) -> dict[str, int]:
    (tmp_path / "probe_command.py").write_text(PROBE)
    clean = {k: v for k, v in os.environ.items() if k not in VARIABLES}
    clean["PYTHONPATH"] = os.pathsep.join([str(tmp_path), *filter(None, [os.environ.get("PYTHONPATH")])])
    done = subprocess.run([sys.executable, "-c", SCRIPT, how], env={**clean, **env}, capture_output=True,
                          text=True, timeout=120, check=True)
    return json.loads(done.stdout)


def test_a_command_runs_on_one_blas_thread_unless_the_user_set_more(tmp_path) -> None:
    uncapped = _probe(tmp_path, "directly")  # the reference: what the libraries choose on their own
    if max(uncapped.values()) <= 1:
        pytest.skip("a one-core machine: the libraries choose one thread on their own")
    capped_run = _probe(tmp_path, "through_main")
    assert len(capped_run) >= 2 and set(capped_run.values()) == {1}  # numpy's and scipy's OpenBLAS (+ OpenMP)
    user = _probe(tmp_path, "through_main", OPENBLAS_NUM_THREADS="2")
    assert {n for lib, n in user.items() if "openblas" in lib} == {2}


def test_main_caps_libraries_loaded_before_it_ran(tmp_path, monkeypatch) -> None:
    """In-process (a script calling main after numpy loaded): threadpoolctl limits what is loaded."""
    import spherecal.cli as cli

    (tmp_path / "probe_command.py").write_text(PROBE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(cli.COMMANDS, "probe", "probe_command")
    for variable in VARIABLES:
        monkeypatch.delenv(variable, raising=False)
    with threadpool_limits(limits=2):
        assert max(blas_threads().values()) == 2  # the reference, before
        cli_output = _run_main(cli)
        assert max(blas_threads().values()) == 2  # restored after the command
    assert set(json.loads(cli_output).values()) == {1}


def _run_main(cli) -> str:
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        assert cli.main(["probe"]) == 0
    return buffer.getvalue()


def _threads_in_worker(_: int) -> dict[str, int]:
    return blas_threads()


def test_a_pool_worker_forked_from_a_two_thread_process_runs_capped(monkeypatch) -> None:
    from concurrent.futures import ProcessPoolExecutor

    for variable in VARIABLES:
        monkeypatch.delenv(variable, raising=False)

    with threadpool_limits(limits=2), ProcessPoolExecutor(max_workers=1) as pool:
        inherited = pool.submit(_threads_in_worker, 0).result()
        inside = pool.submit(capped, _threads_in_worker, 0).result()
    assert max(inherited.values()) == 2  # the reference: a forked worker inherits its parent's pools
    assert set(inside.values()) == {1}


def test_limits_follow_the_users_variables() -> None:
    assert limits({}) == {"openblas": 1, "mkl": 1, "blis": 1, "openmp": 1}
    user = {"OPENBLAS_NUM_THREADS": "3", "OMP_NUM_THREADS": "4,2", "MKL_NUM_THREADS": "x", "BLIS_NUM_THREADS": "0"}
    got = limits(user)
    assert got == {"openblas": 3, "mkl": 1, "blis": 1, "openmp": 4}
