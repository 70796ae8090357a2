"""Memo of the early stages of :func:`core.estimate` across calls on one cloud.

An interactive viewer re-estimates the same cloud with a few parameters changed; a
change of the refinement passes leaves the neighbours, the outlier scores, the initial
normals, their orientation, the crease reference and the chosen k as they were. Pass
one :class:`StageCache` as ``estimate(..., cache=...)`` to every call: each stage's
output is kept under a key made of the inputs (a digest of the points, and of the given
normals) and of the plan fields that stage reads (:data:`STAGE_FIELDS`), and re-used
when the key matches. The pipeline itself stays in :func:`core.estimate`: the cache
only decides whether a stage function runs. The result is bit-identical with and
without a cache (tests/core/test_stage_cache.py).

Only the last output of each stage is kept (memory: one cloud's worth, e.g. ~0.3 GB
for 1M points with k = "auto"). Kept arrays are made read-only, so a caller editing a
result's ``k_point`` gets an error instead of silently changing the next result.
"""

from __future__ import annotations

import hashlib
from collections import Counter

import numpy as np

__all__ = ["StageCache", "STAGE_FIELDS"]

_BASE = ("k_initial", "k_search", "initial", "auto", "noise", "robust")
#: Plan fields (:class:`core.planning.EstimatePlan`) each cached stage depends on, on top of
#: the cloud, its given normals and the neighbour graph. Each stage lists those of the
#: stages it takes its inputs from. The fit/refine and flags stages are not cached: they
#: are what a change of passes, tol or method re-runs.
STAGE_FIELDS = {
    "neighbours": ("k_search",),
    "scores": ("k_initial",),
    "initial": _BASE,
    "orientation": _BASE + ("orientation",),
    "reference": _BASE + ("orientation", "method", "options"),
    "scale": _BASE + ("orientation", "k", "candidates"),
}


class StageCache:
    """Outputs of :func:`core.estimate`'s early stages, re-used while their inputs hold.

    Attributes
    ----------
    computed, reused : collections.Counter
        How many times each stage (a key of :data:`STAGE_FIELDS`) ran or was re-used.

    Examples
    --------
    >>> from core import estimate, shapes
    >>> from core.stage_cache import StageCache
    >>> cache, pts = StageCache(), shapes.sphere(2000, seed=1).points
    >>> a = estimate(pts, k=15, passes=1, cache=cache)
    >>> b = estimate(pts, k=15, passes=3, cache=cache)  # neighbours to chosen k re-used
    >>> cache.computed["initial"], cache.reused["initial"]
    (1, 1)
    """

    def __init__(self):
        self._entries: dict[str, tuple[tuple, object]] = {}
        self._nb = None
        self._nb_token = 0
        self.computed: Counter = Counter()
        self.reused: Counter = Counter()

    def clear(self) -> None:
        """Forget every kept output (the counters stay)."""
        self._entries.clear()
        self._nb = None

    def bind(self, points: np.ndarray, normals: np.ndarray | None, plan) -> "_Memo":
        """The memo of one :func:`core.estimate` call on ``points`` (validated) with ``plan``."""
        inputs = (_digest(points), None if normals is None else _digest(normals))
        return _Memo(self, inputs, plan)

    def _token(self, nb) -> int:
        """A number naming the neighbour graph ``nb`` while it is the one in use."""
        if nb is not self._nb:
            self._nb, self._nb_token = nb, self._nb_token + 1
        return self._nb_token

    def _get(self, stage: str, key: tuple, compute):
        kept = self._entries.get(stage)
        if kept is not None and kept[0] == key:
            self.reused[stage] += 1
            return kept[1]
        value = _read_only(compute())
        self._entries[stage] = (key, value)
        self.computed[stage] += 1
        return value


class _Memo:
    """Runs a stage or returns its kept output; ``None`` cache: always runs."""

    def __init__(self, cache: StageCache | None, inputs: tuple, plan):
        self.cache, self.inputs, self.plan = cache, inputs, plan
        self.graph = None

    def neighbours(self, compute, given):
        """The neighbour graph and its spatial order, ``compute()``'s ``(nb, order)``: from
        ``given`` (the caller's graph) as is, else a kept search; later stages are keyed by
        the graph ``nb`` itself."""
        nb, order = compute() if given is not None or self.cache is None else self._run("neighbours", compute)
        self.graph = None if self.cache is None else self.cache._token(nb)
        return nb, order

    def __call__(self, stage: str, compute):
        return compute() if self.cache is None else self._run(stage, compute)

    def _run(self, stage: str, compute):
        fields = tuple(_field(self.plan, name) for name in STAGE_FIELDS[stage])
        return self.cache._get(stage, (self.inputs, self.graph, fields), compute)


def memo(cache: StageCache | None, points, normals, plan) -> _Memo:
    """The memo :func:`core.estimate` runs its stages through (a pass-through without a cache)."""
    if cache is None:
        return _Memo(None, (), plan)
    if not isinstance(cache, StageCache):
        raise ValueError(f"cache must be a core.stage_cache.StageCache or None, got {type(cache).__name__}")
    return cache.bind(points, normals, plan)


def _field(plan, name: str):
    value = getattr(plan, name)
    if name == "method":
        return value.name
    if name == "options":
        return repr(sorted(value.items()))
    return repr(value)


def _digest(a: np.ndarray) -> tuple:
    """Shape, dtype and a BLAKE2 hash of the bytes (~40 ms for 1M points)."""
    a = np.ascontiguousarray(a)
    return a.shape, a.dtype.str, hashlib.blake2b(a.data, digest_size=16).hexdigest()


def _read_only(value):
    """Mark the arrays of a stage's output (an array or a tuple of them) read-only."""
    if isinstance(value, np.ndarray):
        value.flags.writeable = False
    elif isinstance(value, tuple):
        for item in value:
            _read_only(item)
    return value
