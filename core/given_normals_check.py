"""Whether a cloud's given normals are a better start than the estimator's own (k="auto").

Scans arrive with normals a tool computed, often crudely (PCA on 6 neighbours): as initial
normals they cost 2-9x in median |H| error against the estimator's own initial normals
(2-jets on the noise-grown neighbourhood, :mod:`core.initial_normals`), while exact ones
(analytic) gain 1.4-4x. Which is the better start is read from the data:

- theta: each given normal's angle to the own one. Its mean square is the sum of the two
  errors' (given and own err independently): theta^2 = e_given^2 + e_own^2.
- phi: the angle between two own estimates on disjoint halves of the same neighbours
  (even and odd ranks). Each half has twice the variance of the whole, so phi^2 / 4
  measures e_own^2, the spread the point noise explains, on this cloud, whatever its
  noise, sampling or scale (no model of either).

The roughness ratio ``R = median(theta^2) / (median(phi^2) / 4)`` is about 1 for exact
normals (0.3-2.7 on tori, spheres, ellipsoids, saddles at noise 0.05-0.5 spacing) and
1 + (e_given/e_own)^2 otherwise: crude PCA normals on 5-8 neighbours read 9-600. Given normals are the
start while R <= :func:`max_roughness` (2 at low noise, 12 at 0.5 spacing: the fits
average independent errors over the neighbours noise adds); above it the own normals are, with the given
ones' signs (orientation "keep" holds). Angles are unsigned and scale-free: the verdict
does not depend on a rotation, a scale or the normals' signs.

Per cloud, not per region: the median over the cloud is immune to the creases where
the own jets lean (their halves agree, theta is the own bias). Pooled over each point's 64
nearest instead, exact normals read above the bar at 11-21 % of a cube's points (its edges,
noise 0-0.5) and 4 % of ``shapes.graded``: a verdict per region would drop exact normals
where they help most. A file's normals mostly come from one tool.
Noise-free, e_own is only the jets' bias (0.1 degrees on a torus) and any start leads to
the same result (tilts of 2 degrees: the same |H| error): e_own is taken as at least
:data:`OWN_FLOOR`.
"""

from __future__ import annotations

import numpy as np

from .normals import jet_normals

#: the given normals start the fits up to R = 1 + (k_initial - k0) / ROUGHNESS_K, where k0
#: is the plan's initial k (15), and at least up to MIN_ROUGHNESS (:func:`max_roughness`)
ROUGHNESS_K = 4.0
MIN_ROUGHNESS = 2.0
#: degrees: the own normals' error taken as at least this (noise-free clouds, see above)
OWN_FLOOR = 0.25
#: degrees between a given row and its own normal beyond which the row's side is its neighbours' (:func:`signed_like`)
SIDE_DEGREES = 60.0


def max_roughness(k_initial, k0) -> float:
    """The largest R at which the given normals start the fits, at the own normals'
    ``k_initial`` (grown from ``k0`` by the noise): independent errors of given normals
    are averaged by the fits over the neighbours the noise adds, while the own normals'
    errors are shared by neighbours (they fit overlapping rows). Measured crossover of the
    result's median |H| error, given normals tilted at random vs the own (torus, sphere,
    ellipsoid, saddle): R 2-3 at k_initial 19-22 (noise 0.05-0.07 spacing), 4.5-5 at 27 (0.1),
    6-7.5 at 38 (0.2), 11-14 at 60 (0.5). Exact normals read R <= 2.7 at any noise."""
    return max(MIN_ROUGHNESS, 1.0 + (k_initial - k0) / ROUGHNESS_K)


def roughness(pts, given, own, has_own, idx, dist) -> float:
    """R of the module docstring: ``given`` (N, 3) unit normals (NaN rows allowed), ``own``
    (N, 3) the estimator's initial normals where ``has_own``, ``idx``/``dist`` (N, k) the
    neighbours they were fitted on (the point first). NaN where no row has both."""
    k = idx.shape[1]
    halves = [jet_normals(pts, own, has_own, np.ascontiguousarray(idx[:, cols]), np.ascontiguousarray(dist[:, cols]))
              for cols in (np.arange(0, k, 2), np.r_[0, np.arange(1, k, 2)])]
    (first, height_a), (second, height_b) = halves
    theta2 = _angle2(given, own)
    phi2 = _angle2(first, second)  # where a half's jet was refused (height NaN) it kept the own normal
    both = has_own & np.isfinite(theta2) & np.isfinite(height_a) & np.isfinite(height_b)
    if not both.any():
        return float("nan")
    own2 = max(float(np.median(phi2[both])) / 4.0, np.radians(OWN_FLOOR) ** 2)
    return float(np.median(theta2[both]) / own2)


def _angle2(a, b) -> np.ndarray:
    """Squared unsigned angle (radians) between the rows of ``a`` and ``b`` (NaN where either is)."""
    with np.errstate(invalid="ignore"):
        cos = np.abs(np.einsum("ij,ij->i", a, b))
        sin = np.linalg.norm(np.cross(a, b), axis=1)
    return np.arctan2(sin, cos) ** 2


def signed_like(own, has_own, given, idx) -> tuple[np.ndarray, np.ndarray]:
    """The ``own`` normals turned to the side the ``given`` ones face, and the given rows
    where there is no own normal: ``(normals, has_normal)``. A given row more than
    :data:`SIDE_DEGREES` off its own normal (a crude normal at high noise lies near the
    tangent plane) does not tell a side: its ``idx`` neighbours' given rows vote."""
    given0 = np.nan_to_num(given)
    dot = np.einsum("ij,ij->i", np.nan_to_num(own), given0)
    vague = np.flatnonzero(np.abs(dot) < np.cos(np.radians(SIDE_DEGREES)))
    dot[vague] = np.einsum("ij,ikj->i", np.nan_to_num(own[vague]), given0[idx[vague]])
    turned = np.where((dot < 0)[:, None], -own, own)
    normals = np.where(has_own[:, None], turned, given)
    return normals, np.isfinite(normals).all(axis=1)
