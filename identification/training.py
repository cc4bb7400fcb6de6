"""What a calibration was trained on, by content: per-fixture digests of the samples, and leaving fixtures out.

The calibrated file's ``calibration.trained_on`` block (written by ``calibrate``, read by ``validate``)::

    trained_on:
      digest: sha256 of the fixture's joint angles [rad], float64 little-endian, rows sorted
      fixtures:
        front_h0: {samples: 30, read: <sha256 of the samples as read>, used: <sha256 after dedup/subsampling>,
                   sketch: [<16 hex digits>, ...]}

``validate`` marks a fixture of its samples as used in the fit when its digest equals either one of
any trained fixture, whatever either is named (MUKCa calls the placements of every robot ``front``,
``left``...), or when one of its samples is in a trained fixture's ``sketch``: the smallest
:data:`SKETCH` of the per-sample hashes of the samples as read
(:func:`~spherecal.correction.files.samples.configuration_hashes`). A bottom-k sketch: a fixture holding a
share ``f`` of a trained fixture's samples (the recording imported again with another subsample, or all of it
again) misses every one of them with probability ``(1 - f)^k``, 1e-6 for a fifth at 64.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset, DatasetError, configuration_hashes, configurations_digest

#: How the digests of ``trained_on`` are made (written beside them).
DIGEST = "sha256 of the fixture's joint angles [rad], float64 little-endian, rows sorted"
#: Per-sample hashes kept per trained fixture (the smallest), and at most this many over all fixtures (a file
#: of 10^4 fixtures keeps the robot file small: 8 each at least).
SKETCH = 64
SKETCH_TOTAL = 8192


def training_record(read: Dataset, used: Dataset) -> dict:
    """The ``trained_on`` block: per fixture used, its sample count and the digests as read and as used."""
    fixtures = {}
    k = max(8, min(SKETCH, SKETCH_TOTAL // max(len(used.fixture_names), 1)))
    for name in used.fixture_names:
        fixtures[name] = {
            "samples": int(np.count_nonzero(used.labels == name)),
            "read": configurations_digest(read.for_fixture(name)),
            "used": configurations_digest(used.for_fixture(name)),
            "sketch": [f"{h:016x}" for h in np.unique(configuration_hashes(read.for_fixture(name)))[:k]],
        }
    return {"digest": DIGEST, "fixtures": fixtures}


def trained_digests(block: dict | None) -> set[str] | None:
    """Every digest a calibration block records (None when it records none: an older file)."""
    trained = block.get("trained_on") if isinstance(block, dict) else None
    fixtures = trained.get("fixtures") if isinstance(trained, dict) else None
    if not isinstance(fixtures, dict):
        return None
    return {v for entry in fixtures.values() if isinstance(entry, dict) for k, v in entry.items()
            if k in ("read", "used") and isinstance(v, str)}


def trained_sketch(block: dict | None) -> set[int]:
    """Every per-sample hash the ``sketch`` entries of a calibration block record (empty for an older file)."""
    trained = block.get("trained_on") if isinstance(block, dict) else None
    fixtures = trained.get("fixtures") if isinstance(trained, dict) else None
    out: set[int] = set()
    for entry in fixtures.values() if isinstance(fixtures, dict) else ():
        sketch = entry.get("sketch") if isinstance(entry, dict) else None
        for text in sketch if isinstance(sketch, list) else ():
            try:
                out.add(int(str(text), 16))
            except ValueError:
                continue  # a hand-edited entry recognises nothing
    return out


def exclude_fixtures(
    dataset: Dataset, spec: FixtureSpec | None, names: list[str] | tuple[str, ...]
) -> tuple[Dataset, FixtureSpec | None]:
    """The samples and fixtures without the fixtures ``names`` (and every known distance naming one).

    Raises:
        DatasetError: a name that is not a fixture of the samples (one line naming the file and the
            fixtures it has), or no fixture left.
    """
    if not names:
        return dataset, spec
    have = dataset.fixture_names
    for name in names:
        if name not in have:
            raise DatasetError(
                f"{dataset.source or 'samples'}: field 'fixture': --exclude-fixture {name!r} is not a fixture of the "
                f"samples (they have {', '.join(have)})"
            )
    keep = ~np.isin(dataset.labels, list(names))
    if not keep.any():
        raise DatasetError(f"{dataset.source or 'samples'}: field 'fixture': --exclude-fixture leaves no fixture")
    dataset = dataset.select(np.flatnonzero(keep))
    if spec is not None:
        left = set(dataset.fixture_names)
        kept = [k for k, d in enumerate(spec.distances) if d[0] in left and d[1] in left]
        spec = replace(spec.keep_distances(kept), names=tuple(n for n in spec.names if n in left),
                       positions={k: v for k, v in spec.positions.items() if k in left})
    return dataset, spec
