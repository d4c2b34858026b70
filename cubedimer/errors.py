"""The one error of bad input data, :class:`DatasetError` (raised by the data-set loader and the meta.json reader)."""
from __future__ import annotations

__all__ = ["DatasetError"]


class DatasetError(ValueError):
    """A bad input file; ``str(err)`` is a one-line message naming the file and the problem."""
