"""Connected components of a list of pairs: the places of near copies
(:mod:`core.duplicates`), the parts of a stacked frame's clump (:mod:`core.clumps`) and
the regions of a volume (:mod:`core.volumetric`)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["pair_components"]


def pair_components(n: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """(n,) the component of each of ``n`` nodes that the pairs ``rows[i]``-``cols[i]``
    join (undirected; a node in no pair is a component of its own), numbered 0, 1, ...
    (:func:`scipy.sparse.csgraph.connected_components`)."""
    pairs = coo_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(n, n))
    return connected_components(pairs, directed=False)[1]
