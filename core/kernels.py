"""Compiled inner loops (numba, ``nogil``): the hot paths of a large estimate.

Each kernel is a plain loop over points doing what the numpy reference in the
docstring says; they release the GIL so a GUI thread keeps running.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

_OPTS = dict(cache=True, nogil=True)
#: points per parallel work item (scratch arrays are allocated once per block)
_BLOCK = 256


@njit(**_OPTS, inline="always")
def _theta(x):
    """Eq. 14: (1 - x^2)^4 for x < 1, else 0."""
    if x >= 1.0:
        return 0.0
    t = 1.0 - x * x
    return t * t * t * t


@njit(**_OPTS)
def _smallest_eigvec_sym3(a00, a01, a02, a11, a12, a22):
    """Eigenvalues (ascending) of a symmetric 3x3 and the unit eigenvector of the smallest.

    Closed-form eigenvalues (Smith 1961); the eigenvector is the largest cross product of
    two rows of A - l_min I. Returns (l0, l1, l2, x, y, z); NaN vector if A = c I.
    """
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1
    if p2 <= 0.0:
        return q, q, q, math.nan, math.nan, math.nan
    p = math.sqrt(p2 / 6.0)
    if p * p * p == 0.0:  # harden: underflows for entries below ~1e-103; no direction then
        return q, q, q, math.nan, math.nan, math.nan
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
    ox = oy = oz = 0.0
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
            ox, oy, oz = x, y, z
    s = math.sqrt(best)
    if not s > 0.0:
        return l0, l1, l2, math.nan, math.nan, math.nan
    return l0, l1, l2, ox / s, oy / s, oz / s


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
        l0, l1, l2, x, y, z = _smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
        if l1 > collinear * max(l2, 1e-300) and l1 > l0 and math.isfinite(x):
            normals[i, 0], normals[i, 1], normals[i, 2] = x, y, z
            ok[i] = True


#: share of a ring of neighbours that may lie off the tangent graph before k stops growing
FOLD_FRACTION = 0.2
#: a neighbour whose normal turns more than 70 degrees from the local mean normal is off the graph
FOLD_COS = 0.34
#: heights within this many RMS heights of the smallest neighbourhood are noise, not a fold
FOLD_NOISE = 3.0
#: fewest off-graph neighbours that make a fold (a few turned normals in a small ring are noise)
FOLD_MIN_BAD = 3
#: most monomials of the normal fit (degree 3: 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3)
MAX_TERMS = 10
# rows of the per-block vector scratch of the NF kernels
_BX, _BY, _CX, _CY, _C1, _C2, _D, _E = range(8)


@njit(**_OPTS, inline="always")
def n_terms(degree):
    """Monomials of a bivariate polynomial of ``degree``."""
    return (degree + 1) * (degree + 2) // 2


@njit(**_OPTS, inline="always")
def _poly_row(u, v, degree, row):
    """Monomials of (u, v) by total degree: 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3."""
    row[0] = 1.0
    prev = 0
    c = 1
    for d in range(1, degree + 1):
        for b in range(d):
            row[c] = row[prev + b] * u
            c += 1
        row[c] = row[prev + d - 1] * v
        c += 1
        prev += d


@njit(**_OPTS)
def _cholesky(G, p, rcond, d, L):
    """Cholesky factor L of the equilibrated p x p matrix G (lower triangle used; unit
    diagonal after scaling by d = sqrt(diag G)). False when a pivot is <= rcond
    (rank deficient: too few or collinear neighbours for the polynomial)."""
    for a in range(p):
        if not G[a, a] > 0.0:
            return False
        d[a] = math.sqrt(G[a, a])
    for a in range(p):
        for c in range(a + 1):
            s = G[a, c] / (d[a] * d[c])
            for e in range(c):
                s -= L[a, e] * L[c, e]
            if a == c:
                if not s > rcond:
                    return False
                L[a, a] = math.sqrt(s)
            else:
                L[a, c] = s / L[c, c]
    return True


@njit(**_OPTS)
def _chol_solve(L, d, p, b, x):
    """x = G^-1 b with the factor of :func:`_cholesky` (x must not alias b)."""
    for a in range(p):
        s = b[a] / d[a]
        for e in range(a):
            s -= L[a, e] * x[e]
        x[a] = s / L[a, a]
    for a in range(p - 1, -1, -1):
        s = x[a]
        for e in range(a + 1, p):
            s -= L[e, a] * x[e]
        x[a] = s / L[a, a]
    for a in range(p):
        x[a] /= d[a]


@njit(**_OPTS)
def _fit_scratch(kmax):
    """Per-block scratch of the NF solves: monomials R, the vectors of :func:`_solve`
    (rows _BX.._E), the normal matrix G, its factor L and the sums acc."""
    R = np.empty((MAX_TERMS, kmax))
    vec = np.zeros((_E + 1, MAX_TERMS))
    G = np.zeros((MAX_TERMS, MAX_TERMS))
    L = np.zeros((MAX_TERMS, MAX_TERMS))
    acc = np.zeros(5)
    return R, vec, G, L, acc


@njit(**_OPTS)
def _monomials(u, v, n, degree, R):
    """R[:, j] = the monomials (:func:`_poly_row`) of neighbour j < n, once per point:
    every reweighting and every nested size reuses them."""
    for j in range(n):
        _poly_row(u[j], v[j], degree, R[:, j])


@njit(cache=True, nogil=True, fastmath=True)
def _accumulate(R, X, Y, wt, j0, j1, degree, vec, G, acc):
    """Add neighbours j0..j1-1 to the weighted normal equations of X and Y on the
    monomials R (G lower triangle, right-hand sides vec[_BX], vec[_BY]) and to acc =
    (sum w, sum w X^2, sum w Y^2). Sums run over neighbours innermost (vectorised), or
    all in one pass for degree 1, whose few sums over short neighbourhoods gain nothing
    from vectors."""
    if degree == 1:
        s1 = su = sv = suu = suv = svv = x0 = x1 = x2 = y0 = y1 = y2 = xx = yy = 0.0
        for j in range(j0, j1):
            w = wt[j]
            uj, vj, Xj, Yj = R[1, j], R[2, j], X[j], Y[j]
            wu, wv = w * uj, w * vj
            s1 += w
            su += wu
            sv += wv
            suu += wu * uj
            suv += wu * vj
            svv += wv * vj
            x0 += w * Xj
            x1 += wu * Xj
            x2 += wv * Xj
            y0 += w * Yj
            y1 += wu * Yj
            y2 += wv * Yj
            xx += w * Xj * Xj
            yy += w * Yj * Yj
        G[0, 0] += s1
        G[1, 0] += su
        G[2, 0] += sv
        G[1, 1] += suu
        G[2, 1] += suv
        G[2, 2] += svv
        vec[_BX, 0] += x0
        vec[_BX, 1] += x1
        vec[_BX, 2] += x2
        vec[_BY, 0] += y0
        vec[_BY, 1] += y1
        vec[_BY, 2] += y2
        acc[0] += s1
        acc[1] += xx
        acc[2] += yy
        return
    p = n_terms(degree)
    for a in range(p):
        sx = 0.0
        sy = 0.0
        for j in range(j0, j1):
            t = wt[j] * R[a, j]
            sx += t * X[j]
            sy += t * Y[j]
        vec[_BX, a] += sx
        vec[_BY, a] += sy
        for c in range(a + 1):
            g = 0.0
            for j in range(j0, j1):
                g += wt[j] * R[a, j] * R[c, j]
            G[a, c] += g
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    for j in range(j0, j1):
        s0 += wt[j]
        s1 += wt[j] * X[j] * X[j]
        s2 += wt[j] * Y[j] * Y[j]
    acc[0] += s0
    acc[1] += s1
    acc[2] += s2


@njit(**_OPTS)
def _reset(degree, vec, G, acc):
    p = n_terms(degree)
    G[:p, :p] = 0.0
    vec[_BX, :p] = 0.0
    vec[_BY, :p] = 0.0
    acc[:] = 0.0


@njit(**_OPTS)
def _solve_linear(rcond, vec, G, acc):
    """:func:`_solve` for degree 1 (the paper's eqs. 25–26) by the closed-form inverse of
    the equilibrated 3x3 matrix: the common case, and twice as fast as a Cholesky."""
    s1, su, sv, suu, suv, svv = G[0, 0], G[1, 0], G[2, 0], G[1, 1], G[2, 1], G[2, 2]
    if not (s1 > 0.0 and suu > 0.0 and svv > 0.0):
        return False
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
        return False
    # G = D Gs D, so G^-1 = D^-1 adj(Gs) D^-1 / det
    e00 = i00 / (det * d0 * d0)
    e01 = i01 / (det * d0 * d1)
    e02 = i02 / (det * d0 * d2)
    e11 = i11 / (det * d1 * d1)
    e12 = i12 / (det * d1 * d2)
    e22 = i22 / (det * d2 * d2)
    x0, x1, x2 = vec[_BX, 0], vec[_BX, 1], vec[_BX, 2]
    y0, y1, y2 = vec[_BY, 0], vec[_BY, 1], vec[_BY, 2]
    vec[_CX, 0] = e00 * x0 + e01 * x1 + e02 * x2
    vec[_CX, 1] = e01 * x0 + e11 * x1 + e12 * x2
    vec[_CX, 2] = e02 * x0 + e12 * x1 + e22 * x2
    vec[_CY, 0] = e00 * y0 + e01 * y1 + e02 * y2
    vec[_CY, 1] = e01 * y0 + e11 * y1 + e12 * y2
    vec[_CY, 2] = e02 * y0 + e12 * y1 + e22 * y2
    vec[_C1, 0], vec[_C1, 1], vec[_C1, 2] = e01, e11, e12
    vec[_C2, 0], vec[_C2, 1], vec[_C2, 2] = e02, e12, e22
    acc[3] = max(acc[1] - (vec[_CX, 0] * x0 + vec[_CX, 1] * x1 + vec[_CX, 2] * x2), 0.0)
    acc[4] = max(acc[2] - (vec[_CY, 0] * y0 + vec[_CY, 1] * y1 + vec[_CY, 2] * y2), 0.0)
    return True


@njit(**_OPTS)
def _solve(degree, rcond, vec, G, L, acc):
    """Least squares of X and Y on the monomials (eqs. 25–26 for degree 1).

    Fills vec[_CX], vec[_CY] (coefficients: constant = mu, then the slopes = W rows),
    vec[_C1], vec[_C2] (columns 1, 2 of G^-1) and acc[3], acc[4] (residual sums of
    squares of X, Y). False when G is near singular.
    """
    if degree == 1:
        return _solve_linear(rcond, vec, G, acc)
    p = n_terms(degree)
    if not _cholesky(G, p, rcond, vec[_D], L):
        return False
    _chol_solve(L, vec[_D], p, vec[_BX], vec[_CX])
    _chol_solve(L, vec[_D], p, vec[_BY], vec[_CY])
    e = vec[_E]
    e[:p] = 0.0
    e[1] = 1.0
    _chol_solve(L, vec[_D], p, e, vec[_C1])
    e[1] = 0.0
    e[2] = 1.0
    _chol_solve(L, vec[_D], p, e, vec[_C2])
    fx = fy = 0.0
    for a in range(p):
        fx += vec[_CX, a] * vec[_BX, a]
        fy += vec[_CY, a] * vec[_BY, a]
    acc[3] = max(acc[1] - fx, 0.0)
    acc[4] = max(acc[2] - fy, 0.0)
    return True


@njit(**_OPTS)
def _gather(points, normals, idx, centres, h, t1, t2, z, r, n, weighting, theta_reach, u, v, X, Y, base):
    """Neighbours 0..n-1 of centre r in its frame: offsets (u, v) / h, normal components
    (X, Y) flipped to agree with the frame's z (§4.3), and base weights (0 without a normal)."""
    i = centres[r]
    hi = h[r]
    a0, a1, a2 = t1[r, 0], t1[r, 1], t1[r, 2]
    b0, b1, b2 = t2[r, 0], t2[r, 1], t2[r, 2]
    c0, c1, c2 = z[r, 0], z[r, 1], z[r, 2]
    for j in range(n):
        q = idx[r, j]
        nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
        dx = (points[q, 0] - points[i, 0]) / hi
        dy = (points[q, 1] - points[i, 1]) / hi
        dz = (points[q, 2] - points[i, 2]) / hi
        u[j] = dx * a0 + dy * a1 + dz * a2
        v[j] = dx * b0 + dy * b1 + dz * b2
        if not math.isfinite(nx):
            X[j] = Y[j] = base[j] = 0.0
            continue
        sgn = 1.0 if nx * c0 + ny * c1 + nz * c2 >= 0.0 else -1.0
        X[j] = sgn * (nx * a0 + ny * a1 + nz * a2)
        Y[j] = sgn * (nx * b0 + ny * b1 + nz * b2)
        base[j] = 1.0
        if weighting == 1:
            base[j] = _theta(math.sqrt(dx * dx + dy * dy + dz * dz) / theta_reach)


@njit(**_OPTS)
def _slope_variances(degree, n, vec, acc):
    """Least-squares variances of W11, (W12 + W21)/2 and W22 from the residuals."""
    p = n_terms(degree)
    dof = max(acc[0] * (1.0 - p / max(n, p + 1)), 1e-12)
    sx2 = acc[3] / dof
    sy2 = acc[4] / dof
    e11, e22 = vec[_C1, 1], vec[_C2, 2]
    return sx2 * e11, 0.25 * (sx2 * e22 + sy2 * e11), sy2 * e22


@njit(**_OPTS)
def _select(a, lo, hi, kth):
    """Partially order a[lo:hi] in place so a[kth] is the value a full sort would put there."""
    while hi - lo > 1:
        pivot = a[(lo + hi) // 2]
        i, j = lo, hi - 1
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if kth <= j:
            hi = j + 1
        elif kth >= i:
            lo = i
        else:
            return
    return


@njit(**_OPTS)
def _median(a, m):
    """Median of a[:m] (reorders it), without the copy np.median makes."""
    _select(a, 0, m, m // 2)
    upper = a[m // 2]
    if m % 2:
        return upper
    _select(a, 0, m // 2, m // 2 - 1)
    return 0.5 * (upper + a[m // 2 - 1])


@njit(**_OPTS)
def _robust_weights(R, X, Y, base, n, degree, vec, kind, wt, res, tmp):
    """IRLS weights from the residuals of the current fit (Huber 1.345 or Tukey 4.685 x MAD)."""
    p = n_terms(degree)
    m = 0
    for j in range(n):
        rx = X[j]
        ry = Y[j]
        for a in range(p):
            rx -= vec[_CX, a] * R[a, j]
            ry -= vec[_CY, a] * R[a, j]
        res[j] = math.sqrt(rx * rx + ry * ry)
        if base[j] > 0.0:
            m += 1
    if m == 0:
        return
    c = 0
    for j in range(n):
        if base[j] > 0.0:
            tmp[c] = res[j]
            c += 1
    scale = max(1.4826 * _median(tmp, m), 1e-4)
    for j in range(n):
        r = res[j] / scale
        if kind == 1:  # Huber
            f = 1.0 if r <= 1.345 else 1.345 / r
        else:  # Tukey biweight
            f = (1.0 - (r / 4.685) ** 2) ** 2 if r < 4.685 else 0.0
        wt[j] = base[j] * f


@njit(**_OPTS, parallel=True)
def normal_fit(points, normals, idx, kc, h, centres, t1, t2, z, theta_reach, weighting, constraint,
               robust, irls, degree, rcond, mu, W, var, rms, spread, ok):
    """NF per point (§4.3–4.4): fit X, Y of the neighbours' normals with a polynomial in (u, v).

    kc (M,): neighbours used per point (the first kc of each row of idx). degree: 1 is
    the paper's linear model [1, u, v] (eqs. 25–26); 2 and 3 add the higher monomials, so
    the slopes at p (W) are not biased by the curving of the normal field over a wide
    neighbourhood. weighting: 0 uniform (eqs. 25–26), 1 theta of eq. 14. constraint: 0
    none, 1 Euclidean projection onto the symmetry plane (§4.4), 2 exact (Lagrange
    multiplier in the metric of the normal equations, two fixed-point iterations on mu).
    robust: 0 none, 1 Huber, 2 Tukey (``irls`` reweighting iterations). Coordinates are divided by h;
    W is returned in those units, with var (M, 3) the least-squares variances of W11,
    (W12 + W21)/2, W22 and rms (M,) the weighted RMS residual of the normal components,
    spread (M,) their weighted RMS deviation from their mean (how much the normals turn
    over the neighbourhood).
    """
    m = len(centres)
    kmax = idx.shape[1]
    n_blocks = (m + _BLOCK - 1) // _BLOCK
    for blk in prange(n_blocks):
        # scratch arrays once per block: a per-point allocation would cost more than the fit
        u = np.empty(kmax)
        v = np.empty(kmax)
        X = np.empty(kmax)
        Y = np.empty(kmax)
        base = np.empty(kmax)
        wt = np.empty(kmax)
        res = np.empty(kmax)
        tmp = np.empty(kmax)
        R, vec, G, L, acc = _fit_scratch(kmax)
        for r in range(blk * _BLOCK, min(m, (blk + 1) * _BLOCK)):
            _nf_point(points, normals, idx, kc, h, centres, t1, t2, z, theta_reach, weighting, constraint,
                      robust, irls, degree, rcond, mu, W, var, rms, spread, ok, r, u, v, X, Y, base, wt, res,
                      tmp, R, vec, G, L, acc)


@njit(**_OPTS)
def _nf_point(points, normals, idx, kc, h, centres, t1, t2, z, theta_reach, weighting, constraint,
              robust, irls, degree, rcond, mu, W, var, rms, spread, ok, r, u, v, X, Y, base, wt, res,
              tmp, R, vec, G, L, acc):
    """The NF fit of centre ``r`` (see :func:`normal_fit`), using the scratch arrays given."""
    n = kc[r]
    _gather(points, normals, idx, centres, h, t1, t2, z, r, n, weighting, theta_reach, u, v, X, Y, base)
    for j in range(n):
        wt[j] = base[j]
    _monomials(u, v, n, degree, R)
    _reset(degree, vec, G, acc)
    _accumulate(R, X, Y, wt, 0, n, degree, vec, G, acc)
    ok[r] = _solve(degree, rcond, vec, G, L, acc)
    if robust > 0:
        for _ in range(irls):
            if not ok[r]:
                break
            _robust_weights(R, X, Y, base, n, degree, vec, robust, wt, res, tmp)
            _reset(degree, vec, G, acc)
            _accumulate(R, X, Y, wt, 0, n, degree, vec, G, acc)
            ok[r] = _solve(degree, rcond, vec, G, L, acc)
    if not ok[r]:
        return
    cx0, cx1, cx2 = vec[_CX, 0], vec[_CX, 1], vec[_CX, 2]
    cy0, cy1, cy2 = vec[_CY, 0], vec[_CY, 1], vec[_CY, 2]
    if constraint == 2:
        # G^-1 a for a = (0, g1, g2, 0.. | 0, g3, g4, 0..): columns 1, 2 of G^-1 are needed
        e01, e11, e12 = vec[_C1, 0], vec[_C1, 1], vec[_C1, 2]
        e02, e22 = vec[_C2, 0], vec[_C2, 2]
        ex0, ex1, ex2, ey0, ey1, ey2 = cx0, cx1, cx2, cy0, cy1, cy2
        for _ in range(2):
            m1, m2 = cx0, cy0
            g1, g2, g3, g4 = m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2
            ax0, ax1, ax2 = e01 * g1 + e02 * g2, e11 * g1 + e12 * g2, e12 * g1 + e22 * g2
            ay0, ay1, ay2 = e01 * g3 + e02 * g4, e11 * g3 + e12 * g4, e12 * g3 + e22 * g4
            num = g1 * ex1 + g2 * ex2 + g3 * ey1 + g4 * ey2
            den = g1 * ax1 + g2 * ax2 + g3 * ay1 + g4 * ay2
            if den == 0.0:
                break
            lam = num / den
            cx0, cx1, cx2 = ex0 - lam * ax0, ex1 - lam * ax1, ex2 - lam * ax2
            cy0, cy1, cy2 = ey0 - lam * ay0, ey1 - lam * ay1, ey2 - lam * ay2
    w11, w12, w21, w22 = cx1, cx2, cy1, cy2
    if constraint == 1:
        g1, g2, g3, g4 = cx0 * cy0, -(1.0 - cy0 * cy0), 1.0 - cx0 * cx0, -cx0 * cy0
        t = (g1 * w11 + g2 * w12 + g3 * w21 + g4 * w22) / (g1 * g1 + g2 * g2 + g3 * g3 + g4 * g4)
        w11 -= t * g1
        w12 -= t * g2
        w21 -= t * g3
        w22 -= t * g4
    mu[r, 0] = cx0
    mu[r, 1] = cy0
    W[r, 0, 0] = w11
    W[r, 0, 1] = w12
    W[r, 1, 0] = w21
    W[r, 1, 1] = w22
    var[r, 0], var[r, 1], var[r, 2] = _slope_variances(degree, n, vec, acc)
    sw = max(acc[0], 1e-300)
    rms[r] = math.sqrt((acc[3] + acc[4]) / sw)
    mx, my = vec[_BX, 0] / sw, vec[_BY, 0] / sw
    spread[r] = math.sqrt(max(acc[1] / sw - mx * mx + acc[2] / sw - my * my, 0.0))


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


@njit(**_OPTS, parallel=True)
def outlier_scores(points, idx, floor, score):
    """Distance of each point from the plane of its neighbours, in units of their spread.

    The plane is the least-squares plane of the neighbours without the point itself
    (centroid and smallest principal axis); the unit is the neighbours' RMS distance to
    that plane plus ``floor`` x their mean distance to the centroid, so that a clean flat
    patch does not make every tiny offset look infinite.
    """
    n, k = idx.shape
    for i in prange(n):
        cx = cy = cz = 0.0
        m = 0
        for j in range(1, k):
            q = idx[i, j]
            cx += points[q, 0]
            cy += points[q, 1]
            cz += points[q, 2]
            m += 1
        if m < 3:
            score[i] = math.nan
            continue
        cx /= m
        cy /= m
        cz /= m
        c00 = c01 = c02 = c11 = c12 = c22 = 0.0
        spread = 0.0
        for j in range(1, k):
            q = idx[i, j]
            dx, dy, dz = points[q, 0] - cx, points[q, 1] - cy, points[q, 2] - cz
            c00 += dx * dx
            c01 += dx * dy
            c02 += dx * dz
            c11 += dy * dy
            c12 += dy * dz
            c22 += dz * dz
            spread += math.sqrt(dx * dx + dy * dy + dz * dz)
        l0, l1, l2, x, y, z = _smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
        if not math.isfinite(x):
            score[i] = math.nan
            continue
        d = abs((points[i, 0] - cx) * x + (points[i, 1] - cy) * y + (points[i, 2] - cz) * z)
        unit = math.sqrt(max(l0, 0.0) / m) + floor * spread / m
        score[i] = d / unit if unit > 0.0 else (0.0 if d == 0.0 else math.inf)


@njit(**_OPTS)
def _local_reference(points, normals, idx, r, n, z, ref):
    """What a fold of centre r is judged against, from its neighbours 0..n-1 (the
    smallest neighbourhood): ``ref`` gets their centroid (0:3) and mean normal (3:6,
    sign-aligned with z), which unlike the centre's own point and normal are not thrown
    far off by noise, the RMS height of the neighbours over that plane (6: the scale of
    the position noise, plus a little curvature) and the share of them whose normals
    turn more than FOLD_COS from the mean (7: what the normal noise alone does)."""
    c0, c1, c2 = z[r, 0], z[r, 1], z[r, 2]
    ref[:] = 0.0
    seen = 0
    for j in range(n):
        q = idx[r, j]
        nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
        if not math.isfinite(nx):
            continue
        sgn = 1.0 if nx * c0 + ny * c1 + nz * c2 >= 0.0 else -1.0
        for a in range(3):
            ref[a] += points[q, a]
            ref[3 + a] += sgn * normals[q, a]
        seen += 1
    norm = math.sqrt(ref[3] ** 2 + ref[4] ** 2 + ref[5] ** 2)
    if seen == 0 or norm == 0.0:
        ref[0:3] = points[idx[r, 0]]
        ref[3], ref[4], ref[5] = c0, c1, c2
        ref[6] = ref[7] = 0.0
        return
    ref[0:3] /= seen
    ref[3:6] /= norm
    height2 = 0.0
    turned = 0
    for j in range(n):
        q = idx[r, j]
        if not math.isfinite(normals[q, 0]):
            continue
        w = 0.0
        facing = 0.0
        for a in range(3):
            w += (points[q, a] - ref[a]) * ref[3 + a]
            facing += normals[q, a] * ref[3 + a]
        height2 += w * w
        if facing < FOLD_COS:
            turned += 1
    ref[6] = math.sqrt(height2 / seen)
    ref[7] = turned / seen


@njit(**_OPTS)
def _folded(points, normals, idx, r, j0, j1, ref):
    """Whether the ring of neighbours j0..j1-1 of centre r has left the graph of a
    function over the local plane ``ref`` (see :func:`_local_reference`): more of it
    than FOLD_FRACTION (plus the share of the smallest neighbourhood) seen more than 45
    degrees above or below the plane (beyond FOLD_NOISE x the noise height), or with
    normals turned more than 70 degrees: the far side of a thin part, another sheet, a
    crease. No model of the normal field fits there, and the residual variance such a
    ring adds would hide the bias from the ICI test. Judged against the neighbourhood,
    not the centre alone, so a noisy centre is not taken for a fold."""
    margin = FOLD_NOISE * ref[6]
    bad = 0
    seen = 0
    for j in range(j0, j1):
        q = idx[r, j]
        if not math.isfinite(normals[q, 0]):  # no normal (or a known outlier): not counted
            continue
        seen += 1
        w = 0.0
        d2 = 0.0
        facing = 0.0
        for a in range(3):
            d = points[q, a] - ref[a]
            w += d * ref[3 + a]
            d2 += d * d
            facing += normals[q, a] * ref[3 + a]
        lift = max(abs(w) - margin, 0.0)
        if 2.0 * lift * lift > d2 or facing < FOLD_COS:
            bad += 1
    return bad >= FOLD_MIN_BAD and bad > (FOLD_FRACTION + ref[7]) * seen


@njit(**_OPTS)
def _fold_limit(points, normals, idx, r, ks, ref):
    """How many of the candidate sizes ``ks`` stay on the graph: the first ring that folds
    ends them, if the next ring folds too (a fold persists as the neighbourhood grows;
    a ring that noise alone makes look folded is seldom followed by another). The last
    ring has no ring beyond it and ends them on its own."""
    before = False
    for c in range(1, len(ks)):
        folded = _folded(points, normals, idx, r, ks[c - 1], ks[c], ref)
        if before and folded:
            return c - 1
        before = folded
    return len(ks) - 1 if before else len(ks)


@njit(**_OPTS, parallel=True)
def choose_scales(points, normals, idx, h, centres, t1, t2, z, ks, degree, gamma, rcond, chosen):
    """Intersection of confidence intervals over nested neighbourhoods (see core.scale).

    One pass over each centre's ks[-1] neighbours: the NF sums (polynomial of
    ``degree``) grow neighbour by neighbour and are solved at each candidate size ks[c]
    (uniform weights, no constraint, lengths in units of h = the distance to the largest
    neighbourhood). ``chosen`` gets the largest k whose interval [W - gamma s, W + gamma s]
    still meets all previous ones.
    """
    m = len(centres)
    kmax = ks[-1]
    n_blocks = (m + _BLOCK - 1) // _BLOCK
    for blk in prange(n_blocks):
        u = np.empty(kmax)
        v = np.empty(kmax)
        X = np.empty(kmax)
        Y = np.empty(kmax)
        base = np.empty(kmax)
        R, vec, G, L, acc = _fit_scratch(kmax)
        lo = np.empty(3)
        hi = np.empty(3)
        ref = np.empty(8)
        for r in range(blk * _BLOCK, min(m, (blk + 1) * _BLOCK)):
            _gather(points, normals, idx, centres, h, t1, t2, z, r, kmax, 0, 1.0, u, v, X, Y, base)
            _monomials(u, v, kmax, degree, R)
            _reset(degree, vec, G, acc)
            lo[:] = -math.inf
            hi[:] = math.inf
            pick = ks[0]
            prev = 0
            _local_reference(points, normals, idx, r, ks[0], z, ref)
            stop = _fold_limit(points, normals, idx, r, ks, ref)
            for c in range(stop):
                _accumulate(R, X, Y, base, prev, ks[c], degree, vec, G, acc)
                prev = ks[c]
                if not _solve(degree, rcond, vec, G, L, acc):
                    if c == 0:
                        continue
                    break
                v0, v1, v2 = _slope_variances(degree, ks[c], vec, acc)
                est0 = vec[_CX, 1]
                est1 = 0.5 * (vec[_CX, 2] + vec[_CY, 1])
                est2 = vec[_CY, 2]
                lo[0] = max(lo[0], est0 - gamma * math.sqrt(v0))
                hi[0] = min(hi[0], est0 + gamma * math.sqrt(v0))
                lo[1] = max(lo[1], est1 - gamma * math.sqrt(v1))
                hi[1] = min(hi[1], est1 + gamma * math.sqrt(v1))
                lo[2] = max(lo[2], est2 - gamma * math.sqrt(v2))
                hi[2] = min(hi[2], est2 + gamma * math.sqrt(v2))
                if lo[0] > hi[0] or lo[1] > hi[1] or lo[2] > hi[2]:
                    break
                pick = ks[c]
            chosen[r] = pick


@njit(**_OPTS, parallel=True)
def jet_normals(points, idx, h, centres, t1, t2, z, rcond, normals, height, ok):
    """Normals of the osculating 2-jet (Cazals & Pouget 2005) in the frames given.

    Fits w = c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2 to the neighbours (lengths / h) by
    least squares (6x6 normal equations, equilibrated, Cholesky); the normal of the graph
    at the origin is (-c1, -c2, 1) / |.|, ``height`` the RMS residual of w (in length
    units, corrected for the 6 fitted terms): the noise of the positions along the
    normal, once the quadric has taken up the curvature. Near-singular systems leave ok False.
    """
    m = len(centres)
    k = idx.shape[1]
    n_blocks = (m + _BLOCK - 1) // _BLOCK
    for blk in prange(n_blocks):
        G = np.empty((6, 6))
        L = np.empty((6, 6))
        b = np.empty(6)
        row = np.empty(6)
        d = np.empty(6)
        x = np.empty(6)
        for r in range(blk * _BLOCK, min(m, (blk + 1) * _BLOCK)):
            ok[r] = False
            i = centres[r]
            hi = h[r]
            G[:, :] = 0.0
            b[:] = 0.0
            ww = 0.0
            for j in range(k):
                q = idx[r, j]
                dx = (points[q, 0] - points[i, 0]) / hi
                dy = (points[q, 1] - points[i, 1]) / hi
                dz = (points[q, 2] - points[i, 2]) / hi
                u = dx * t1[r, 0] + dy * t1[r, 1] + dz * t1[r, 2]
                v = dx * t2[r, 0] + dy * t2[r, 1] + dz * t2[r, 2]
                w = dx * z[r, 0] + dy * z[r, 1] + dz * z[r, 2]
                _poly_row(u, v, 2, row)
                ww += w * w
                for a in range(6):
                    b[a] += row[a] * w
                    for c in range(a + 1):
                        G[a, c] += row[a] * row[c]
            if not _cholesky(G, 6, rcond, d, L):
                continue
            _chol_solve(L, d, 6, b, x)
            c1, c2 = x[1], x[2]
            nrm = math.sqrt(1.0 + c1 * c1 + c2 * c2)
            for a in range(3):
                normals[r, a] = (-c1 * t1[r, a] - c2 * t2[r, a] + z[r, a]) / nrm
            rss = ww
            for a in range(6):
                rss -= x[a] * b[a]
            height[r] = hi * math.sqrt(max(rss, 0.0) / max(k - 6, 1))
            ok[r] = True
