"""Shared by the readers' tests: a file refused with a message that names it and the problem,
and what a read costs."""

from __future__ import annotations

import gc
import time

import pytest

from core.io import CloudFileError, read_cloud


def refused(path, *parts):
    """``read_cloud(path)`` raises a CloudFileError whose message holds the file's name and each of ``parts``."""
    with pytest.raises(CloudFileError) as info:
        read_cloud(path)
    for part in (path.name, *parts):
        assert part in str(info.value), str(info.value)


def cpu_seconds(work, repeats: int = 3) -> float:
    """The least CPU seconds of the process over ``repeats`` calls of ``work()`` (the collector
    off): what the work costs, which a loaded machine does not stretch as it does wall time.
    "At once" is then a bound against an ordinary file's read measured in the same run."""
    spent = []
    gc.collect()
    gc.disable()
    try:
        for _ in range(repeats):
            start = time.process_time()
            work()
            spent.append(time.process_time() - start)
    finally:
        gc.enable()
    return min(spent)
