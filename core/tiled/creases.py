"""The crease flag in tiles, judged against the whole cloud's typical residual.

A crease must stand out against the cloud's typical normal-fit residual (its median,
:func:`core.creases.judge_creases`). With an integer k that residual is the final fit's,
known only once every tile has fitted: each tile keeps, for its own points, what the test
needs with another typical (:func:`core.creases.crease_residuals`, part ``.crease``) and
its sorted samples of the median (part ``.crease_samples``, each distinct position once);
the run then selects the whole cloud's median exactly (:func:`core.tiled.wholecloud.median_of`)
and re-judges the flag of every tile's rows in place (:func:`rejudge`), before the signs
and the assembly read them. The re-judging depends only on the files, so it is the same
when a run is resumed.
"""

from __future__ import annotations

import numpy as np

from ..duplicates import CopiesNeighbours
from ..tuning import CREASE_NOISE

PART, SAMPLES = ".crease", ".crease_samples"


def tile_parts(res, own: np.ndarray, nb) -> tuple[np.ndarray, np.ndarray]:
    """(the residuals of the tile's own points, their sorted samples of the median) from
    the tile's estimate ``res`` (its points ``own``; ``nb`` its graph: with copies, each
    distinct position counts once, as :func:`core.estimate` counts them)."""
    residual = res._crease_residual
    if residual is None:  # a degenerate tile: nothing valid, no crease
        residual = np.full(len(own), np.nan)
    sampled = own.copy()
    if isinstance(nb, CopiesNeighbours):
        first = np.zeros(len(own), dtype=bool)
        first[nb._merged.first] = True
        sampled &= first
    values = np.abs(residual[sampled])
    return residual[own], np.sort(values[np.isfinite(values)])


def save(store, tile: int, residual: np.ndarray, samples: np.ndarray) -> None:
    """A tile's crease parts (written before its marker)."""
    store.save_array(store.result_path(tile, PART), np.asarray(residual, dtype=np.float64))
    store.save_array(store.result_path(tile, SAMPLES), np.asarray(samples, dtype=np.float64))


def samples(store, n_tiles: int) -> list:
    """Every tile's sorted samples (memory maps), for the exact median."""
    return [np.load(store.result_path(t, SAMPLES), mmap_mode="r") for t in range(n_tiles)]


def rejudge(store, n_tiles: int, typical: float) -> int:
    """Set every tile's crease flags to the test against ``typical``; returns how many
    points changed. Only the crease column of a tile whose flags change is rewritten."""
    changed = 0
    for t in range(n_tiles):
        path = store.result_path(t)
        rows = np.load(path, mmap_mode="r")
        if len(rows) == 0:
            continue
        residual = np.load(store.result_path(t, PART))
        crease = (rows["valid"] != 0) & (residual > CREASE_NOISE * typical)
        differ = int(np.count_nonzero(crease != (rows["crease"] != 0)))
        del rows
        if differ:
            rows = np.load(path, mmap_mode="r+")
            rows["crease"] = crease
            rows.flush()
            del rows
            changed += differ
    return changed
