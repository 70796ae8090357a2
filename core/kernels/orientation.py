"""Consistent normal orientation (Hoppe et al. 1992): Prim's minimum spanning tree with a binary heap."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._base import OPTS


@njit(**OPTS)
def _sym_adjacency(idx, ok):
    """CSR of the symmetrised kNN graph over points with a normal (self loops dropped)."""
    n, k = idx.shape
    deg = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        if not ok[i]:
            continue
        for j in range(1, k):
            q = idx[i, j]
            if q != i and ok[q]:
                deg[i + 1] += 1
                deg[q + 1] += 1
    for i in range(n):
        deg[i + 1] += deg[i]
    adj = np.empty(deg[n], dtype=np.int64)
    fill = deg[:-1].copy()
    for i in range(n):
        if not ok[i]:
            continue
        for j in range(1, k):
            q = idx[i, j]
            if q != i and ok[q]:
                adj[fill[i]] = q
                fill[i] += 1
                adj[fill[q]] = i
                fill[q] += 1
    return deg, adj


@njit(**OPTS)
def _heap_push(hw, hn, hp, size, w, node, parent):
    c = size
    while c > 0:
        par = (c - 1) >> 1
        if hw[par] <= w:
            break
        hw[c], hn[c], hp[c] = hw[par], hn[par], hp[par]
        c = par
    hw[c], hn[c], hp[c] = w, node, parent
    return size + 1


@njit(**OPTS)
def _heap_pop(hw, hn, hp, size):
    w, node, parent = hw[0], hn[0], hp[0]
    size -= 1
    lw, ln, lp = hw[size], hn[size], hp[size]
    c = 0
    while True:
        ch = 2 * c + 1
        if ch >= size:
            break
        if ch + 1 < size and hw[ch + 1] < hw[ch]:
            ch += 1
        if hw[ch] >= lw:
            break
        hw[c], hn[c], hp[c] = hw[ch], hn[ch], hp[ch]
        c = ch
    hw[c], hn[c], hp[c] = lw, ln, lp
    return w, node, parent, size


@njit(**OPTS)
def propagate_orientation(z_order, normals, idx, ok, labels):
    """Hoppe et al. (1992): orient along a minimum spanning tree (Prim) of the kNN graph.

    Edge cost 1 - |n_i . n_j|. Each connected component is seeded at its highest point
    (z_order lists points by decreasing z), whose normal is made to point +z. Flips
    ``normals`` in place, writes a component label per point (-1 without a normal), and
    returns the number of components.
    """
    n = len(normals)
    deg, adj = _sym_adjacency(idx, ok)
    cap = len(adj) + 1
    hw = np.empty(cap)
    hn = np.empty(cap, dtype=np.int64)
    hp = np.empty(cap, dtype=np.int64)
    done = np.zeros(n, dtype=np.bool_)
    best = np.full(n, np.inf)  # cheapest edge seen into each node: push only improvements
    for i in range(n):
        labels[i] = -1
    comp = 0
    for s in z_order:
        if done[s] or not ok[s]:
            continue
        if normals[s, 2] < 0.0:
            normals[s, 0], normals[s, 1], normals[s, 2] = -normals[s, 0], -normals[s, 1], -normals[s, 2]
        size = _heap_push(hw, hn, hp, 0, 0.0, s, s)
        while size > 0:
            _, node, parent, size = _heap_pop(hw, hn, hp, size)
            if done[node]:
                continue
            done[node] = True
            labels[node] = comp
            d = (normals[node, 0] * normals[parent, 0] + normals[node, 1] * normals[parent, 1]
                 + normals[node, 2] * normals[parent, 2])
            if d < 0.0:
                normals[node, 0], normals[node, 1], normals[node, 2] = (
                    -normals[node, 0], -normals[node, 1], -normals[node, 2])
            for e in range(deg[node], deg[node + 1]):
                q = adj[e]
                if done[q]:
                    continue
                c = 1.0 - abs(normals[node, 0] * normals[q, 0] + normals[node, 1] * normals[q, 1]
                              + normals[node, 2] * normals[q, 2])
                if c < best[q]:
                    best[q] = c
                    size = _heap_push(hw, hn, hp, size, c, q, node)
        comp += 1
    return comp
