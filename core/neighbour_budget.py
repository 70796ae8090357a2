"""How many neighbours k="auto" may consider per point, from the memory its lists hold.

A neighbour held in a whole graph costs an index and a distance (int32 + float64, 12
bytes); :data:`core.tuning.NEIGHBOUR_BUDGET` counts such entries (~0.8 GB). k="auto"
holds :data:`core.tuning.SEARCH_WIDTH` columns of every row; wider rows are kept as
indices only (4 bytes, a third of an entry), and only at the points that fit on them
(:func:`core.wide_rows.rows_at_least`): for a size shared at anchors
(:func:`core.anchors.per_anchor`: 1 in round(k / ANCHOR_ROWS) points, from 1.5 x ANCHOR_ROWS)
about ANCHOR_ROWS per point whatever k, else every point's k. So a size is a
candidate if every point may hold it whole (:func:`whole_cap`, the rule before the
anchors) or if the points' lists at that size fit the budget on the way to a size whose
fits are shared (:func:`affordable`): a noisy cloud of 1M points reaches 320 neighbours
(56 before: its mean |H| error 0.21 against 0.022, README "Wide fits at sparse anchors");
from ~1.03M points the bridge (113 at every point) no longer fits and the sizes end at 56.
The whole graph is widened past the held columns only within :func:`whole_cap`
(:func:`core.wide_rows.rows_at_least`, the initial normals).
"""

from __future__ import annotations

from .anchors import per_anchor
from .tuning import NEIGHBOUR_BUDGET, SEARCH_WIDTH

#: an index-only row entry against a whole one (int32 against int32 + float64)
INDEX_SHARE = 4 / 12


def whole_cap(n_points: int, floor: int, k_top: int = 0) -> int:
    """The most neighbours every point of a cloud of ``n_points`` may hold (at least ``floor``);
    where fits of up to ``k_top`` are shared at anchors, less the anchors' rows held beside
    (a 1M-point cloud's initial normals: 80 -> 53 whole columns)."""
    beside = entries(k_top) - SEARCH_WIDTH if per_anchor(k_top) >= 2 else 0.0
    return min(n_points, max(floor, int(NEIGHBOUR_BUDGET / max(n_points, 1) - beside)))


def entries(k: int) -> float:
    """Whole-entry equivalents per point that fits of up to ``k`` neighbours hold (module)."""
    if k <= SEARCH_WIDTH:
        return float(k)
    per = per_anchor(k)
    rows = k / per if per >= 2 else k  # the anchors' rows spread over the points, or every point's
    return SEARCH_WIDTH + INDEX_SHARE * rows


def affordable(sizes, n_points: int, floor: int) -> tuple[int, ...]:
    """The first of ``sizes`` (ascending) up to ``n_points`` that a cloud of ``n_points`` may
    consider: those within :func:`whole_cap`, then while ``n_points x entries(k)`` fits the
    budget, if they reach a size shared at anchors (else they end at the whole cap)."""
    cap, kept = whole_cap(n_points, floor), []
    for k in sizes:
        if k > n_points or (k > cap and n_points * entries(k) > NEIGHBOUR_BUDGET):
            break
        kept.append(k)
    while kept and kept[-1] > cap and per_anchor(kept[-1]) < 2:  # past the whole graph only on the way to
        kept.pop()  # shared sizes: alone, every point would fit on its index rows (1.1M at 0.5 spacing: 50 -> 71 s)
    return tuple(kept)
