"""Wide normal fits shared between nearby points (k="auto" with noise).

Where a point's fit is wide (k >= :data:`core.tuning.SHARE_MIN_K`: noise made the rule
average many neighbours) its fitted cubic normal field X(u, v), Y(u, v) (eqs. 23-26 with
degree 3) describes the whole neighbourhood, not only its centre. A point within
:data:`core.tuning.SHARE_REACH` x the fit radius of such a centre (a *satellite*) takes
the centre's field at its own offset (u, v) instead of solving its own robust fit:
mu = (X, Y)(u, v) and W = [[X_u, X_v], [Y_u, Y_v]](u, v), the matrix of dn in the basis
(r_u, r_v) of the graph over the centre's tangent plane (eq. 21), projected onto eq. 22's
plane at the new mu and read through the shared :func:`core.frame.darboux_frame`. Centres
are chosen greedily in the spatial order (:func:`core.kernels.share.assign_satellites`),
so the result does not depend on the number of threads.
"""

from __future__ import annotations

import numpy as np

from . import tuning
from .frame import darboux_frame
from .kernels.frame import local_frames
from .kernels.permute import put_rows
from .kernels.share import CENTRE, OWN, Blend, assign_satellites, blend_normals

_CHUNK = 32_768


def satellites(nb, nrm, kc, h, eligible) -> np.ndarray | None:
    """``centre_of`` (N,) int64: the centre whose fit point i takes, or -1 where it fits
    itself (None when no point shares). ``eligible`` (N,) bool: the points that may be
    centres or satellites; ``kc``, ``h`` the fits' sizes and radii; ``nrm`` the normals
    whose agreement keeps a satellite on its centre's side of a fold."""
    eligible = eligible & (kc >= tuning.SHARE_MIN_K) & (h > 0)
    if tuning.SHARE_REACH <= 0 or not eligible.any():
        return None
    idx, dist = nb.take(min(tuning.SHARE_SCAN, nb.width))
    centre_of = np.full(len(kc), OWN, dtype=np.int64)
    assign_satellites(np.ascontiguousarray(idx), np.ascontiguousarray(dist), np.ascontiguousarray(kc, dtype=np.int64),
                      np.ascontiguousarray(h, dtype=np.float64), eligible, np.ascontiguousarray(nrm, dtype=np.float64),
                      tuning.SHARE_REACH, tuning.SHARE_K_RATIO, tuning.SHARE_COS, centre_of)
    centre_of[centre_of == CENTRE] = OWN
    return centre_of if (centre_of >= 0).any() else None


class SharedFitter:
    """A :class:`core.stages._Fitter` whose satellites (``centre_of`` >= 0) take their
    centre's fit (see the module docstring); same ``into`` as the fitter's. A pass fitted
    in two calls on the same ``out`` (the pass rule's sample, then the rest) fits each
    centre once."""

    def __init__(self, fitter, centre_of, nb):
        self.fitter, self.centre_of = fitter, centre_of
        self.scan = tuple(np.ascontiguousarray(a) for a in nb.take(min(tuning.SHARE_SCAN, nb.width)))
        self.degree = int(fitter.options.get("degree", 1))
        self.project = fitter.options.get("constraint", "project") != "none"
        is_centre = np.zeros(len(centre_of), dtype=bool)
        is_centre[centre_of[centre_of >= 0]] = True
        self.sink = _Coefs(is_centre, self.degree)
        self.out, self.done = None, None

    def into(self, out, nrm, has_normal, report) -> None:
        """Fit the points with ``has_normal`` into ``out``: the centres their satellites
        need (whether or not they are asked for), the others themselves, then the satellites."""
        f, n = self.fitter, len(self.centre_of)
        if out is not self.out:  # a new pass
            self.out, self.done = out, np.zeros(n, dtype=bool)
        usable = has_normal & (f.h > 0)
        sat = usable & (self.centre_of >= 0)
        need = np.zeros(n, dtype=bool)
        need[self.centre_of[sat]] = True
        direct = ((usable & ~sat) | need) & ~self.done
        f.into(out, nrm, direct, report.sub(0.0, 0.9), sink=self.sink)
        self.done |= direct
        lost = np.zeros(n, dtype=bool)
        lost[sat] = ~out.valid[self.centre_of[sat]]  # a centre without a fit: its satellites fit themselves
        if lost.any():
            f.into(out, nrm, lost, report.sub(0.9, 0.95))
        rows = np.flatnonzero(sat & ~lost)
        for start in range(0, len(rows), _CHUNK):
            self._satellites(out, nrm, rows[start:start + _CHUNK])
        report(1.0, f.method.name)

    def _satellites(self, out, nrm, rows) -> None:
        """Satellites ``rows``: the centre's field at their offsets, through the shared frame."""
        pts, c = self.fitter.pts, self.centre_of[rows]
        z, t1, t2 = np.empty((len(c), 3)), np.empty((len(c), 3)), np.empty((len(c), 3))
        local_frames(np.ascontiguousarray(nrm, dtype=np.float64), c, z, t1, t2)  # the centre's fit frame
        hc = self.fitter.h[c]
        d = (pts[rows] - pts[c]) / hc[:, None]
        u, v = np.einsum("mj,mj->m", d, t1), np.einsum("mj,mj->m", d, t2)
        mu, W = field_at(self.sink.of(c), u, v, self.degree)
        if self.project:
            W = projected(mu, W)
        frame = darboux_frame(t1, t2, z, mu, W / hc[:, None, None])
        good = frame.ok
        stored = [(frame.normal, out.normals), (frame.e1, out.e1), (frame.e2, out.e2), (frame.k1, out.k1),
                  (frame.k2, out.k2), (out.rms[c], out.rms), (out.spread[c], out.spread), (good, out.valid)]
        for src, dst in stored:
            put_rows(good, rows, np.ascontiguousarray(src, dtype=dst.dtype).reshape(len(rows), -1),
                     dst.reshape(len(dst), -1))


    def blended(self, fit, nrm, new):
        """The next pass's input normals ``new`` (N, 3) with the satellites' blended from
        the fields of every centre within SHARE_BLEND x its radius (:func:`core.kernels.share.blend_normals`):
        one centre's field alone makes the inputs of its satellites err together."""
        sats = np.flatnonzero((self.centre_of >= 0) & fit.valid)
        if tuning.SHARE_BLEND <= 0 or not len(sats):
            return new
        f, sink = self.fitter, self.sink
        row = np.where(fit.valid, sink.row, -1)
        centres = np.flatnonzero(sink.row >= 0)
        frames = np.empty((len(centres), 3, 3))
        z, t1, t2 = np.empty((len(centres), 3)), np.empty((len(centres), 3)), np.empty((len(centres), 3))
        local_frames(np.ascontiguousarray(nrm, dtype=np.float64), centres, z, t1, t2)  # the pass's fit frames
        frames[sink.row[centres], 0], frames[sink.row[centres], 1], frames[sink.row[centres], 2] = t1, t2, z
        out = np.empty((len(sats), 3))
        new = np.ascontiguousarray(new, dtype=np.float64)
        blend_normals(f.pts, *self.scan, np.ascontiguousarray(f.kc, dtype=np.int64), np.ascontiguousarray(f.h), row,
                      sink.coef, frames, sats, new, Blend(tuning.SHARE_BLEND, tuning.SHARE_K_RATIO, tuning.SHARE_COS),
                      out)
        new = new.copy()
        new[sats] = out
        return new


class _Coefs:
    """The fitted polynomials of the points in ``kept`` (N,) bool, as the chunks are fitted
    (each pass overwrites them; a satellite reads its centre's only once it is valid)."""

    def __init__(self, kept, degree):
        self.row = np.full(len(kept), -1, dtype=np.int64)
        rows = np.flatnonzero(kept)
        self.row[rows] = np.arange(len(rows))
        self.coef = np.zeros((len(rows), 2, (degree + 1) * (degree + 2) // 2))

    def __call__(self, centres, coef) -> None:
        at = self.row[centres]
        mine = at >= 0
        self.coef[at[mine]] = coef[mine]

    def of(self, centres) -> np.ndarray:
        return self.coef[self.row[centres]]


def field_at(coef, u, v, degree):
    """(mu, W) of the fitted fields at (u, v) (units of h): values and first derivatives
    of the monomials 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3 (:func:`core.kernels.algebra.poly_row`)."""
    one, zero = np.ones_like(u), np.zeros_like(u)
    value = [one, u, v, u * u, u * v, v * v, u ** 3, u * u * v, u * v * v, v ** 3]
    d_u = [zero, one, zero, 2 * u, v, zero, 3 * u * u, 2 * u * v, v * v, zero]
    d_v = [zero, zero, one, zero, u, 2 * v, zero, u * u, 2 * u * v, 3 * v * v]
    t = (degree + 1) * (degree + 2) // 2
    basis = np.stack([np.stack(b[:t], axis=1) for b in (value, d_u, d_v)], axis=1)  # (M, 3, T)
    at = np.einsum("mct,mbt->mcb", coef, basis)  # (M, component X/Y, value/d_u/d_v)
    return np.ascontiguousarray(at[:, :, 0]), np.ascontiguousarray(at[:, :, 1:])


def projected(mu, W):
    """W projected onto eq. 22's plane at ``mu`` (§4.4, as the fit's own constraint)."""
    m1, m2 = mu[:, 0], mu[:, 1]
    g = np.stack([m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2], axis=1)
    w = W.reshape(len(W), 4)
    t = np.einsum("mi,mi->m", g, w) / np.einsum("mi,mi->m", g, g)
    return (w - t[:, None] * g).reshape(-1, 2, 2)
