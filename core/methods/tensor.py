"""CT: the curvature tensor fitted to normal differences (Batagelo & Wu 2007; Kalogerakis et al. 2007)."""

from __future__ import annotations

import numpy as np

from ..linalg import weighted_lstsq
from ._result import MethodFit
from ._sanity import turns_too_fast

DOC = (
    "Curvature tensor: with z along the normal of p, fit a symmetric 2x2 tensor "
    "[[a, b], [b, c]] so that it maps each neighbour's tangent offset (u, v) to its normal's "
    "tangent components (X, Y). NF with mu = 0 and a symmetric W (§4.4 end)."
)


def fit(chunk):
    """Fit (mu = 0, W symmetric) per point."""
    patch = chunk.patch
    u, v = patch.u, patch.v
    zero = np.zeros_like(u)
    A = np.concatenate(
        [np.stack([u, v, zero], axis=2), np.stack([zero, u, v], axis=2)], axis=1
    )
    y = np.concatenate([patch.X, patch.Y], axis=1)
    wt = np.concatenate([patch.weight, patch.weight], axis=1)
    x, ok = weighted_lstsq(A, y, wt)
    a, b, c = x[:, 0], x[:, 1], x[:, 2]
    W = np.stack([np.stack([a, b], axis=1), np.stack([b, c], axis=1)], axis=1)
    return MethodFit(np.zeros((len(u), 2)), W, ok & ~turns_too_fast(W))
