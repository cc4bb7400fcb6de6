"""The did-you-mean helper of the file readers: cutoff and count as each reader asks."""

from __future__ import annotations

from spherecal.correction.files.suggest import close_names


def test_cutoff_is_the_similarity_ratio_worked_by_hand() -> None:
    # 'inertial' in 'inertials': 8 matching characters of 8 + 9, ratio 2 * 8 / 17 = 0.941
    assert close_names("inertial", ["inertials", "dh"], cutoff=0.94) == ["inertials"]
    assert close_names("inertial", ["inertials", "dh"], cutoff=0.95) == []


def test_at_most_n_best_first_and_keys_compared_as_text() -> None:
    links = ["link1", "link2", "link3", "link4", "base"]
    assert len(close_names("link", links, cutoff=0.5, n=3)) == 3  # four at 0.889 ('base' 0.25): three kept
    assert close_names("lnk2", links, cutoff=0.5) == ["link2"]  # 8/9 beats link1 at 6/9
    assert close_names(12, [1, 13, 120], cutoff=0.5, n=3) == ["120", "1", "13"]  # 4/5, 2/3, 2/4
