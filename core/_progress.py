"""Progress reporting and cooperative cancellation for long runs."""

from __future__ import annotations


class Cancelled(Exception):
    """Raised inside a long computation when its progress callback returned False."""


class Progress:
    """Wrap a user callback ``callback(fraction, stage) -> None | False``.

    ``fraction`` runs 0..1 over the whole job; stages map onto sub-ranges with
    :meth:`sub`. Returning ``False`` from the callback cancels the job.
    """

    def __init__(self, callback=None, start: float = 0.0, stop: float = 1.0):
        if callback is not None and not callable(callback):
            raise ValueError(f"progress must be callable or None, got {callback!r}")
        self._callback = callback
        self._start = start
        self._span = stop - start

    def __call__(self, fraction: float, stage: str) -> None:
        if self._callback is None:
            return
        answer = self._callback(self._start + self._span * min(max(fraction, 0.0), 1.0), stage)
        if answer is not None and not answer:  # False, and numpy's False_ or a 0 alike
            raise Cancelled(f"cancelled during {stage}")

    def sub(self, start: float, stop: float) -> "Progress":
        """A reporter for the sub-range [start, stop] of this one."""
        return Progress(
            self._callback, self._start + self._span * start, self._start + self._span * stop
        )
