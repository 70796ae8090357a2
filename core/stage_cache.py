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

The neighbour stage searches ``max(k, k_max)`` neighbours (``StageCache(k_max=...)``, head
room) and serves every later call on the same cloud whose plan needs at most that many,
on the points in spatial order as a call without a cache (:mod:`core.spatial_order`):
an interactive k slider then never searches again. The first k neighbours of a larger
search are those of a search for k (ties go to the lowest index either way); so the
search holds only the columns the plan reads at first (:func:`core.stages.search_width`)
and the graph searches the rest when a later call needs them
(:class:`core.wide_neighbours.WidenableNeighbours`).

Only the last ``keep`` outputs of each stage are kept (``keep=2``: a method and the one it
is compared with), and one neighbour graph (memory: one cloud's worth per kept output,
e.g. ~0.3 GB for 1M points with k = "auto"). Kept arrays are made read-only, so a caller
editing a result's ``k_point`` gets an error instead of silently changing the next result.
"""

from __future__ import annotations

import hashlib
from collections import Counter

import numpy as np

from .wide_neighbours import LazyNeighbours

__all__ = ["StageCache", "STAGE_FIELDS"]

_BASE = ("k_initial", "k_search", "initial", "auto", "noise", "fold_typical", "robust")
#: Plan fields (:class:`core.planning.EstimatePlan`) each cached stage depends on, on top of
#: the cloud, its given normals and the neighbour graph. Each stage lists those of the
#: stages it takes its inputs from. The fit/refine and flags stages are not cached: they
#: are what a change of passes, tol or method re-runs.
STAGE_FIELDS = {
    "neighbours": ("k_search",),  # served by any kept search of at least k_search (StageCache._search)
    "scores": ("k_initial",),
    "sheets": ("k_initial", "auto"),
    "initial": _BASE + ("viewpoint",),  # the scanner's rays widen some (core.plane_spread.ray_sheets)
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
    k_max : int
        The neighbour search finds at least this many neighbours (head room for a later
        call with a larger k; set it before a call).

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

    def __init__(self, *, k_max: int = 0, keep: int = 1):
        self.k_max = int(k_max)
        self.keep = max(int(keep), 1)
        self._entries: dict[str, list[tuple[tuple, object]]] = {}
        self._graph = None  # (inputs, (nb, order)) of the last search
        self._caller = None  # (nb, the same graph in the caller's order)
        self._given = None  # (a caller's graph, its points' inputs, (that graph as the stages read it, its order))
        self._nb = None
        self._nb_token = 0
        self._merged = None  # (digest, core.duplicates.Merged) of the last cloud with copies (remember)
        self.computed: Counter = Counter()
        self.reused: Counter = Counter()

    def clear(self) -> None:
        """Forget every kept output (the counters stay)."""
        self._entries.clear()
        self._graph = self._caller = self._nb = self._merged = self._given = None

    def known_merge(self, points: np.ndarray):
        """The places kept for ``points`` (:meth:`remember`), or None; nothing to compare (no
        digest of the points) while no merge is kept. A merge of another cloud stays kept: the
        estimate of the places themselves asks here too."""
        if self._merged is None or self._merged[0] != _digest(points):
            return None
        self.reused["merged"] += 1
        return self._merged[1]

    def remember(self, points: np.ndarray, merged) -> None:
        """Keep the places found on ``points`` (:mod:`core.duplicates`): a viewer's re-estimate
        does not sort a 1M-point cloud again (0.8 s), nor search it twice for near copies."""
        self._merged = (_digest(points), merged)
        self.computed["merged"] += 1

    def bind(self, points: np.ndarray, normals: np.ndarray | None, plan, views=None) -> "_Memo":
        """The memo of one :func:`core.estimate` call on ``points`` (validated) with ``plan``
        (and one viewpoint per point, ``views``, where the plan faces them)."""
        inputs = (_digest(points), None if normals is None else _digest(normals))
        return _Memo(self, inputs, plan, None if views is None else _digest(views))

    def _token(self, nb) -> int:
        """A number naming the neighbour graph ``nb`` while it is the one in use."""
        if nb is not self._nb:
            self._nb, self._nb_token = nb, self._nb_token + 1
            self._entries.clear()  # every later stage is keyed by the graph: the old outputs are dead
        return self._nb_token

    def _get(self, stage: str, key: tuple, compute):
        kept = self._entries.setdefault(stage, [])
        for i, (k, value) in enumerate(kept):
            if k == key:
                kept.append(kept.pop(i))  # the most recently used last
                self.reused[stage] += 1
                return value
        value = _read_only(compute())
        kept.append((key, value))
        del kept[:-self.keep]
        self.computed[stage] += 1
        return value

    def _search(self, inputs: tuple, k: int, n: int, compute):
        """The kept graph if it holds ``k`` neighbours of these points, else ``compute(k')``,
        ``k'`` = ``k`` raised to :attr:`k_max` (at most ``n``), kept instead."""
        if self._graph is not None and self._graph[0] == inputs and self._graph[1][0].k_max >= k:
            self.reused["neighbours"] += 1
            return self._graph[1]
        self._graph = self._caller = None  # the old graph goes before the new one is searched
        found = compute(min(max(k, self.k_max), n))
        self._graph = (inputs, found)
        self.computed["neighbours"] += 1
        return found

    def _given_graph(self, given, inputs: tuple, compute):
        """``compute()``'s ``(nb, order)`` for the caller's graph ``given`` on the points of
        ``inputs``, kept while the same graph is passed for them (its copy in spatial order is
        then the same graph to the stages)."""
        if self._given is None or self._given[0] is not given or self._given[1] != inputs:
            self._given = None
            self._given = (given, inputs, compute())
        return self._given[2]

    def caller_neighbours(self, order, nb, points):
        """``order.neighbours_to_caller(nb, points)`` kept with ``nb``: the results of one
        graph share one copy in the caller's order."""
        if self._caller is None or self._caller[0] is not nb:
            self._caller = (nb, _to_caller(order, nb, points, in_place=False))
        return self._caller[1]


class _Memo:
    """Runs a stage or returns its kept output; ``None`` cache: always runs."""

    def __init__(self, cache: StageCache | None, inputs: tuple, plan, views=None):
        self.cache, self.inputs, self.plan = cache, inputs, plan
        self.views = views  # the viewpoints' digest: a key of the stages that read the orientation
        self.graph = None

    def neighbours(self, compute, given):
        """The neighbour graph and its spatial order, ``compute(k)``'s ``(nb, order)`` for
        ``k`` neighbours: from ``given`` (the caller's graph) as is, else a kept search with
        head room (:attr:`StageCache.k_max`); later stages are keyed by the graph ``nb`` itself."""
        if self.cache is None:
            nb, order = compute(self.plan.k_search)
        elif given is not None:
            nb, order = self.cache._given_graph(given, self.inputs, lambda: compute(self.plan.k_search))
        else:
            nb, order = self.cache._search(self.inputs[0], self.plan.k_search, self.plan.n_points, compute)
        self.graph = None if self.cache is None else self.cache._token(nb)
        return nb, order

    def __call__(self, stage: str, compute):
        return compute() if self.cache is None else self._run(stage, compute)

    def _run(self, stage: str, compute):
        names = STAGE_FIELDS[stage]
        fields = tuple(_field(self.plan, name) for name in names)
        if "orientation" in names or ("viewpoint" in names and fields[names.index("viewpoint")] is not None):
            fields += (self.views,)
        return self.cache._get(stage, (self.inputs, self.graph, fields), compute)


def memo(cache: StageCache | None, points, normals, plan, views=None) -> _Memo:
    """The memo :func:`core.estimate` runs its stages through (a pass-through without a cache)."""
    if cache is None:
        return _Memo(None, (), plan)
    return checked(cache).bind(points, normals, plan, views)


def checked(cache):
    """``cache`` if it is a :class:`StageCache` or None, else a ValueError naming it."""
    if cache is not None and not isinstance(cache, StageCache):
        raise ValueError(f"cache must be a core.stage_cache.StageCache or None, got {type(cache).__name__}")
    return cache


def caller_neighbours(cache: StageCache | None, order, nb, points):
    """The neighbour graph ``nb`` (on the points in spatial ``order``) as neighbours of the
    caller's ``points``: reordered in place without a cache, kept with it
    (:meth:`StageCache.caller_neighbours`)."""
    if cache is None:
        return _to_caller(order, nb, points, in_place=True)
    return cache.caller_neighbours(order, nb, points)


def _to_caller(order, nb, points, *, in_place):
    """``order.neighbours_to_caller``, put off until the whole graph is read
    (:class:`core.wide_neighbours.LazyNeighbours`): most callers never read a result's
    graph (converting it was 1.1 s of a 1M-point estimate), and a graph that holds only
    its first columns (:class:`core.wide_neighbours.WidenableNeighbours`) would be searched
    in full for it. ``take`` and ``rows`` are served from ``nb`` in the caller's order."""
    if order.order is None:
        return nb
    return LazyNeighbours(points, nb, order.order, lambda: order.neighbours_to_caller(nb, points, in_place=in_place))


def _field(plan, name: str):
    if name == "viewpoint":  # a viewpoint (or each point's) where k="auto" reads it, else None
        return repr(plan.orientation) if plan.auto and plan.faces_viewpoints else None
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
