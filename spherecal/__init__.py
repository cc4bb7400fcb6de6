"""spherecal: kinematic calibration of a serial arm from spherical-joint self-motion.

Subpackages (imported as ``spherecal.<name>``; in the source tree they are the folders at the
repository root, mapped into this package by ``pyproject.toml``):

* :mod:`spherecal.correction`: the kinematic model, parameter layout, robot and data files (the base
  layer; imports nothing else of spherecal).
* :mod:`spherecal.identification`: samples in, calibrated parameters out.
* :mod:`spherecal.controller`: MuJoCo plant, QP differential IK, null-space self-motion, compensation.
* :mod:`spherecal.validation`: simulated motion capture, comparisons, campaigns, Rerun, planning.
* :mod:`spherecal.cli`: the ``spherecal`` command line (library code never imports it).
"""

from __future__ import annotations

import importlib.abc as _abc
import importlib.util as _util
import os as _os
import sys as _sys

#: The design card's folders, mapped into this package (the CLI modules live in this folder).
SUBPACKAGES = ("correction", "identification", "controller", "validation")


class _SourceFolders(_abc.MetaPathFinder):
    """Finds ``spherecal.<subpackage>`` in the repository root of a source checkout, and nothing else.

    Installed (``pip install .``) the subpackages are copied into this folder; an editable install
    maps them with its own import hook. Only a source checkout imported without either (this folder
    found first on ``sys.path``) needs this finder: it maps the four folders of
    :data:`SUBPACKAGES` by name, so ``spherecal.tests`` or ``spherecal.bench`` never import.
    """

    def __init__(self, root: str) -> None:
        self.root = root

    def find_spec(self, fullname, path=None, target=None):  # noqa: D102 - importlib protocol
        prefix, _, name = fullname.partition(".")
        if prefix != __name__ or name not in SUBPACKAGES:
            return None
        folder = _os.path.join(self.root, name)
        return _util.spec_from_file_location(
            fullname, _os.path.join(folder, "__init__.py"), submodule_search_locations=[folder]
        )


_HERE = _os.path.dirname(_os.path.abspath(__file__))
_ROOT = _os.path.dirname(_HERE)
if not _os.path.isdir(_os.path.join(_HERE, "correction")) and all(
    _os.path.isfile(_os.path.join(_ROOT, name, "__init__.py")) for name in SUBPACKAGES
):
    # Appended: an editable install's hook (earlier on the list) keeps precedence where there is one.
    if not any(isinstance(finder, _SourceFolders) for finder in _sys.meta_path):
        _sys.meta_path.append(_SourceFolders(_ROOT))
