"""Compiled inner loops (numba, ``nogil``): the hot paths of a large estimate.

Each kernel is a plain loop over points doing what the numpy reference in the
docstring says; they release the GIL so a GUI thread keeps running.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

_OPTS = dict(cache=True, nogil=True)


@njit(**_OPTS, inline="always")
def _theta(x):
    """Eq. 14: (1 - x^2)^4 for x < 1, else 0."""
    if x >= 1.0:
        return 0.0
    t = 1.0 - x * x
    return t * t * t * t


@njit(**_OPTS)
def _smallest_eigvec_sym3(a00, a01, a02, a11, a12, a22, out):
    """Eigenvalues (ascending) of a symmetric 3x3 and the unit eigenvector of the smallest.

    Closed-form eigenvalues (Smith 1961); the eigenvector is the largest cross product of
    two rows of A - l_min I. Returns (l0, l1, l2); ``out`` receives the vector.
    """
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1
    if p2 <= 0.0:
        out[0] = math.nan
        out[1] = math.nan
        out[2] = math.nan
        return q, q, q
    p = math.sqrt(p2 / 6.0)
    det = (
        b00 * (b11 * b22 - a12 * a12)
        - a01 * (a01 * b22 - a12 * a02)
        + a02 * (a01 * a12 - b11 * a02)
    )
    r = det / (2.0 * p * p * p)
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    l2 = q + 2.0 * p * math.cos(phi)
    l0 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    l1 = 3.0 * q - l2 - l0
    r0x, r0y, r0z = a00 - l0, a01, a02
    r1x, r1y, r1z = a01, a11 - l0, a12
    r2x, r2y, r2z = a02, a12, a22 - l0
    best = -1.0
    for c in range(3):
        if c == 0:
            x, y, z = r0y * r1z - r0z * r1y, r0z * r1x - r0x * r1z, r0x * r1y - r0y * r1x
        elif c == 1:
            x, y, z = r0y * r2z - r0z * r2y, r0z * r2x - r0x * r2z, r0x * r2y - r0y * r2x
        else:
            x, y, z = r1y * r2z - r1z * r2y, r1z * r2x - r1x * r2z, r1x * r2y - r1y * r2x
        nn = x * x + y * y + z * z
        if nn > best:
            best = nn
            out[0], out[1], out[2] = x, y, z
    s = math.sqrt(best)
    if s > 0.0:
        out[0] /= s
        out[1] /= s
        out[2] /= s
    return l0, l1, l2


@njit(**_OPTS, parallel=True)
def pca_normals(points, idx, dist, start, reach, collinear, normals, ok):
    """Weighted-PCA normal of points ``start + i`` (eqs. 13–14), written into ``normals`` / ``ok``.

    Numpy reference: C = sum_i theta(d_i/h) (p_i - q)(p_i - q)^T / h^2, with h =
    reach x distance to the k-th neighbour; n = eigenvector of the smallest eigenvalue.
    """
    n, k = idx.shape
    for i in prange(n):
        h = dist[i, k - 1] * reach
        ok[i] = False
        normals[i, 0] = math.nan
        normals[i, 1] = math.nan
        normals[i, 2] = math.nan
        if not h > 0.0:
            continue
        c00 = c01 = c02 = c11 = c12 = c22 = 0.0
        g = start + i
        for j in range(k):
            q = idx[i, j]
            w = _theta(dist[i, j] / h)
            dx = (points[q, 0] - points[g, 0]) / h
            dy = (points[q, 1] - points[g, 1]) / h
            dz = (points[q, 2] - points[g, 2]) / h
            c00 += w * dx * dx
            c01 += w * dx * dy
            c02 += w * dx * dz
            c11 += w * dy * dy
            c12 += w * dy * dz
            c22 += w * dz * dz
        vec = np.empty(3)
        l0, l1, l2 = _smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22, vec)
        if l1 > collinear * max(l2, 1e-300) and l1 > l0 and math.isfinite(vec[0]):
            normals[i, 0], normals[i, 1], normals[i, 2] = vec[0], vec[1], vec[2]
            ok[i] = True


@njit(**_OPTS, parallel=True)
def normal_fit(points, normals, idx, h, centres, t1, t2, z, theta_reach, weighting, constraint, rcond,
               mu, W, ok):
    """NF per point (§4.3–4.4): fit X, Y of the neighbours' normals with [1, u, v].

    weighting: 0 uniform (eqs. 25–26), 1 theta of eq. 14. constraint: 0 none,
    1 Euclidean projection onto the symmetry plane (§4.4), 2 exact (Lagrange multiplier
    in the metric of the normal equations, two fixed-point iterations on mu).
    Coordinates are divided by h; W is returned in those units.
    """
    m = len(centres)
    k = idx.shape[1]
    for r in prange(m):
        i = centres[r]
        hi = h[r]
        a0, a1, a2 = t1[r, 0], t1[r, 1], t1[r, 2]
        b0, b1, b2 = t2[r, 0], t2[r, 1], t2[r, 2]
        c0, c1, c2 = z[r, 0], z[r, 1], z[r, 2]
        s1 = su = sv = suu = suv = svv = 0.0
        x0 = x1 = x2 = y0 = y1 = y2 = 0.0
        for j in range(k):
            q = idx[r, j]
            nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
            if not math.isfinite(nx):
                continue
            dx = (points[q, 0] - points[i, 0]) / hi
            dy = (points[q, 1] - points[i, 1]) / hi
            dz = (points[q, 2] - points[i, 2]) / hi
            u = dx * a0 + dy * a1 + dz * a2
            v = dx * b0 + dy * b1 + dz * b2
            X = nx * a0 + ny * a1 + nz * a2
            Y = nx * b0 + ny * b1 + nz * b2
            if nx * c0 + ny * c1 + nz * c2 < 0.0:
                X, Y = -X, -Y
            wt = 1.0
            if weighting == 1:
                wt = _theta(math.sqrt(dx * dx + dy * dy + dz * dz) / theta_reach)
            s1 += wt
            su += wt * u
            sv += wt * v
            suu += wt * u * u
            suv += wt * u * v
            svv += wt * v * v
            x0 += wt * X
            x1 += wt * u * X
            x2 += wt * v * X
            y0 += wt * Y
            y1 += wt * u * Y
            y2 += wt * v * Y
        # equilibrate, test conditioning by the determinant, invert by the adjugate
        ok[r] = False
        if not (s1 > 0.0 and suu > 0.0 and svv > 0.0):
            continue
        d0, d1, d2 = math.sqrt(s1), math.sqrt(suu), math.sqrt(svv)
        g01, g02, g12 = su / (d0 * d1), sv / (d0 * d2), suv / (d1 * d2)
        i00 = 1.0 - g12 * g12
        i01 = g02 * g12 - g01
        i02 = g01 * g12 - g02
        i11 = 1.0 - g02 * g02
        i12 = g01 * g02 - g12
        i22 = 1.0 - g01 * g01
        det = i00 + g01 * i01 + g02 * i02
        if not det > rcond:
            continue
        # inverse of G = D Gs D is D^-1 Gs^-1 D^-1
        inv = np.empty((3, 3))
        inv[0, 0] = i00 / det / (d0 * d0)
        inv[0, 1] = inv[1, 0] = i01 / det / (d0 * d1)
        inv[0, 2] = inv[2, 0] = i02 / det / (d0 * d2)
        inv[1, 1] = i11 / det / (d1 * d1)
        inv[1, 2] = inv[2, 1] = i12 / det / (d1 * d2)
        inv[2, 2] = i22 / det / (d2 * d2)
        cx = np.empty(3)
        cy = np.empty(3)
        for p in range(3):
            cx[p] = inv[p, 0] * x0 + inv[p, 1] * x1 + inv[p, 2] * x2
            cy[p] = inv[p, 0] * y0 + inv[p, 1] * y1 + inv[p, 2] * y2
        if constraint == 2:
            ex0, ex1, ex2, ey0, ey1, ey2 = cx[0], cx[1], cx[2], cy[0], cy[1], cy[2]
            for _ in range(2):
                m1, m2 = cx[0], cy[0]
                g1, g2, g3, g4 = m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2
                # G^-1 a for a = (0, g1, g2 | 0, g3, g4)
                ax0 = inv[0, 1] * g1 + inv[0, 2] * g2
                ax1 = inv[1, 1] * g1 + inv[1, 2] * g2
                ax2 = inv[2, 1] * g1 + inv[2, 2] * g2
                ay0 = inv[0, 1] * g3 + inv[0, 2] * g4
                ay1 = inv[1, 1] * g3 + inv[1, 2] * g4
                ay2 = inv[2, 1] * g3 + inv[2, 2] * g4
                num = g1 * ex1 + g2 * ex2 + g3 * ey1 + g4 * ey2
                den = g1 * ax1 + g2 * ax2 + g3 * ay1 + g4 * ay2
                if den == 0.0:
                    break
                lam = num / den
                cx[0], cx[1], cx[2] = ex0 - lam * ax0, ex1 - lam * ax1, ex2 - lam * ax2
                cy[0], cy[1], cy[2] = ey0 - lam * ay0, ey1 - lam * ay1, ey2 - lam * ay2
        w11, w12, w21, w22 = cx[1], cx[2], cy[1], cy[2]
        if constraint == 1:
            m1, m2 = cx[0], cy[0]
            g1, g2, g3, g4 = m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2
            t = (g1 * w11 + g2 * w12 + g3 * w21 + g4 * w22) / (g1 * g1 + g2 * g2 + g3 * g3 + g4 * g4)
            w11 -= t * g1
            w12 -= t * g2
            w21 -= t * g3
            w22 -= t * g4
        mu[r, 0] = cx[0]
        mu[r, 1] = cy[0]
        W[r, 0, 0] = w11
        W[r, 0, 1] = w12
        W[r, 1, 0] = w21
        W[r, 1, 1] = w22
        ok[r] = True


@njit(**_OPTS)
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


@njit(**_OPTS)
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


@njit(**_OPTS)
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


@njit(**_OPTS)
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
