"""The did-you-mean of a refusal: the known names nearest a misspelt one."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


def close_names(word: Any, names: Iterable, cutoff: float, n: int = 1) -> list[str]:
    """The (at most ``n``) names of ``names`` nearest ``word``, best first, each with difflib's similarity ratio at
    least ``cutoff`` (0 to 1); empty when none is that close.

    Each caller keeps its own ``cutoff``: a short list of block names (``'inertials'``, ``'dh'``) needs a high
    one so that no unrelated key is "corrected", a URDF's many link names a lower one to suggest anything.
    ``word`` and ``names`` are compared as text (``str``), as YAML keys may be numbers.
    """
    return difflib.get_close_matches(str(word), [str(name) for name in names], n=n, cutoff=cutoff)
