"""What the estimate sees at one point: its neighbours, its Darboux frame, the fitted normal
field and the local surface, the normal curvature in every direction (Euler's formula) and
the Dupin indicatrix. Pure numpy, for teaching overlays and for checking a single point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ._validate import check_result
from .point_types import TYPE_NAMES, ZERO, classify, curvature_scale

#: neighbours used when the result carries no neighbourhood (the paper's k)
DEFAULT_K = 15
#: the Gauss map ratio is a limit for small neighbourhoods: over the 226 neighbours of an
#: automatic k on the 5000-point torus it read 0.80 for |K| = 1.01; over the nearest 25,
#: 1.00 (and 0.17, 0.22, 0.74 for |K| = 0.16, 0.23, 0.80)
GAUSS_MAP_NEIGHBOURS = 25


@dataclass(frozen=True, eq=False)
class LocalFit:
    """The local picture at point ``index`` of a result.

    Attributes
    ----------
    index : int; origin : (3,) the point p.
    e1, e2, normal : (3,) the Darboux frame (unit, right-handed: e1 x e2 = n).
    k1, k2 : float, principal curvatures (k1 >= k2); kind : str, the point's type.
    neighbours : (m,) indices into the cloud (the point itself first).
    local : (m, 3) neighbour offsets (u, v, w) along (e1, e2, n).
    local_normals : (m, 3) neighbours' normals in the frame, oriented like n.
    mu, W : (2,), (2, 2) the linear normal field X = mu1 + W[0] . (u, v),
        Y = mu2 + W[1] . (u, v) fitted to ``local_normals`` (paper eqs. 15-21).
    radius : float, distance to the farthest neighbour.
    scale : float, the cloud's curvature scale (:func:`core.curvature_scale`); a curvature
        below ``ZERO * scale`` counts as zero, as in :func:`core.point_types`.
    """

    index: int
    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    normal: np.ndarray
    k1: float
    k2: float
    kind: str
    neighbours: np.ndarray
    local: np.ndarray
    local_normals: np.ndarray
    mu: np.ndarray
    W: np.ndarray
    radius: float
    scale: float

    def to_world(self, uvw) -> np.ndarray:
        """(..., 3) local (u, v, w) coordinates -> world points."""
        uvw = np.asarray(uvw, dtype=float)
        return self.origin + uvw[..., :1] * self.e1 + uvw[..., 1:2] * self.e2 + uvw[..., 2:] * self.normal

    def normal_curvature(self, theta) -> np.ndarray:
        """Euler's formula k_n(theta) = k1 cos^2 theta + k2 sin^2 theta, theta from e1 (radians)."""
        theta = np.asarray(theta, dtype=float)
        return self.k1 * np.cos(theta) ** 2 + self.k2 * np.sin(theta) ** 2

    def height(self, u, v) -> np.ndarray:
        """The osculating paraboloid w = -(k1 u^2 + k2 v^2) / 2 (it bends away from the normal
        where k > 0, like a sphere with outward normals)."""
        return -0.5 * (self.k1 * np.asarray(u) ** 2 + self.k2 * np.asarray(v) ** 2)

    def measured_curvatures(self):
        """Each neighbour's normal curvature from its normal difference (the paper's idea):
        k_j = <n_j - n_p, t_j> / |t_j|^2 along its tangent offset t_j = (u_j, v_j).

        Returns (theta, k): (m - 1,) angles from e1 in [0, pi) and curvatures.
        """
        u, v = self.local[1:, 0], self.local[1:, 1]
        X, Y = self.local_normals[1:, 0], self.local_normals[1:, 1]
        r2 = u * u + v * v
        ok = r2 > 1e-24
        theta = np.mod(np.arctan2(v[ok], u[ok]), np.pi)
        return theta, (X[ok] * u[ok] + Y[ok] * v[ok]) / r2[ok]

    def gauss_map_ratio(self) -> float:
        """Area of the neighbours' normals on the unit sphere over the area of the neighbours
        on the surface (both convex hulls, in the tangent plane), over the ``GAUSS_MAP_NEIGHBOURS``
        nearest: about |K| for a small neighbourhood, Gauss's own definition of the curvature.
        NaN if either is degenerate."""
        from scipy.spatial import ConvexHull, QhullError

        m = GAUSS_MAP_NEIGHBOURS
        try:
            spread = ConvexHull(self.local_normals[:m, :2]).volume  # 2D "volume" is the area
            patch = ConvexHull(self.local[:m, :2]).volume
        except (QhullError, ValueError):
            return float("nan")
        return float(spread / patch) if patch > 0 else float("nan")

    def fitted_normals(self) -> np.ndarray:
        """The linear normal field evaluated at the neighbours, (m, 3) unit, in the frame."""
        uv = self.local[:, :2]
        XY = self.mu + uv @ self.W.T
        Z = np.sqrt(np.clip(1.0 - (XY**2).sum(1), 0.0, None))
        out = np.column_stack([XY, Z])
        return out / np.linalg.norm(out, axis=1, keepdims=True)

    def section(self, theta: float, band: float | None = None):
        """Neighbours near the normal plane at angle ``theta``: (s, w) coordinates in that
        plane, sorted by s. ``band`` (default a fifth of the radius) is the slab half-width."""
        band = 0.2 * self.radius if band is None else band
        d = np.array([np.cos(theta), np.sin(theta)])
        s = self.local[:, :2] @ d
        off = self.local[:, :2] @ np.array([-d[1], d[0]])
        keep = np.abs(off) <= band
        order = np.argsort(s[keep])
        return s[keep][order], self.local[keep, 2][order]

    def osculating_circle(self, theta: float, n: int = 96, reach: float | None = None) -> np.ndarray:
        """World points of the osculating circle of the normal section at ``theta``: centre
        p - n / k_n, radius 1 / |k_n|; a straight segment across the neighbourhood where k_n
        counts as zero (an infinite radius, :data:`core.point_types.ZERO`). With ``reach``,
        only the arc within that distance of p (the segment within it, if straight)."""
        k = float(self.normal_curvature(theta))
        d = np.cos(theta) * self.e1 + np.sin(theta) * self.e2
        if abs(k) < ZERO * self.scale:
            s = np.linspace(-1.0, 1.0, 2) * (1.5 * self.radius if reach is None else reach)
            return self.origin + s[:, None] * d
        centre = self.origin - self.normal / k
        rad = 1.0 / abs(k)
        half = np.pi if reach is None or reach >= 2 * rad else 2 * np.arcsin(reach / (2 * rad))
        t = np.linspace(-half, half, n)
        return centre + rad * (np.cos(t)[:, None] * self.normal * np.sign(k) + np.sin(t)[:, None] * d)

    def dupin(self, size: float | None = None, n: int = 181) -> list:
        """The Dupin indicatrix |k_n(phi)| r^2 = const in the tangent plane, as world
        polylines: an ellipse (elliptic), two hyperbola pairs (hyperbolic, k_n > 0 and < 0),
        two parallel lines (parabolic), a circle (umbilic), nothing (planar). Scaled so its
        nearest point is at ``size`` (default 0.6 x radius); cut at 2.5 x size."""
        size = 0.6 * self.radius if size is None else size
        kmax = max(abs(self.k1), abs(self.k2))
        if self.kind == "planar" or kmax == 0:
            return []
        # start where |k_n| is smallest (an asymptote, if any), so no branch wraps past the end
        grid = np.linspace(0, np.pi, 721)
        phi0 = grid[np.argmin(np.abs(self.normal_curvature(grid)))]
        phi = phi0 + np.linspace(0, 2 * np.pi, n)
        kn = self.normal_curvature(phi)
        with np.errstate(divide="ignore"):
            r = size * np.sqrt(kmax / np.abs(kn))
        keep = r <= 2.5 * size
        pieces, start = [], None
        for i in range(n + 1):
            if i < n and keep[i] and (start is None or np.sign(kn[i]) == np.sign(kn[start])):
                start = i if start is None else start
                continue
            if start is not None and i - start >= 2:
                sl = slice(start, i)
                uvw = np.column_stack([r[sl] * np.cos(phi[sl]), r[sl] * np.sin(phi[sl]), np.zeros(i - start)])
                pieces.append(self.to_world(uvw))
            start = i if (i < n and keep[i]) else None
        return pieces


def local_fit(res, index: int, *, scale: float | None = None) -> LocalFit:
    """The local picture at point ``index`` of a :class:`core.CurvatureResult`.

    The normal field is fitted, as NF does (eqs. 15-21), to the result's final normals over the
    point's own neighbourhood (``res.k_point[index]`` neighbours): it shows what one more NR
    pass would fit. ``scale`` is the cloud's curvature scale (computed when not given; pass
    it to avoid an O(N) pass per pick).
    """
    n = len(check_result(res).points)
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
        raise ValueError(f"index={index!r} is invalid; must be an integer in [0, {n - 1}]")
    index = int(index)
    if not res.valid[index]:
        raise ValueError(f"index={index} is an invalid point (degenerate neighbourhood): it has no frame")
    idx = _neighbourhood(res, index)
    p, nrm = res.points[index], res.normals[index]
    e1 = res.e1[index] - nrm * np.dot(res.e1[index], nrm)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(nrm, e1)
    R = np.stack([e1, e2, nrm])
    local = (res.points[idx] - p) @ R.T
    ln = res.normals[idx] @ R.T
    ln *= np.where(ln[:, 2] < 0, -1.0, 1.0)[:, None]
    A = np.column_stack([np.ones(len(idx)), local[:, :2]])
    coef, *_ = np.linalg.lstsq(A, ln[:, :2], rcond=None)
    scale = curvature_scale(res) if scale is None else float(scale)
    kind = TYPE_NAMES[classify(res.k1[index], res.k2[index], True, scale=scale)[0]]
    return LocalFit(index, p.copy(), e1, e2, nrm.copy(), float(res.k1[index]), float(res.k2[index]), kind,
                    idx, local, ln, coef[0], coef[1:].T.copy(), float(np.linalg.norm(local, axis=1).max()), scale)


def _neighbourhood(res, index):
    nb = res.neighbours
    k = int(res.k_point[index]) if res.k_point is not None and res.k_point[index] > 0 else DEFAULT_K
    if nb is not None and nb.matches(res.points) and k <= nb.k_max:
        return np.asarray(nb.rows(np.array([index]), k)[0][0])  # one row: a lazy graph searches only it
    k = min(k, len(res.points))
    _, idx = cKDTree(res.points).query(res.points[index], k=k)
    return np.atleast_1d(idx)
