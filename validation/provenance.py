"""The provenance block of every output, where validation code has found it so far (the one
implementation is :mod:`spherecal.correction.files.provenance`)."""

from __future__ import annotations

from spherecal.correction.files.provenance import PACKAGES, comment_block, file_digest, provenance, versions

__all__ = ["PACKAGES", "comment_block", "file_digest", "provenance", "versions"]
