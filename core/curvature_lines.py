"""Lines of curvature: streamlines of the principal direction fields e1 and e2.

e1 and e2 are line fields (their sign means nothing), so the tracer turns every sampled
direction towards the direction it came from. A line advances by midpoint (RK2) steps of
half a spacing, is pulled back onto the surface through the neighbours' osculating
paraboloids, and stops at umbilics and flat regions (where k1 - k2 is small against the
cloud's curvature scale and the direction is undefined), where the neighbours disagree about
the direction, where it leaves the cloud, or where it closes on itself.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ._progress import Progress
from ._validate import check_choice, check_result
from .duplicates import find_duplicates
from .point_types import curvature_scale
from .tuning import NEAR_COPY

#: neighbours interpolating the field at a point of a line (6: the first ring of a sample)
FIELD_NEIGHBOURS = 6
#: step length in spacings: half a spacing resolves the field; on the 5000-point torus the
#: meridians drift < 0.5 degree with it (a whole spacing: ~1 degree)
STEP = 0.5
#: stop where |k1 - k2| < this x the curvature scale (an umbilic or a flat region)
UMBILIC = 0.1
#: stop where the aligned neighbour directions average to less than this length (they disagree)
COHERENCE = 0.8
#: stop where the nearest point is farther than this many spacings (off the cloud). Random
#: samples have holes: at 3, a third of the torus' meridians stopped in one (the chance that a
#: spot is 3 mean spacings from every point of a Poisson sample is 0.2 %, per step)
OFF_CLOUD = 6.0
#: stop where one step turns by more than 45 degrees (cosine): a line of curvature turns by
#: about h k1 radians per step, a few degrees; a sharp turn is a singularity of the field
MAX_TURN = np.cos(np.deg2rad(45.0))
#: a line passing this many spacings from its own seed has looped (the lateral drift of one
#: loop on the 5000-point torus is below 1 spacing; the seed separation is 10)
CLOSE_SPACINGS = 3.0
#: default seed separation in spacings
SEED_SPACING = 10.0


class _Field:
    """The line field of one principal direction, interpolated from the valid points."""

    def __init__(self, res, which):
        ok = res.valid & np.isfinite(res.k1) & np.isfinite(res.k2)
        if not ok.any():
            raise ValueError("res has no valid point: no principal directions to trace")
        ok = np.flatnonzero(ok)
        # one copy of each repeated point (a cloud stored twice): the spacing is between
        # distinct points, and the neighbours interpolating the field are distinct
        merged = find_duplicates(np.ascontiguousarray(res.points[ok], dtype=np.float64))
        ok = ok if merged is None else ok[merged.first]
        if len(ok) < 2:
            raise ValueError("res has fewer than two distinct valid points: no line to trace")
        self.pts = res.points[ok]
        self.dirs = (res.e1 if which == "e1" else res.e2)[ok]
        self.nrm, self.e1, self.e2 = res.normals[ok], res.e1[ok], res.e2[ok]
        self.k1, self.k2 = res.k1[ok], res.k2[ok]
        self.tree = cKDTree(self.pts)
        self.spacing = _spacing(self.tree, self.pts)
        self.aniso = (self.k1 - self.k2) / curvature_scale(res)

    def sample(self, x, ref):
        """Direction at x turned towards ref, and a per-row "may continue" flag."""
        k = min(FIELD_NEIGHBOURS, len(self.pts))
        d, idx = self.tree.query(x, k=k)
        d, idx = d.reshape(len(x), k), idx.reshape(len(x), k)
        w = np.exp(-((d**2 - d[:, :1] ** 2) / self.spacing**2))
        w /= w.sum(1, keepdims=True)
        f = self.dirs[idx]
        f = f * np.sign(np.einsum("lkj,lj->lk", f, ref) + 1e-300)[..., None]
        avg = np.einsum("lk,lkj->lj", w, f)
        coherence = np.linalg.norm(avg, axis=1)
        n = self.nrm[idx[:, 0]]
        avg -= n * np.einsum("lj,lj->l", avg, n)[:, None]
        avg /= np.maximum(np.linalg.norm(avg, axis=1, keepdims=True), 1e-300)
        aniso = np.einsum("lk,lk->l", w, self.aniso[idx])
        ok = (coherence >= COHERENCE) & (aniso >= UMBILIC) & (d[:, 0] <= OFF_CLOUD * self.spacing)
        return avg, ok

    def project(self, x):
        """Pull x onto the weighted osculating paraboloids of its nearest points."""
        k = min(FIELD_NEIGHBOURS, len(self.pts))
        d, idx = self.tree.query(x, k=k)
        d, idx = d.reshape(len(x), k), idx.reshape(len(x), k)
        w = np.exp(-((d**2 - d[:, :1] ** 2) / self.spacing**2))
        w /= w.sum(1, keepdims=True)
        t = x[:, None, :] - self.pts[idx]
        n = self.nrm[idx]
        u = np.einsum("lkj,lkj->lk", t, self.e1[idx])
        v = np.einsum("lkj,lkj->lk", t, self.e2[idx])
        h = np.einsum("lkj,lkj->lk", t, n)
        target = -0.5 * (self.k1[idx] * u * u + self.k2[idx] * v * v)
        return x + np.einsum("lk,lkj->lj", w * (target - h), n)


def _spacing(tree, pts) -> float:
    """Mean distance from a point to its nearest neighbour that is not a near copy of it
    (closer than NEAR_COPY x the median FIELD_NEIGHBOURS-th neighbour distance: a point
    written twice 1e-6 apart made the spacing, and the step, a millionth of the true one)."""
    d, _ = tree.query(pts, k=min(FIELD_NEIGHBOURS + 1, len(pts)))
    d = d[:, 1:]
    far = d > NEAR_COPY * np.median(d[:, -1])
    nearest = d[np.arange(len(d)), far.argmax(axis=1)][far.any(axis=1)]
    spacing = float(np.mean(nearest)) if nearest.size else 0.0
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError("res has no two valid points apart: no spacing to step by")
    return spacing


def _trace(field, seeds, start_dirs, h, max_steps, report):
    """Advance all lines together; returns a list of (m, 3) polylines.

    A line that comes back past its seed (its distance to the seed stops falling within
    CLOSE_SPACINGS spacings) has made a loop and stops; it is joined to its seed if it passes
    within two steps of it."""
    x = seeds.copy()
    ref = start_dirs.copy()
    paths = [[p.copy()] for p in x]
    active = np.ones(len(x), dtype=bool)
    last = np.full(len(x), np.inf)
    looped = np.zeros(len(x), dtype=bool)
    for step in range(max_steps):
        rows = np.flatnonzero(active)
        if len(rows) == 0:
            break
        report(step / max_steps, "lines of curvature")
        d1, ok1 = field.sample(x[rows], ref[rows])
        d2, ok2 = field.sample(x[rows] + 0.5 * h * d1, d1)
        new = field.project(x[rows] + h * d2)
        ok = ok1 & ok2 & (np.einsum("lj,lj->l", d2, ref[rows]) > MAX_TURN)
        dist = np.linalg.norm(new - seeds[rows], axis=1)
        near = (step >= 8) & (dist < CLOSE_SPACINGS * field.spacing)
        closed = near & (dist > last[rows])
        for j, r in enumerate(rows):
            if ok[j] and not closed[j]:
                paths[r].append(new[j])
            elif closed[j] and last[r] < 2.0 * h:
                paths[r].append(seeds[r].copy())
        x[rows], ref[rows], last[rows] = new, d2, np.where(near, dist, np.inf)
        active[rows] = ok & ~closed
        looped[rows] = closed
    return [np.array(p) for p in paths], looped


def seed_points(points, spacing: float, separation: float, *, seed: int = 0) -> np.ndarray:
    """Indices of points at least ``separation`` apart (greedy Poisson-disk subsample)."""
    tree = cKDTree(points)
    covered = np.zeros(len(points), dtype=bool)
    chosen = []
    for i in np.random.default_rng(seed).permutation(len(points)):
        if not covered[i]:
            chosen.append(i)
            covered[tree.query_ball_point(points[i], separation)] = True
    return np.array(chosen, dtype=int)


def curvature_lines(res, *, direction: str = "e1", seeds=None, separation: float = SEED_SPACING,
                    step: float = STEP, max_length: float | None = None, progress=None) -> list:
    """Lines of curvature of a :class:`core.CurvatureResult`, traced through e1 or e2.

    Parameters
    ----------
    res : CurvatureResult.
    direction : "e1" (the direction of k1, the larger curvature) or "e2".
    seeds : optional (s,) indices of the points to start from; default points ``separation``
        spacings apart.
    separation : float > 0, seed separation in mean spacings.
    step : float in (0, 2], step length in mean spacings.
    max_length : float, the longest line (default 3 x the bounding-box diagonal).
    progress : callable(fraction, stage) -> None | False, optional, called every step;
        returning False cancels (:class:`core.Cancelled`), as in :func:`core.estimate`.

    Returns
    -------
    list of (m, 3) arrays, longest first, one polyline per seed (traced both ways from it);
    lines of a single point, and lines running mostly within ``separation / 2`` of a longer
    one (the same line of curvature from another seed), left out.

    Examples
    --------
    >>> import core
    >>> s = core.shapes.cylinder(3000, seed=0)
    >>> lines = core.curvature_lines(core.estimate(s.points, s.normals, k=20), direction="e2")
    >>> len(lines) > 0
    True
    """
    direction = check_choice(direction, name="direction", choices=("e1", "e2"))
    if not (np.isscalar(step) and 0 < step <= 2):
        raise ValueError(f"step={step!r} is invalid; must be a number in (0, 2] (spacings)")
    if not (np.isscalar(separation) and separation > 0):
        raise ValueError(f"separation={separation!r} is invalid; must be a number > 0 (spacings)")
    field = _Field(check_result(res), direction)
    h = step * field.spacing
    if max_length is None:
        max_length = 3.0 * float(np.linalg.norm(np.ptp(field.pts, axis=0)))
    if seeds is None:
        start = seed_points(field.pts, field.spacing, separation * field.spacing)
        x0 = field.pts[start]
    else:
        seeds = np.asarray(seeds, dtype=int).ravel()
        if seeds.size and (seeds.min() < 0 or seeds.max() >= len(res.points)):
            raise ValueError(f"seeds must be point indices in [0, {len(res.points) - 1}]")
        x0 = res.points[seeds]
    d0, _ = field.sample(x0, np.tile([1.0, 0.3, 0.1], (len(x0), 1)))
    steps = int(np.ceil(max_length / h))
    report = Progress(progress)
    fwd, looped = _trace(field, x0, d0, h, steps, report.sub(0.0, 0.5))
    lines = [f for f, loop in zip(fwd, looped) if loop]
    open_ = np.flatnonzero(~looped)
    back, _ = _trace(field, x0[open_], -d0[open_], h, steps, report.sub(0.5, 1.0))
    for i, b in zip(open_, back):
        line = np.concatenate([b[::-1], fwd[i][1:]])
        if len(line) > 1:
            lines.append(line)
    return _thin(lines, 0.5 * separation * field.spacing, report)


def _thin(lines, gap, report):
    """Keep lines longest first, dropping one whose points lie mostly (over half) within
    ``gap`` of the lines kept (seeds along one line of curvature trace it again)."""
    kept, tree = [], None
    for line in sorted(lines, key=len, reverse=True):
        report(1.0, "lines of curvature")
        if tree is not None and np.mean(tree.query(line, k=1)[0] < gap) > 0.5:
            continue
        kept.append(line)
        tree = cKDTree(np.concatenate(kept))
    return kept
