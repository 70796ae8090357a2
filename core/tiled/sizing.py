"""How many tiles: the fewest work for the workers within the memory budget, with the halo
each tile will load measured on the cloud's sample rather than assumed.

A tile loads its own points and every point its answers depend on (:mod:`.halo`): with an
integer k a few k-neighbour rings, with k="auto" a chain of up to 15 rings of the largest
candidate (4 passes, anchored fits). That margin is estimated on the sample as the task's
first margin is (:func:`core.tiled.halo.first_margin`: the 99th percentile of the k-th
neighbour distance times the rings), each candidate split of the sample is grown by it,
and the points in the grown boxes are what a tile holds. A tile count is feasible when
its largest tile fits the budget; among those within 15 % of the best estimated time (tiles
per worker x their loaded points) and of the least work (all tiles' loaded points), the most
tiles win (a slow tile then leaves the others less idle; tiles hold less memory).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .halo import first_margin
from .plan import make_plan
from .task import tile_chain

#: sample points the margin and the loads are measured on
_PROBE, _COUNTED = 2_000, 20_000
#: a tile count within this factor of the best estimated time, with more tiles, is taken
_NEAR_BEST = 1.15
#: tiles of fewer points than this are taken only when no larger tiles fit the memory (each
#: task costs a process's reads and set-up besides its points)
MIN_POINTS = 50_000


class HaloTooWide(UserWarning):
    """The budget allows only tiles that load several times their own points."""


def margin_on_sample(sample: np.ndarray, count: int, k: int, rings: int) -> float:
    """The first margin of a tile of the whole cloud (``count`` points), from its ``sample``
    (:func:`core.tiled.halo.first_margin` on a share of the points)."""
    return first_margin(sample, k, rings, share=len(sample) / max(count, len(sample)), probe=_PROBE)


def loads(sample: np.ndarray, count: int, n_tiles: int, margin: float) -> np.ndarray:
    """Points each of ``n_tiles`` tiles (split as the run splits) holds with its halo."""
    counted = sample[:: max(1, len(sample) // _COUNTED)]  # split and counted on fewer points: the same shares
    plan = make_plan(counted, count, -(-count // n_tiles))
    per = count / len(counted)
    return np.array([per * np.count_nonzero(((counted >= lo - margin) & (counted <= hi + margin)).all(axis=1))
                     for lo, hi in zip(plan.lo, plan.hi)])


def choose_tile_points(sample, count: int, *, spec, workers: int, room: int, bytes_per_point: int,
                       least_tiles: int) -> int:
    """Points per tile for ``count`` points on ``workers`` workers, each holding at most
    ``room`` bytes of tile (``bytes_per_point`` a loaded point), at least ``least_tiles``."""
    k_max, chain = tile_chain(spec)
    margin = margin_on_sample(sample, count, k_max, max(rings for rings, _ in chain))
    options = []  # (tiles, most points a tile holds, estimated time, mean points a tile holds)
    for n in _tile_counts(count, workers, least_tiles):
        held = loads(sample, count, n, margin)
        options.append((n, held.max(), math.ceil(n / workers) * held.mean(), held.mean()))
    fits = [o for o in options if o[1] * bytes_per_point <= room]
    n, held = _best(fits, count)[:2] if fits else _least_halo(options)
    if held > 3 * count / n or not fits:
        _warn_wide(count, n, held, room, bytes_per_point)
    return -(-count // n)


def _best(fits, count):
    """The most tiles within 15 % of the best time and of the least work (tiles of fewer than
    :data:`MIN_POINTS` only as many as memory needs)."""
    fits = [o for o in fits if count / o[0] >= MIN_POINTS] or fits[:1]
    wall = min(o[2] for o in fits)
    work = min(o[0] * o[3] for o in fits)
    near = [o for o in fits if o[2] <= _NEAR_BEST * wall and o[0] * o[3] <= _NEAR_BEST * work]
    return max(near or fits, key=lambda o: o[0])


def _least_halo(options):
    """When no tiling fits the room: the least held (to 2 digits), then the least work."""
    return min(options, key=lambda o: (float(f"{o[1]:.2g}"), o[0] * o[3]))[:2]


def _tile_counts(count: int, workers: int, least: int) -> list[int]:
    """Tile counts to try: from ``least`` (what memory needs without halos) up by ~25 % steps
    to 3 tiles a worker or 8 x ``least`` (tiles of 1000 points at least), and the workers'
    multiples."""
    most = max(least, min(count // 1000, max(3 * workers, 8 * least)))
    found = {min(most, max(least, w * workers)) for w in (1, 2, 3)}
    n = max(1, least)
    while n <= most:
        found.add(n)
        n = max(n + 1, int(n * 1.25))
    return sorted(found)


def _warn_wide(count, n, held, room, bytes_per_point) -> None:
    need = held * bytes_per_point
    warnings.warn(HaloTooWide(
        f"tiles of {count // n} points each hold about {held:.0f} points with their halos (the neighbourhoods "
        f"their answers depend on reach that far): {need / 1e9:.2f} GB against {room / 1e9:.2f} GB of room per "
        "worker; a larger --memory (memory=) allows larger tiles with less halo, and a cloud that fits in memory "
        "is estimated whole, with the same answer, without tile options (core.estimate)"), stacklevel=3)
