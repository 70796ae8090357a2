"""Shared by the readers' tests: a file refused with a message that names it and the problem."""

from __future__ import annotations

import pytest

from core.io import CloudFileError, read_cloud


def refused(path, *parts):
    """``read_cloud(path)`` raises a CloudFileError whose message holds the file's name and each of ``parts``."""
    with pytest.raises(CloudFileError) as info:
        read_cloud(path)
    for part in (path.name, *parts):
        assert part in str(info.value), str(info.value)
