"""A controls engineer's trial of ``spherecal.controller``'s exports: every name the package lists is what it says,
whatever was imported before. The package listed the function ``ik``, but its submodule of the same name replaces
that attribute as soon as anything imports it (``compensation``, ``exploration``, ``self_motion`` do): a trial got
``TypeError: 'module' object is not callable``. The function is ``controller.ik.ik``."""

from __future__ import annotations

import subprocess
import sys
import types

import pytest

SCRIPT = """
import types
{first}
import spherecal.controller as package
shadowed = [name for name in package.__all__ if isinstance(getattr(package, name), types.ModuleType)]
assert not shadowed, shadowed
from spherecal.controller import ik
from spherecal.controller.ik import IKResult, ik as function
assert isinstance(ik, types.ModuleType) and ik.ik is function and ik.IKResult is IKResult
print("ok")
"""


@pytest.mark.parametrize("first", ["", "import spherecal.controller.compensation",
                                   "from spherecal.controller.ik import ik as _"])
def test_no_exported_name_is_a_submodule_whatever_came_first(first) -> None:
    done = subprocess.run([sys.executable, "-c", SCRIPT.format(first=first)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_the_listed_names_are_not_modules() -> None:
    import spherecal.controller as package

    assert "ik" not in package.__all__
    assert not [name for name in package.__all__ if isinstance(getattr(package, name), types.ModuleType)]
