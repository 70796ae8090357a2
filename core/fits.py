"""One fit of a method over all points (:func:`fit_all`): the chunks of centres, the frames
(:func:`core.frame.darboux_frame`) stored into a :class:`Fit`, and with k="auto" the followers
reading their anchors' fits (:mod:`core.anchors`); :func:`invalid_at` makes points invalid.
The stages of :mod:`core.stages` and the passes of :mod:`core.refinement` fit through it."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import anchors
from .anchor_blend import blended
from .frame import darboux_frame, frame_valid
from .kernels.permute import put_rows
from .patch import Chunk

_CHUNK = 32_768
#: a fit's chunk holds at least _CHUNK centres, more when their neighbourhoods are narrow:
#: up to this many (centre, neighbour) entries, the most a chunk of _CHUNK held at k = 56
#: (k = 15: 122k centres, so 100k points are one chunk, where 4 chunks cost 4 launches of each
#: kernel and 4 rounds of numpy between them; the results do not depend on the chunks)
_CHUNK_ENTRIES = _CHUNK * 56


class Fit(NamedTuple):
    """One fit of the method over all points: refined ``normals``, ``k1``, ``k2``,
    ``e1``, ``e2`` (NaN where not ``valid``), and the normal fit's residual ``rms``, the
    normals' ``spread`` (NaN for methods without a normal fit) and the ``degree`` of the
    polynomial it fitted (:func:`core.kernels.lstsq.solve_determined`; 0 where none)."""

    normals: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    valid: np.ndarray
    rms: np.ndarray
    spread: np.ndarray
    degree: np.ndarray



def fit_all(pts, nrm, idx, kc, h, has_normal, *, method, options, report, frames=True) -> Fit:
    """One fit of ``method`` with ``options`` over all points in chunks, through the shared
    frame path: point i uses its first ``kc[i]`` neighbours in ``idx``, lengths in units of
    ``h[i]``; points without ``has_normal`` (or h = 0) stay invalid. Without ``frames`` the fit
    is read for its ``valid``, ``rms``, ``spread`` and ``degree`` alone: the frames' fields are
    None (no principal directions computed, no frame stored: 0.05 s CPU of a default estimate
    of 100k points went to the crease reference's frames)."""
    out = empty_fit(len(pts), frames=frames)
    Fitter(pts, idx, kc, h, method, options).into(out, nrm, has_normal, report)
    return out


def empty_fit(n, *, frames=True) -> Fit:
    """A :class:`Fit` of ``n`` invalid points (without ``frames``: normals, k1, k2, e1, e2 None)."""
    def vectors():
        return np.full((n, 3), np.nan) if frames else None

    def scalars(kept=True):
        return np.full(n, np.nan) if kept else None

    return Fit(vectors(), scalars(frames), scalars(frames), vectors(), vectors(), np.zeros(n, dtype=bool),
               scalars(), scalars(), np.zeros(n, dtype=np.int8))


class Fitter(NamedTuple):
    """What every fit of a refinement shares: the points, their neighbours ``idx``, the
    sizes ``kc``, the length units ``h``, the method and its options (see :func:`fit_all`),
    and with k="auto" the anchors whose fits each point reads (``anchor``, :mod:`core.anchors`)."""

    pts: np.ndarray
    idx: np.ndarray
    kc: np.ndarray
    h: np.ndarray
    method: object
    options: dict
    anchor: np.ndarray | None = None

    def into(self, out: Fit, nrm, has_normal, report, kept=None):
        """Fit the points with ``has_normal`` (and h > 0) to the normals ``nrm``, into ``out``;
        with anchors, the followers among them read their anchors' fits (fitted here too
        unless ``kept``, what an earlier call of the same pass returned, holds them).
        Returns the anchors' fits (:class:`core.anchors.Kept`), or None without anchors."""
        usable = has_normal & (self.h > 0)
        if self.anchor is None:
            return self._fit(out, nrm, usable, report)
        kept = anchors.Kept(self.anchor) if kept is None else kept
        fit_at, follow = anchors.split(self.anchor, usable, kept)
        self._fit(out, nrm, fit_at, report.sub(0.0, 0.95), kept)
        alone = self._follow(out, kept, nrm, np.flatnonzero(follow))
        if alone.any():  # their anchor's fit failed: their own, on rows searched now
            if hasattr(self.idx, "ensure"):
                self.idx.ensure(np.flatnonzero(alone), self.h)
            self._fit(out, nrm, alone, report.sub(0.95, 1.0))
        return kept

    def _fit(self, out, nrm, usable, report, kept=None) -> None:
        n = len(self.pts)
        whole = isinstance(self.idx, np.ndarray) and self.idx.flags.c_contiguous
        step = max(_CHUNK, _CHUNK_ENTRIES // max(int(self.kc.max()), 1)) if n else _CHUNK
        for start in range(0, n, step):
            stop = min(n, start + step)
            c = start + np.flatnonzero(usable[start:stop])
            for chunk in self._chunks(nrm, c, whole):
                _fit_chunk(chunk, self.method, self.options, out, kept)
            report(stop / n, self.method.name)

    def _chunks(self, nrm, c, whole):
        """The :class:`Chunk` of centres ``c`` on the rows in place, where the NF kernel reads
        them (a copy of 32k rows of 320 was 4 % of a noisy k="auto" estimate): the whole
        graph's (``whole``), or held and searched rows' (:meth:`core.wide_rows._Rows.parts`);
        else on a copy of their rows."""
        if not len(c):
            return []
        if whole:
            return [Chunk.build(self.pts, nrm, self.idx, self.h[c], c, self.kc[c], rows=c)]
        if hasattr(self.idx, "parts"):
            return [Chunk.build(self.pts, nrm, rows_of, self.h[at], at, self.kc[at], rows=rows)
                    for rows_of, rows, at in self.idx.parts(c)]
        return [Chunk.build(self.pts, nrm, self.idx[c], self.h[c], c, self.kc[c])]

    def _follow(self, out: Fit, kept, nrm, points) -> np.ndarray:
        """Store at the followers ``points`` their anchors' fits read at their offsets and
        averaged (:mod:`core.anchor_blend`); returns the (N,) mask of those where an anchor's
        fit failed."""
        alone = np.zeros(len(self.pts), dtype=bool)
        if not len(points):
            return alone
        frame, good, r = blended(kept, self.pts, nrm, points, self.anchor[points], self.options.get("constraint", "project"))
        alone[points[~good]] = True
        _store(out, points, frame, {"rms": kept.rms[r], "spread": kept.spread[r], "degree": kept.degree[r]}, good)
        return alone


def _fit_chunk(chunk, method, opts, out: Fit, kept=None) -> None:
    """Fit ``chunk`` into ``out``; ``kept`` keeps the anchors' fits, with their polynomials (NF's).
    Where ``out`` holds no frames (:func:`fit_all` without ``frames``) only their validity is found."""
    mu, W, ok, diag = method.fit(chunk, **opts) if kept is None else method.fit(chunk, **opts, coefficients=True)
    if out.normals is None:
        valid = frame_valid(chunk.t1, chunk.t2, chunk.z, mu, W / chunk.h[:, None, None])
        _store(out, chunk.centres, None, diag, ok & valid)
        return
    frame = darboux_frame(chunk.t1, chunk.t2, chunk.z, mu, W / chunk.h[:, None, None])
    good = ok & frame.ok
    if kept is not None:
        kept.take(chunk, diag, good)
    _store(out, chunk.centres, frame, diag, good)


def _store(out: Fit, centres, frame, diag, good) -> None:
    """``out``'s rows ``centres[good]`` = the frame's (unless None) and the fit's diagnostics' (valid
    last: True where good)."""
    stored = [] if frame is None else \
        [(frame.normal, out.normals), (frame.e1, out.e1), (frame.e2, out.e2), (frame.k1, out.k1), (frame.k2, out.k2)]
    if diag is not None and "rms" in diag:
        stored += [(diag["rms"], out.rms), (diag["spread"], out.spread), (diag["degree"], out.degree)]
    stored.append((good, out.valid))
    for src, dst in stored:  # dst[centres[good]] = src[good], one compiled loop per array
        put_rows(good, centres, _columns(src, dst.dtype), dst.reshape(len(dst), -1))


def _columns(a, dtype):
    """``a`` as a C-contiguous (M, c) array of ``dtype`` (a view where it already is one)."""
    a = np.ascontiguousarray(a, dtype=dtype)
    return a.reshape(len(a), -1)


#: the fields an invalid point holds NaN in besides its normal (see :func:`invalid_at`)
CURVATURES = ("k1", "k2", "e1", "e2")


def invalid_at(fit: Fit, where, fields=CURVATURES) -> Fit:
    """``fit`` with the points ``where`` (N,) bool invalid: ``valid`` False and NaN in ``fields``
    there (new arrays: a fit kept for a later pass is not changed)."""
    cleared = {name: np.where(where.reshape((-1,) + (1,) * (getattr(fit, name).ndim - 1)), np.nan, getattr(fit, name))
               for name in fields}
    return fit._replace(**cleared, valid=fit.valid & ~where)
