"""samples.csv and fixtures.yaml: round trips, duplicates, subsampling, one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction.files import samples
from spherecal.correction.files.fixtures import FixtureSpec, read_fixtures, write_fixtures
from spherecal.correction.files.samples import Dataset, DatasetError, _first_of_clusters, first_of_rows
from spherecal.correction.files.samples_csv import read_samples, write_samples

HEADER = "fixture,q1,q2,q3,q4,q5,q6,q7\n"
GOOD = "P1,0,0,0,-1,0,1,0\n"


def _dataset(panda, rng, count=10, t=True) -> Dataset:
    q = panda.random_configurations(count, rng)
    labels = ["P1"] * (count // 2) + ["P2"] * (count - count // 2)
    return Dataset(labels=labels, q=q, t=np.arange(count) * 1e-3 if t else None)


def test_samples_round_trip_exactly(tmp_path, panda, rng) -> None:
    for t in (True, False):
        ds = _dataset(panda, rng, t=t)
        write_samples(tmp_path / "s.csv", ds)
        back = read_samples(tmp_path / "s.csv", panda)
        assert back.fixture_names == ("P1", "P2")
        assert back.counts() == {"P1": 5, "P2": 5}
        assert np.array_equal(back.q, ds.q)
        assert (back.t is None) == (not t)
        if t:
            assert np.array_equal(back.t, ds.t)


def test_fixture_order_is_first_appearance(panda, rng) -> None:
    ds = Dataset(labels=["B", "A", "B", "C"], q=panda.random_configurations(4, rng))
    assert ds.fixture_names == ("B", "A", "C")
    assert ds.fixture_index.tolist() == [0, 1, 0, 2]
    assert ds.for_fixture("B").shape == (2, 7)


def test_fixture_index_names_each_sample_s_fixture(rng) -> None:
    labels = np.array(["B", "A", "C", "B", "A", "A"] * 50)
    given = Dataset(labels=labels, q=rng.normal(size=(labels.size, 7)), fixture_names=("C", "A", "B"))
    np.testing.assert_array_equal(given.fixture_index, [("C", "A", "B").index(label) for label in labels])
    unlisted = Dataset(labels=labels, q=given.q, fixture_names=("A", "B"))
    with pytest.raises(KeyError, match="C"):
        _ = unlisted.fixture_index


def test_deduplicate_exact_and_near(panda, rng) -> None:
    q = panda.random_configurations(6, rng)
    extra = np.vstack([q[0], q[1] + 5e-5, q[2] + 5e-3])  # exact, near, distinct
    ds = Dataset(labels=["P"] * 9, q=np.vstack([q, extra]))
    assert ds.deduplicated(0.0).n_samples == 8
    assert ds.deduplicated(1e-4).n_samples == 7
    assert ds.deduplicated(1e-2).n_samples == 6
    kept = ds.deduplicated(1e-4)
    assert np.array_equal(kept.q[:6], q)  # the earlier sample is the one kept
    # the same configuration at two fixtures is not a duplicate
    two = Dataset(labels=["A", "B"], q=np.vstack([q[0], q[0]]))
    assert two.deduplicated().n_samples == 2


def test_tiny_or_nan_dedup_tolerance(panda, rng) -> None:
    # q / 1e-20 overflowed int64: 245 of 300 distinct samples were dropped as "duplicates"
    ds = _dataset(panda, rng, count=300)
    assert ds.deduplicated(1e-20).n_samples == 300
    with pytest.raises(ValueError, match="tol must be >= 0"):
        ds.deduplicated(float("nan"))


def _first_of_clusters_by_hand(q: np.ndarray, tol: float) -> np.ndarray:
    """The rule of Dataset.deduplicated, one sample at a time: the first sample of each tol grid cell, kept unless an
    earlier kept one lies within tol on every joint."""
    cells = np.floor(q / tol) if tol > 0 else q
    seen, keep = set(), np.zeros(len(q), dtype=bool)
    for k, cell in enumerate(cells):
        key = tuple(float(c) + 0.0 for c in cell)
        if key in seen:
            continue
        seen.add(key)
        kept = np.flatnonzero(keep)
        keep[k] = tol == 0 or not np.any(np.abs(q[kept] - q[k]).max(axis=1) <= tol)
    return keep


def test_deduplicate_follows_its_rule_on_dense_repeats() -> None:
    # a still arm at 1 kHz: bursts of encoder noise about a few configurations, and slow motion between them
    rng = np.random.default_rng(7)
    for trial in range(40):
        centres = rng.normal(0, 3e-4, (rng.integers(1, 6), rng.integers(1, 8)))
        q = centres[rng.integers(0, len(centres), 300)] + rng.normal(0, [0, 2e-6, 5e-5, 2e-4][trial % 4], (300, 1))
        q[rng.random(q.shape) < 0.05] = -0.0 if trial % 2 else 0.0  # -0.0 and 0.0 are one value
        for tol in (0.0, 1e-4, 3e-4):
            np.testing.assert_array_equal(_first_of_clusters(q, tol), _first_of_clusters_by_hand(q, tol))


def testfirst_of_rows_is_numpy_unique_s() -> None:
    rng = np.random.default_rng(8)
    cells = np.floor(rng.normal(0, 2, (2000, 7)))
    cells[rng.random(cells.shape) < 0.2] = -0.0
    expected = np.sort(np.unique(cells, axis=0, return_index=True)[1])
    np.testing.assert_array_equal(first_of_rows(cells), expected)
    cells[5, 3] = np.nan  # not finite: np.unique itself
    np.testing.assert_array_equal(first_of_rows(cells), np.sort(np.unique(cells, axis=0,
                                                                                   return_index=True)[1]))


def test_subsample_is_seeded_and_per_fixture(panda, rng) -> None:
    ds = _dataset(panda, rng, count=40)
    a = ds.subsampled(7, np.random.default_rng(3))
    b = ds.subsampled(7, np.random.default_rng(3))
    c = ds.subsampled(7, np.random.default_rng(4))
    assert a.counts() == {"P1": 7, "P2": 7}
    assert np.array_equal(a.q, b.q) and not np.array_equal(a.q, c.q)
    assert np.all(np.diff(a.t[a.labels == "P1"]) > 0)  # recording order kept
    assert ds.subsampled(None, rng) is ds


@pytest.mark.parametrize(
    ("text", "row", "field"),
    [
        (HEADER + GOOD + "P1,0,0,0,-1,0,1,nan\n", 3, "q7"),
        (HEADER + "P1,0,0,abc,-1,0,1,0\n", 2, "q3"),
        ("fixture,q1,q2,q3,q4,q5,q6\nP1,0,0,0,-1,0,1\n", 1, "q*"),
        (HEADER + "P1,0,0,0,-1,0,1\n", 2, "q7"),
        (HEADER + "P1,0,0,0,-1,0,1,0,0\n", 2, "column 9"),
        (HEADER + GOOD + GOOD + "P1,0,0,0,2.5,0,1,0\n", 4, "q4"),  # past a quarter turn (less: used, warned)
        ("", 1, "fixture"),
        (HEADER, 2, "fixture"),
        ("fixture,q1,q2,q3,q4,q5,q6,q7,q7\n", 1, "q7"),
        ("fixture,q1,q2,q3,q4,q5,q6,x\n", 1, "x"),
        ("fixture,q1,t,q2,q3,q4,q5,q6,q7\n", 1, "t"),
        ("P,q1,q2,q3,q4,q5,q6,q7\n", 1, "P"),
        (HEADER + ",0,0,0,-1,0,1,0\n", 2, "fixture"),
    ],
)
def test_bad_samples_one_line_naming_file_row_field(tmp_path, panda, text, row, field) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DatasetError) as info:
        read_samples(path, panda)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message and f"row {row}," in message and f"field '{field}'" in message, message


def test_comments_and_blank_lines_keep_line_numbers(tmp_path, panda) -> None:
    path = tmp_path / "s.csv"
    path.write_text("# recorded by hand\n" + HEADER + "\n" + GOOD + "P1,0,0,0,-1,0,1,x\n")
    with pytest.raises(DatasetError, match="row 5, field 'q7'"):
        read_samples(path, panda)


def test_fixtures_round_trip(tmp_path) -> None:
    spec = FixtureSpec(("P1", "P2", "P3"), {"P2": np.array([0.5, 0.1, 0.3])}, [("P1", "P2", 0.5), ("P2", "P3", 0.25)])
    write_fixtures(tmp_path / "f.yaml", spec)
    back = read_fixtures(tmp_path / "f.yaml")
    assert back.names == spec.names
    assert back.distances == spec.distances
    assert np.array_equal(back.positions["P2"], spec.positions["P2"]) and list(back.positions) == ["P2"]


@pytest.mark.parametrize(
    ("text", "row", "field"),
    [
        ("fixtures: {P1: {}, P2: {}}\ndistances:\n  - [P1, P2, -0.5]\n", 3, "distances[0][2]"),
        ("fixtures: {P1: {}, P2: {}}\ndistances:\n  - [P1, P2, 0]\n", 3, "distances[0][2]"),
        ("fixtures: {P1: {}, P2: {}}\ndistances:\n  - [P1, P3, 0.5]\n", 3, "distances[0][1]"),
        ("fixtures:\n  P1: {}\n  P1: {}\n", 3, "P1"),
        ("fixtures:\n  P1: {postion: [1, 2, 3]}\n", 2, "fixtures.P1.postion"),
        ("fixtures:\n  P1: {position: [1, 2]}\n", 2, "fixtures.P1.position"),
        ("", 1, "fixtures"),
        ("fixtures: {}\n", 1, "fixtures"),
        ("fixtures: {P1: {}, P2: {}}\ndistances:\n  - [P1, P1, 0.5]\n", 3, "distances[0]"),
    ],
)
def test_bad_fixtures_one_line(tmp_path, text, row, field) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(DatasetError) as info:
        read_fixtures(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message and f"row {row}," in message and f"field '{field}'" in message, message


def test_distance_to_fixture_without_samples(tmp_path, panda, rng) -> None:
    path = tmp_path / "f.yaml"
    path.write_text("fixtures: {P1: {}, P2: {}, P3: {}}\ndistances:\n  - [P1, P3, 0.5]\n")
    spec = read_fixtures(path)
    with pytest.raises(DatasetError, match=r"row 3, field 'distances\[0\]': fixture 'P3' has no samples"):
        spec.check_against(_dataset(panda, rng))


def test_writers_are_atomic_and_leave_nothing_on_error(tmp_path, panda, rng) -> None:
    ds = Dataset(labels=["P,1"], q=panda.random_configurations(1, rng))
    with pytest.raises(DatasetError):
        write_samples(tmp_path / "s.csv", ds)
    assert list(tmp_path.iterdir()) == []


def test_byte_order_mark_is_not_part_of_the_header(tmp_path, panda) -> None:
    # spreadsheets save "UTF-8 CSV" with a byte-order mark; it used to make the header 'ï»¿fixture'
    path = tmp_path / "s.csv"
    path.write_bytes(b"\xef\xbb\xbf" + (HEADER + GOOD).encode())
    assert read_samples(path, panda).fixture_names == ("P1",)
    yaml_path = tmp_path / "f.yaml"
    yaml_path.write_bytes(b"\xef\xbb\xbffixtures: {P1: {}}\n")
    assert read_fixtures(yaml_path).names == ("P1",)


def test_unlisted_fixture_message_names_it_plainly(tmp_path, panda, rng) -> None:
    from spherecal.identification.build import build_problem

    path = tmp_path / "s.csv"
    path.write_text(HEADER + GOOD + "P9,0,0,0,-1,0,1,0\n")
    with pytest.raises(DatasetError) as info:
        build_problem(panda, read_samples(path, panda), FixtureSpec.unknown(["P1"]))
    assert "row 3, field 'fixture': fixture 'P9' is not listed" in str(info.value)


def test_numbered_fixtures_match_numbered_samples(tmp_path, panda) -> None:
    # "1: {}" used to be refused ("fixture name must be a non-empty string") while samples.csv accepts 1
    path = tmp_path / "f.yaml"
    path.write_text("fixtures:\n  1: {}\n  2: {position: [0.5, 0, 0.3]}\ndistances:\n  - [1, 2, 0.5]\n")
    spec = read_fixtures(path)
    assert spec.names == ("1", "2") and list(spec.positions) == ["2"] and spec.distances == [("1", "2", 0.5)]
    samples = tmp_path / "s.csv"
    samples.write_text(HEADER + GOOD.replace("P1", "1") + GOOD.replace("P1", "2"))
    spec.check_against(read_samples(samples, panda))


def test_limit_excess_in_blocks_is_the_same_as_at_once(panda, monkeypatch) -> None:
    # LimitExcess.add checks a long recording a block at a time: the worst excess of each joint, where it was, and
    # the first row refused are the ones found at once
    rng = np.random.default_rng(9)
    q = rng.uniform(panda.lower - 0.3, panda.upper + 0.3, (50, 7))
    q[[7, 31], 2] = panda.upper[2] + 0.25  # a tie: the first is named
    found = {}
    for block in (100_000, 4, 1):
        monkeypatch.setattr(samples, "LIMIT_BLOCK", block)
        excess = samples.LimitExcess.of(panda)
        excess.add(q, lambda k: f"row {k + 2}", DatasetError)
        hard = q.copy()
        hard[[12, 40], [3, 1]] = panda.upper[[3, 1]] + 2.0
        with pytest.raises(DatasetError) as error:
            samples.LimitExcess.of(panda).add(hard, lambda k: f"row {k + 2}", DatasetError)
        found[block] = (excess.worst, str(error.value))
    assert found[100_000] == found[4] == found[1] and "row 14" in found[1][1]
