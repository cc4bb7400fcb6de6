"""Campaigns: task seeding, aggregation into Table 2, files, determinism over workers, refused sets."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.validation.experiments.campaign import (
    CampaignConfig,
    TaskResult,
    format_table,
    run_campaign,
    run_task,
    table,
    table_csv,
    tasks,
    write_tables,
)
from spherecal.validation.parallel import TaskFailedWarning
from tests.refusal import refused


def fake_runner(task) -> TaskResult:
    """A deterministic stand-in for a calibration: errors drawn from the task's own seed."""
    rng = np.random.default_rng(task.seed)
    mean = rng.uniform(1e-5, 1e-4) * (10 if task.noise else 1)
    return TaskResult(task.row, task.index, mean, 3 * mean, mean + 3e-4, 5e-3, 0.0)


def test_tasks_cover_every_row_and_set_with_distinct_seeds() -> None:
    config = CampaignConfig(sets=3)
    todo = tasks(config)
    assert len(todo) == 4 * 2 * 3
    assert [t.row for t in todo[::3]] == ["P1", "P2", "P3", "Pall", "P1N", "P2N", "P3N", "PallN"]
    assert len({t.seed for t in todo}) == len(todo)
    assert todo[9].fixtures == ("P1", "P2", "P3") and todo[9].noise == 0.0
    assert [t.fixture_set for t in todo[::3]] == ["P1", "P2", "P3", "Pall"] * 2  # the set --rows takes, not parsed
    # a row alone (--rows P2) reproduces that row of the full table (its seeds used to shift with the selection)
    alone = tasks(CampaignConfig(sets=3, fixture_sets=("P2",)))
    assert [t.seed for t in alone] == [t.seed for t in todo if t.row in ("P2", "P2N")]


def test_table_aggregates_mean_std_max_over_sets() -> None:
    results = [TaskResult("P1", i, m, 2 * m, 0.0, 0.0, 0.0) for i, m in enumerate([1e-4, 2e-4, 3e-4])]
    (row,) = table(results)
    assert row.sets == 3
    np.testing.assert_allclose(row.average, [2e-4, np.std([1e-4, 2e-4, 3e-4]), 3e-4])
    np.testing.assert_allclose(row.maximal, [4e-4, 2 * np.std([1e-4, 2e-4, 3e-4]), 6e-4])
    csv_text = table_csv([row], comment="seed 0")
    assert csv_text.splitlines()[0] == "# seed 0"
    assert csv_text.splitlines()[2].startswith("P1,3,0,0,0.200,0.082,0.300,0.400,0.163,0.600")
    assert "0.00 / 0.01" in format_table([row])  # the paper's row beside ours


def test_the_printed_table_keeps_its_columns_for_long_row_names() -> None:
    # 'campaign --model elastic' printed 'P1/elastic   0   1 |' past the 6-character set column: every bar shifted
    results = [TaskResult(name, 0, 1e-4, 2e-4, 0.0, 0.0, 0.0) for name in ("P1", "P1/elastic", "PallNE/auto")]
    lines = format_table(table(results)).splitlines()
    bars = {tuple(i for i, char in enumerate(line) if char == "|") for line in lines}
    assert len(bars) == 1 and len(next(iter(bars))) == 4, lines


def test_refused_sets_are_counted_not_averaged() -> None:
    nan = float("nan")
    results = [
        TaskResult("P1", 0, 1e-4, 2e-4, 0.0, 0.0, 0.0),
        TaskResult("P1", 1, nan, nan, nan, nan, 0.0, refused="samples.csv: rows 2-61, field 'alpha3': ..."),
        TaskResult("P2", 0, nan, nan, nan, nan, 0.0, refused="..."),
    ]
    p1, p2 = table(results)
    assert (p1.sets, p1.refused) == (1, 1) and p1.average[0] == pytest.approx(1e-4)
    assert (p2.sets, p2.refused) == (0, 1) and np.isnan(p2.average[0])
    assert table_csv([p1]).splitlines()[1].startswith("P1,1,1,0,0.100")


def test_campaign_is_the_same_on_one_or_two_workers(tmp_path) -> None:
    config = CampaignConfig(sets=3, fixture_sets=("P1", "Pall"))
    one = run_campaign(config, workers=1, progress=False, runner=fake_runner)
    two = run_campaign(config, workers=2, progress=False, runner=fake_runner)
    assert one.results == two.results and not one.failures and 1 <= len(two.workers) <= 2
    csv_path, md_path = write_tables(table(two.results), tmp_path / "out", comment="test")
    assert csv_path.read_text() == table_csv(table(one.results), comment="test")
    assert md_path.read_text().count("\n| P") == 4
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["table2.csv", "table2.md"]


def test_no_progress_bar_on_a_stderr_that_is_not_a_terminal(capsys) -> None:
    # the campaign's bar was tqdm's default (shown on pipes and log files): `campaign --scheduler` that could not
    # connect printed two bar lines before its one-line refusal
    run_campaign(CampaignConfig(sets=2, fixture_sets=("P1",)), workers=1, progress=True, runner=fake_runner)
    assert capsys.readouterr().err == ""


#: The smallest campaign whose calibrations are refused: an elastic model of 37 unknowns on 10 samples of one
#: fixture (31 equations); with Pall (three fixtures, distances known) the same samples calibrate.
REFUSED = ["campaign", "--sets", "1", "--per-fixture", "10", "--configurations", "50", "--noise", "0", "--model",
           "elastic", "--workers", "1"]


def test_a_campaign_whose_every_set_is_refused_exits_1_in_one_line_and_writes_nothing(tmp_path, capsys) -> None:
    # a review: when every calibration was refused the command printed a table of nan, wrote it and exited 0
    reason = run_task(tasks(CampaignConfig(sets=1, samples=10, configurations=50, noise_levels=(0.0,),
                                           fixture_sets=("P1",), model="elastic"))[0]).refused
    assert reason  # the case is one the calibration refuses
    refused([*REFUSED, "--rows", "P1", "--out", tmp_path / "c"], tmp_path, capsys,
            "no set could be calibrated (1 refused); the first, P1/elastic set 0: " + reason)


def test_a_campaign_whose_every_set_fails_exits_1_and_writes_nothing(tmp_path, capsys, monkeypatch) -> None:
    """A review: when every set raised (as opposed to being refused by the self-check) the command wrote an empty
    table2.csv and table2.md and exited 1; it refuses in one line naming the first failure, nothing written."""
    import spherecal.validation.experiments.campaign as campaign

    def explode(*args, **kwargs):
        raise RuntimeError("solver exploded")

    monkeypatch.setattr(campaign, "motion_set", explode)  # --workers 1: the sets run in this process
    refused([*REFUSED, "--rows", "P1,Pall", "--out", tmp_path / "c"], tmp_path, capsys,
            "error: no set could be run (2 failed); the first, P1/elastic set 0: RuntimeError: solver exploded")


def test_a_campaign_with_some_sets_refused_writes_the_others_and_reports_the_refused(tmp_path, capsys) -> None:
    assert main([*REFUSED, "--rows", "P1,Pall", "--out", str(tmp_path / "c")]) == 0
    out = capsys.readouterr().out
    assert "refused: P1/elastic set 0: " in out
    rows = {line.split(",")[0]: line.split(",")[1:3] for line in (tmp_path / "c" / "table2.csv").read_text()
            .splitlines() if not line.startswith("#")}
    assert rows["P1/elastic"] == ["0", "1"] and rows["Pall/elastic"] == ["1", "0"]  # sets, refused


@pytest.mark.slow
def test_small_real_campaign_is_reproducible(tmp_path) -> None:
    config = CampaignConfig(sets=2, samples=150, configurations=500, fixture_sets=("P1", "Pall"))
    first = run_campaign(config, workers=2, progress=False).results
    again = [run_task(t) for t in tasks(config)[:2]]
    assert [r.mean for r in first[:2]] == [r.mean for r in again]
    rows = {r.name: r for r in table(first)}
    # noise-free with three fixtures and known distances: micrometres; nominal: millimetres
    assert rows["Pall"].average[0] < 1e-5 < 1e-3 < rows["Pall"].nominal_average
    assert rows["PallN"].average[0] < min(0.25e-3, rows["PallN"].nominal_average / 10)  # 150 noisy samples each


@pytest.mark.filterwarnings("error::RuntimeWarning")  # numpy's 'invalid value in sqrt' of a noise-free fit's variance
def test_the_paper_protocol_calibrates_every_set_from_the_perturbed_start() -> None:
    """h10's docs walk-through: `campaign --protocol paper` refused 80 of 80 sets: its nominal model is the true
    robot, which the self-check found already fits the samples ('there is nothing here to calibrate'). The protocol's
    sets are written whatever the self-check says, and land on the truth as the paper's Table 2 does (P1 0.00)."""
    config = CampaignConfig(sets=1, samples=150, configurations=500, fixture_sets=("P1",), protocol="paper")
    results = [run_task(t) for t in tasks(config)]
    assert not any(r.refused for r in results), [r.refused for r in results]
    rows = {r.name: r for r in table(results)}
    assert rows["P1"].average[0] < 1e-5 < 1e-3 < rows["P1"].nominal_average  # the perturbed start: millimetres
    assert rows["P1N"].average[0] < rows["P1N"].nominal_average / 10


def test_a_campaign_with_some_sets_failing_writes_them_as_incomplete_rows_and_exits_1(tmp_path, capsys,
                                                                                        monkeypatch) -> None:
    """A review: with P1's set raising, `campaign --rows P1,P3` wrote a table of P3 alone, nothing in either file
    saying P1 was asked for, and exited 1. The table keeps the sets that finished (hours of a long campaign) and
    says what is missing: P1 listed with no set and one failed, a 'failed:' comment line naming the set and its
    error in both files, one line on stderr naming the set and the --rows that runs it again."""
    import spherecal.validation.experiments.campaign as campaign

    real = campaign.motion_set

    def p1_explodes(truth, start, fixtures, *args, **kwargs):
        if list(fixtures) == ["P1"]:
            raise RuntimeError("solver exploded")
        return real(truth, start, fixtures, *args, **kwargs)

    monkeypatch.setattr(campaign, "motion_set", p1_explodes)  # --workers 1: the sets run in this process
    out = tmp_path / "c"
    assert main(["campaign", "--sets", "1", "--per-fixture", "20", "--configurations", "50", "--noise", "0",
                 "--workers", "1", "--rows", "P1,P3", "--out", str(out)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0] == ("spherecal campaign: error: 1 of 2 sets failed (P1 set 0): written as incomplete rows (the "
                      "'failed' column of table2.csv and table2.md); --rows P1 runs them again")
    text = (out / "table2.csv").read_text()
    comments = [line for line in text.splitlines() if line.startswith("#")]
    assert "# failed: 1 of 2 sets, not in the statistics: P1 set 0 (RuntimeError: solver exploded)" in comments
    header, *rows = [line.split(",") for line in text.splitlines() if not line.startswith("#")]
    assert header[:4] == ["set", "sets", "refused", "failed"]
    assert [row[:4] for row in rows] == [["P1", "0", "0", "1"], ["P3", "1", "0", "0"]]  # the campaign's row order
    assert "failed: 1 of 2 sets, not in the statistics: P1 set 0" in (out / "table2.md").read_text()


def test_failed_sets_are_counted_in_their_rows_in_the_campaigns_order() -> None:
    results = [TaskResult("P2", 0, 1e-4, 2e-4, 1e-4, 1e-3, 0.0), TaskResult("P2", 1, 3e-4, 4e-4, 1e-4, 1e-3, 0.0)]
    rows = table(results, failed=["P1", "P2", "P1"], order=["P1", "P2", "P3"])
    assert [(r.name, r.sets, r.failed) for r in rows] == [("P1", 0, 2), ("P2", 2, 1)]  # P3 never ran: not listed
    assert rows[1].average[0] == pytest.approx(2e-4) and np.isnan(rows[0].average[0])  # failed sets not averaged
    assert table(results) == table(results, (), ())  # without failures: as before
    assert "err" in format_table(rows).splitlines()[0]


def _fails_on_pall(task) -> TaskResult:
    if task.fixtures == ("P1", "P2", "P3"):
        raise RuntimeError("solver exploded")
    return fake_runner(task)


def test_failed_sets_carry_their_fixture_set_for_the_rerun() -> None:
    """The rerun's --rows was recovered from the row's name by a regex; each task carries its fixture set instead,
    whatever the name's suffixes (noise, elastic truth, model)."""
    config = CampaignConfig(sets=2, fixture_sets=("P2", "Pall"), stiffness=(0, 3e4, 3e4, 3e4, 0, 0, 0), model="auto")
    with pytest.warns(TaskFailedWarning, match=r"task PallN?E/auto set [01] failed"):
        run = run_campaign(config, workers=1, progress=False, runner=_fails_on_pall)
    assert run.failed_rows == ("PallE/auto",) * 2 + ("PallNE/auto",) * 2
    assert run.failed_sets == ("Pall",) * 4 and {r.row for r in run.results} == {"P2E/auto", "P2NE/auto"}
