"""Initial normals by weighted PCA (paper eqs. 13–14) and global orientation (Hoppe et al. 1992)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

from .linalg import smallest_eigvec3
from .methods.normal_fit import THETA_REACH, theta

_CHUNK = 65_536
#: a neighbourhood is treated as collinear (no normal) when its middle eigenvalue is this
#: small relative to the largest
COLLINEAR = 1e-10


def pca_normals(points, idx, dist, *, progress=None):
    """Weighted-PCA normals (eqs. 13–14).

    n(q) minimises sum_i <n, p_i - q>^2 theta(|p_i - q| / h), theta(x) = (1 - x^2)^4,
    with h = 1.1 x the distance to the k-th neighbour so no neighbour gets weight 0.

    Returns
    -------
    normals : (N, 3) unit vectors (NaN rows where the neighbourhood has no normal:
        all duplicates or collinear).
    ok : (N,) bool.
    """
    n, k = idx.shape
    normals = np.full((n, 3), np.nan)
    ok = np.zeros(n, dtype=bool)
    for start in range(0, n, _CHUNK):
        stop = min(n, start + _CHUNK)
        rows = slice(start, stop)
        d = points[idx[rows]] - points[start:stop, None, :]
        h = dist[rows, -1] * THETA_REACH
        good = h > 0
        h = np.where(good, h, 1.0)
        wt = theta(dist[rows] / h[:, None])
        ds = d / h[:, None, None]  # scale-free, so the collinearity test is too
        C = np.einsum("mk,mki,mkj->mij", wt, ds, ds)
        vec, vals = smallest_eigvec3(C)
        good &= vals[:, 1] > COLLINEAR * np.maximum(vals[:, 2], 1e-300)
        normals[start:stop] = np.where(good[:, None], vec, np.nan)
        ok[rows] = good
        if progress is not None:
            progress(stop / n, "normals")
    return normals, ok


def orient_normals(points, normals, idx, mode, *, ok=None):
    """Make normal signs globally consistent.

    Parameters
    ----------
    mode : "propagate" (Hoppe et al. 1992: flip along a minimum spanning tree of the
        neighbour graph weighted by 1 - |n_i . n_j|, seeded so the highest point's normal
        points up), "outward" (propagate, then flip each connected component so most
        normals point away from its centroid), "keep", or a (3,) viewpoint array (each
        normal faces the viewpoint).
    """
    normals = normals.copy()
    if ok is None:
        ok = np.isfinite(normals).all(axis=1)
    if isinstance(mode, str) and mode == "keep":
        return normals
    if not isinstance(mode, str):
        view = np.asarray(mode, dtype=float)
        flip = np.einsum("ij,ij->i", normals, view - points) < 0
        normals[flip] *= -1
        return normals
    components = _propagate(points, normals, idx, ok)
    if mode == "outward":
        _outward(points, normals, components)
    return normals


def _graph(normals, idx, ok):
    n, k = idx.shape
    rows = np.repeat(np.arange(n), k - 1)
    cols = idx[:, 1:].ravel().astype(np.int64)
    keep = ok[rows] & ok[cols] & (rows != cols)
    rows, cols = rows[keep], cols[keep]
    cos = np.abs(np.einsum("ij,ij->i", normals[rows], normals[cols]))
    weight = 1.0 - cos + 1e-9  # > 0: csgraph treats explicit zeros as missing edges
    g = coo_matrix((weight, (rows, cols)), shape=(n, n)).tocsr()
    return g.maximum(g.T)


def _propagate(points, normals, idx, ok):
    """Orient along the minimum spanning tree of every component, in one BFS.

    A virtual root joined to each component's seed lets one traversal cover all of them.
    """
    n = len(normals)
    tree = minimum_spanning_tree(_graph(normals, idx, ok))
    _, labels = connected_components(tree, directed=False)
    components = _components(labels, ok)
    seeds = np.array([m[np.argmax(points[m, 2])] for m in components], dtype=np.int64)
    if len(seeds) == 0:
        return components
    flip = normals[seeds, 2] < 0
    normals[seeds[flip]] *= -1
    tree = tree.tocoo()
    rows = np.concatenate([tree.row, np.full(len(seeds), n)])
    cols = np.concatenate([tree.col, seeds])
    ext = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    order, pred = breadth_first_order(ext, n, directed=False, return_predecessors=True)
    ext_normals = np.vstack([normals, np.zeros((1, 3))])
    _flip_along_tree(ext_normals, order, pred)
    normals[:] = ext_normals[:n]
    return components


def _components(labels, ok):
    """Member indices of each connected component made of points with a normal."""
    order = np.argsort(labels, kind="stable")
    bounds = np.flatnonzero(np.diff(labels[order])) + 1
    return [m for m in np.split(order, bounds) if ok[m[0]]]


def _outward(points, normals, components):
    """Flip whole components so that most normals point away from the component centroid."""
    for members in components:
        centre = points[members].mean(axis=0)
        out = np.einsum("ij,ij->i", normals[members], points[members] - centre)
        if np.sum(np.sign(out)) < 0:
            normals[members] *= -1


def _flip_along_tree(normals, order, pred):
    """Give every node the sign that agrees with its tree parent, by pointer jumping."""
    child = order[1:]
    parent = pred[child]
    rel = np.ones(len(normals), dtype=np.int8)
    rel[child] = np.where(np.einsum("ij,ij->i", normals[child], normals[parent]) < 0, -1, 1)
    up = np.arange(len(normals))
    up[child] = parent
    sign = rel.copy()
    # after the loop, sign[i] = product of rel along the path from i to the root
    while True:
        nxt = up[up]
        if np.array_equal(nxt, up):
            break
        sign = sign * sign[up]
        up = nxt
    normals[order] *= sign[order][:, None]
