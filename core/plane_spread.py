"""Neighbourhoods that do not span the tangent plane: curves, and scan lines far apart.

A fit over neighbours that all lie along one line through the point (every point of a
curve; a line scan whose lines are farther apart than its k nearest reach) determines the
slopes along that line only. Across it the lever arms are the neighbours' tiny offsets from
the line, and the curvature across comes out as noise divided by them: a waved sheet
scanned in lines 8 spacings apart gave, at k = 15, a median H error of 77 where |H| is
0.18, with every point reported valid. The **plane spread** of a neighbourhood, sqrt(lambda_min
/ lambda_max) of its offsets from the point projected on the tangent plane, is 1 for
neighbours all around and 0 on a line; below :data:`core.tuning.THIN_SPREAD` the point is
not fitted by NR or the paper's baselines (``valid`` False, NaN curvatures). With
k="auto" NR takes the smallest larger candidate whose neighbours do span the plane. The
position jets of k="auto" are not held to it: their interval rule sees the lever arms
through the variance of their Hessian, and on exact data a thin jet is still right (a
noise-free scan with lines 12 spacings apart: median H error 0.0036 with the jets on
20-28 thin neighbours, 0.45 with NR widened instead). The initial normals of k="auto" are
(:func:`spanning_normals`): a curved scan line's PCA is the plane of the line, and every
later stage works in the frames of the initial normals. A noisy line's PCA plane holds the
line and its noise, so there the test is looser (:data:`LINE_SPREAD`).

A curve that bends in a plane (a scanned profile, a long arc of one ring) spreads over that
plane at wide neighbourhoods (a circle: 0.13 at 320 neighbours, growing with k), so it is
not told apart from a surface by its spread alone: a widened neighbourhood must also not lie
along one curve (:data:`CURVE_SHARE`).
"""

from __future__ import annotations

import numpy as np

from . import kernels
from .kernels.spread import curve_shares, plane_spread, thin_shapes
from .linalg import tangent_basis
from .normals import pca_normals_at
from .tuning import FOLD_FLAT, INITIAL_JET_PIVOT, THETA_REACH, THIN_SPREAD


#: k="auto" with measured noise: NR's neighbours must reach this plane spread (:func:`widened`). A ribbon 200:1 and
#: 4 spacings wide spans 0.08-0.13 at the sizes chosen; the final neighbourhoods of tori, range and stripe scans
#: (3-16x), thin plates and tubes, cubes and thin cylinders at noise 0.1-0.3 spacing: none below 0.2
NOISY_SPREAD = 0.2
#: ... looked at only where the STRIP_K nearest spread less than this (a ribbon's 40 nearest: 0.32-0.78)
STRIP_SCREEN, STRIP_K = 0.8, 40
#: ... and only where some of this many of them, evenly drawn, is narrower than NOISY_SPREAD at its own k
STRIP_PROBE = 256


def spreads(pts, normals, nb, k, centres=None) -> np.ndarray:
    """The plane spread of ``centres`` (default: every point, on the columns the graph
    holds, read in place) over their first ``k`` neighbours (an int, or one per centre) of
    the graph ``nb``, in the plane normal to ``normals``; NaN where a point has no normal."""
    every = centres is None
    centres = np.arange(len(pts)) if every else np.asarray(centres, dtype=np.int64)
    kc = np.broadcast_to(np.asarray(k, dtype=np.int64), centres.shape).copy()
    out = np.empty(len(centres))
    if len(centres):
        idx = nb.take(nb.width)[0] if every else np.ascontiguousarray(nb.rows(centres, int(kc.max()))[0])
        idx.flags.writeable = False  # one compiled signature: the held graph is read-only
        rows = centres if every else np.arange(len(centres))
        plane_spread(pts, np.ascontiguousarray(normals, dtype=np.float64), centres, idx, rows, kc, out)
    return out


def spans_plane(pts, normals, nb, k, threshold=THIN_SPREAD, centres=None) -> np.ndarray:
    """(m,) bool: the first ``k`` (m,) neighbours of each of ``centres`` (default: every
    point) span its tangent plane, a plane spread of at least ``threshold`` (one, or one per
    centre; True where it has no normal: nothing is fitted there anyway). Judged first on the
    graph's held columns (a point whose nearer neighbours span the plane is not re-searched)."""
    narrow = np.minimum(k, nb.width)
    ok = ~(spreads(pts, normals, nb, narrow, centres) < threshold)
    again = np.flatnonzero(~ok & (k > narrow))
    if len(again):
        at = again if centres is None else centres[again]
        ok[again] = ~(spreads(pts, normals, nb, k[again], at) < np.broadcast_to(threshold, ok.shape)[again])
    return ok


def widened(pts, normals, nb, k, ks, noisy=None) -> np.ndarray:
    """``k`` (N,) raised, where a point's neighbours do not span its plane, to the smallest
    candidate of ``ks`` whose neighbours do and lie near one plane, as do those of the next
    candidate (:data:`FLAT_SHARE`); 0 where none does. Scan lines farther apart than k reach
    are a surface at every wider size; a line standing on a plane (a pole, a wire) is not:
    widened on its spread alone, a 200-point pole on a 3000-point plane had 59 points fitted
    (k up to 320, the fits reaching the plane; H -16.5 to 0.7 where there is no surface;
    validity changed at 71 of them under a turn). The next size too: a line with two or
    three points of the plane beside it is flat by chance.

    Where ``noisy`` (N,) bool (the measured noise is not nil) the spread must reach
    :data:`NOISY_SPREAD`: a strip a few spacings wide (a ribbon, 200:1) spans its
    plane at 0.08-0.13 at k = 113-320, and across it the curvature is the noise over
    lever arms of one or two spacings (noise 0.1 spacing: median |H| error 0.37-0.5 where H
    is 0.5, every point valid). Noise-free the narrow fit is exact and is kept."""
    out = np.asarray(k, dtype=np.int64).copy()
    need = np.full(len(out), THIN_SPREAD) if noisy is None else np.where(noisy, NOISY_SPREAD, THIN_SPREAD)
    thin = ~spans_plane(pts, normals, nb, out)
    if noisy is not None:
        thin |= _strips(pts, normals, nb, out, noisy)
    thin = np.flatnonzero(thin)
    for at, cand in enumerate(ks):
        wider = thin[out[thin] < cand]
        if not len(wider):
            continue
        ok = ~(spreads(pts, normals, nb, cand, wider) < need[wider])
        for size in ks[at:at + 2]:
            ok[ok] = _surface(pts, nb.rows(wider[ok], size)[0], curve=False)
        out[wider[ok]] = cand
        thin = np.setdiff1d(thin, wider[ok])
    out[thin] = 0
    return out


def _strips(pts, normals, nb, k, noisy) -> np.ndarray:
    """(N,) bool: ``noisy`` points whose ``k`` nearest spread less than :data:`NOISY_SPREAD`
    (:func:`spans_plane` judges on the graph's held columns, which span a strip: its nearest
    are as wide as they are long, its wider neighbourhoods only longer). Looked at where the
    nearest :data:`STRIP_K` are lopsided already (below :data:`STRIP_SCREEN`), and
    only if some of :data:`STRIP_PROBE` of those, evenly drawn, is thin (as the clumps' screen:
    the wide rows cost 8-14 % of a noisy cloud's estimate where most points are lopsided)."""
    out = np.zeros(len(k), dtype=bool)
    look = np.flatnonzero(noisy)  # the screen reads the same rows whatever the graph holds (tiles)
    if len(look):
        look = look[spreads(pts, normals, nb, np.minimum(k[look], STRIP_K), look) < STRIP_SCREEN]
    probe = look[np.linspace(0, len(look) - 1, min(len(look), STRIP_PROBE)).astype(np.int64)]
    if not (spreads(pts, normals, nb, k[probe], probe) < NOISY_SPREAD).any():
        return out
    for start in range(0, len(look), _CHUNK):  # chunks: the rows of up to 320 neighbours
        part = look[start:start + _CHUNK]
        out[part] = spreads(pts, normals, nb, k[part], part) < NOISY_SPREAD
    return out


def spanning_normals(pts, normals, ok, nb, k: int, ks, suspect=None):
    """Initial normals where a point's ``k`` nearest lie along one curved line (a scan line,
    its neighbours' lines farther than k reach), or in a tube as wide both ways across
    (a noisy scan line, :func:`_thin_shapes`): the weighted-PCA normal (eqs. 13-14) of the
    smallest of ``ks`` above k whose neighbours span the plane of that normal, lie near one
    plane (:data:`FLAT_SHARE`) and are not the line's own (:data:`LINE_TURN`); as they were
    where none does. Returns ``(normals, ok)``
    (``ok`` unchanged), new arrays when any changed.

    The PCA of one curved line is the plane of the line, not the surface: on a sphere
    scanned along parallels 8-16 spacings apart the initial normals were 70-77 degrees off
    (H 0 where it is 1, every point valid). A point whose nearest lie on a straight line has
    no normal and keeps none, and a widened neighbourhood that is not flat is not taken:
    wires and a cube's wireframe are curves, not a surface (widened without those tests, 3.3
    and 5.5x as many of a wireframe's points got normals, and |k| of 1e5)."""
    spread, weighted, flat = _thin_shapes(pts, normals, nb, k)
    spans = ~(spread < LINE_SPREAD) if k <= nb.width else spans_plane(pts, normals, nb, np.full(len(pts), k), LINE_SPREAD)
    line = ok & (~spans | (flat > FOLD_FLAT))
    sheet = np.zeros(len(pts), dtype=bool) if suspect is None else ok & suspect
    thin = np.flatnonzero(line | sheet | (ok & (weighted < LINE_SPREAD)))
    if not len(thin):
        return normals, ok
    normals = normals.copy()
    for start in range(0, len(thin), _CHUNK):  # chunks: 320 neighbours of 1M thin points would be 2.5 GB
        part = thin[start:start + _CHUNK]
        _widen(pts, normals, nb, part, [c for c in ks if c > k], line[part], sheet[part], nb.rows(part, k)[0])
    return normals, ok


_CHUNK = 32_768


def determined_normals(pts, normals, undetermined, nb, k: int, ks):
    """Initial normals where a point's ``k`` nearest span the plane but do not determine a
    quadric (``undetermined`` (N,) bool: its initial 2-jet was refused, a pivot below
    :data:`core.tuning.INITIAL_JET_PIVOT`): the 2-jet normal, in the frame of the weighted-PCA
    normal (eqs. 13-14), of the smallest of ``ks`` above k whose neighbours do; as they were
    where none does. Returns ``normals``, a new array when any changed.

    Two scan lines side by side span the plane, but their PCA plane is lopsided, tilted
    towards the other line over a curved patch, and a quadric is not determined across two
    lines: on a sphere scanned in 30 rings of 300 points the 15 nearest at latitudes 40-60
    degrees are the point's own ring and part of the next; their PCA normal was 11-29
    degrees off and H 0.55 where it is 1 (a third ring, at 20-28 neighbours, determines the
    jet: normals 0.03 degrees off)."""
    todo = np.flatnonzero(undetermined)
    ks = [c for c in ks if c > k]
    if not len(todo) or not ks:
        return normals
    normals = normals.copy()
    for start in range(0, len(todo), _CHUNK):
        _determine(pts, normals, nb, todo[start:start + _CHUNK], ks)
    return normals


def _determine(pts, normals, nb, todo, ks) -> None:
    """:func:`determined_normals` of the centres ``todo``, in place in ``normals``."""
    rows = _CandidateRows(nb, max(ks, default=0))
    for cand in ks:
        idx, dist = rows(todo, cand)
        frame, has = pca_normals_at(pts, todo, idx, dist)
        found, good, tilts = _jets(pts, todo, idx, dist, frame, has)
        normals[todo[tilts]] = found[tilts]  # where the jet is within its noise of the PCA plane, that is kept
        todo = todo[~good]
        if not len(todo):
            return


def _widen(pts, normals, nb, thin, ks, line, sheet, small) -> None:
    """:func:`spanning_normals` of the centres ``thin``, in place in ``normals``. Where no
    candidate turns from the line's plane and the centre is on a ``line`` ((m,) bool: its
    nearest do not span the plane unweighted, or are a tube; not only under the PCA's
    weights, where the normal may be right), the widest that passes the other tests is taken:
    its normal is within :data:`LINE_TURN` of the line's, and it spans more lines (a
    rotating scanner's ground: each noisy ring is a flat strip of the scanner's cone,
    tilted by the ray's elevation, 3-8 degrees beyond 10 m, which no candidate turns from).
    A candidate whose 2-jet is not determined (two lines: their PCA plane leans towards the
    other line) is taken only where no wider one is: near the edge of a sphere patch scanned
    along parallels 12 apart, two lines' PCA normals were 13-15 degrees off, three lines' 0.1.
    A centre neither on a line nor on a ray ``sheet`` (thin only under the PCA's weights)
    takes a candidate only where it fits the centre's own nearest ``small`` at least as well
    as its normal did (:func:`_explains`): under a scanner's tripod, where its rings are small
    circles, some turned candidates were 86 degrees off (|H| up to 124 per metre)."""
    last = np.full((len(thin), 3), np.nan)  # the widest candidate that passed all but the turn
    first = np.full((len(thin), 3), np.nan)  # the first that passed all, its 2-jet not determined
    pos = np.arange(len(thin))
    rows = _CandidateRows(nb, max(ks, default=0))
    for cand in ks:
        idx, dist = rows(thin, cand)
        idx.flags.writeable = False  # the compiled signature :func:`spreads` uses
        found, has = pca_normals_at(pts, thin, idx, dist)
        spread = np.empty(len(thin))
        before = normals[thin]
        normals[thin] = found
        plane_spread(pts, normals, thin, idx, np.arange(len(thin)), np.full(len(thin), cand), spread)
        normals[thin] = before
        turned = np.abs(np.einsum("ij,ij->i", np.nan_to_num(found), before)) < np.cos(np.radians(LINE_TURN))
        passed = has & ~(spread < THIN_SPREAD)
        passed[passed] = _surface(pts, idx[passed])
        jet, determined, tilts = _jets(pts, thin, idx, dist, found, passed, WIDEN_PIVOT)
        found[tilts] = jet[tilts]  # a curved patch's PCA plane leans where its rows are lopsided
        fits = line[pos] | sheet[pos] | ~(passed & turned)
        fits[~fits] = _explains(pts, small[pos[~fits]], found[~fits], before[~fits])
        good = passed & turned & determined & fits
        spare = passed & turned & ~determined & fits & np.isnan(first[pos, 0])
        first[pos[spare]] = found[spare]
        normals[thin[good]] = found[good]
        last[pos[passed & ~turned]] = found[passed & ~turned]
        thin, pos = thin[~good], pos[~good]
        if not len(thin):
            return
    held = np.where(np.isfinite(first[pos, :1]) | ~line[pos, None], first[pos], last[pos])
    normals[thin[np.isfinite(held[:, 0])]] = held[np.isfinite(held[:, 0])]


class _CandidateRows:
    """The rows of the centres still widened at each candidate width: those the graph holds
    read from it; of the others, the first candidate searched at its own width, the rest cut
    from one search at the ``widest`` of the centres left then (a centre's c nearest are the
    first c of its k nearest, ties by index: the same rows). A 1M sphere at 2 spacings of
    noise widens 663k points through all six candidates 56 ... 320 (4 pass below 160): a
    search per candidate was 10 of its 44 s. The centres asked for must be a subsequence of
    the ones searched wide (each chunk's thin points, ascending, fewer after each
    candidate). Returns contiguous rows (new arrays)."""

    def __init__(self, nb, widest):
        self._nb, self._widest = nb, widest
        self._searched, self._wide = False, None

    def __call__(self, centres, k):
        if k <= self._nb.width or not self._searched:
            self._searched |= k > self._nb.width
            idx, dist = self._nb.rows(centres, k)
        else:
            if self._wide is None:
                self._wide = (centres, *self._nb.rows(centres, self._widest))
            at = np.searchsorted(self._wide[0], centres)
            idx, dist = self._wide[1][at, :k], self._wide[2][at, :k]
        return np.ascontiguousarray(idx), np.ascontiguousarray(dist)


def _explains(pts, rows, found, before) -> np.ndarray:
    """(m,) bool: the points of each row of ``rows`` (a point's own nearest) lie at least as
    close to a plane normal to ``found`` as to one normal to ``before``, in RMS."""
    d = pts[rows] - pts[rows].mean(axis=1, keepdims=True)
    return (np.einsum("mki,mi->mk", d, found) ** 2).sum(1) <= (np.einsum("mki,mi->mk", d, before) ** 2).sum(1)


def _jets(pts, centres, idx, dist, frame, has, pivot=INITIAL_JET_PIVOT):
    """The 2-jet normals (Cazals & Pouget; :func:`core.normals.jet_normals`) of ``centres``
    on the rows ``idx`` / ``dist``, in the frames of the normals ``frame`` where ``has``:
    ``(normals, good, tilts)``, good False where the jet is not determined
    (its scaled normal matrix's smallest eigenvalue at most ``pivot``) or there was no frame, tilts True where the jet
    tilts the frame's normal beyond what its residual explains (:data:`JET_SIGNIFICANCE`
    standard errors of its slope): the frame is biased, not the jet noisy."""
    frame = np.where(has[:, None], frame, (0.0, 0.0, 1.0))  # any frame: a row without a normal is not kept
    t1, t2 = tangent_basis(frame)
    m = len(centres)
    found, height, good, se = np.empty((m, 3)), np.empty(m), np.empty(m, dtype=bool), np.empty(m)
    kernels.jet_normals(pts, idx, np.ascontiguousarray(dist[:, -1]), centres, t1, t2, frame, pivot,
                        found, height, good, se)
    good &= has & (dist[:, -1] > 0)
    tilts = np.zeros(m, dtype=bool)
    cos = np.abs(np.einsum("ij,ij->i", found[good], frame[good]))  # rows not fitted hold no jet
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        slope = np.sqrt(np.maximum(1.0 - cos * cos, 0.0)) / cos  # |(c1, c2)|: the jet's tilt
        tilts[good] = slope > JET_SIGNIFICANCE * se[good]
    return found, good, tilts


#: a point's initial normal is looked at again (widened) where the plane spread of its k
#: nearest in the plane of that normal is below this: a *noisy* line's PCA plane holds the
#: line and its noise, so its spread there is the noise over the line's length, not 0. A
#: floor scanned from 1.5 m with 2 mm range noise: under the scanner the rings are 13x farther
#: apart than the points along them and a ring's 15 nearest spread 0.1-0.3 in their PCA plane,
#: which stands on the floor (normals 51 degrees off at the median within 0.2 m of the axis,
#: |H| > 1/m at 91 % of those points -> 3.4 degrees, 7.5 %). Honest samplings spread more
#: (uniform random torus, chirp, plane at 15 neighbours, noise 0 and 0.2: 1st percentile 0.47,
#: none below 0.3); a point wrongly taken for a line only tries the wider candidates, which
#: must span, be flat and turn from its plane to be taken. Both races unchanged.
LINE_SPREAD = 0.3
#: a widened normal is taken only where it turns from the line's own plane by more than this
#: (degrees): a wide arc of one ring of a cylinder scanned in rings 12-16 spacings apart spans
#: a flat plane, the ring's own, and its normal stays 90 degrees off (it is kept as it was)
LINE_TURN = 10.0
#: a widened neighbourhood's 2-jet replaces its PCA normal only where it tilts it by more than
#: this many standard errors of its slope (from its residual): on exact scan lines the PCA
#: plane of lopsided rows leans (a sphere in rings: 4-11 degrees at latitudes 50-70) and the
#: jet's residual is nil; with noise along the lines the jet across them is the noisier of the
#: two (stripes 20 spacings apart, noise 0.1: mean |H error| 0.13 with PCA, 0.30 with jets).
JET_SIGNIFICANCE = 2.0
#: a widened neighbourhood is taken where its 2-jet is determined with pivots above this
#: (else a wider one is looked for, and it is taken only where none is): two scan lines leave
#: the quadric's term across them undetermined, their PCA plane leans towards the other line
#: (13-15 degrees off near the edge of a sphere patch along parallels 12 apart), and a
#: scanner's jitter along them passes core.tuning.INITIAL_JET_PIVOT with jets 10-47 degrees
#: off (the end ring of a cylinder scanned in rings: 8-36 % of its points at 1e-4, 1 % at 1e-2,
#: 0 at 3e-2); three lines' pivots pass 1e-2 (all at 40+ neighbours).
WIDEN_PIVOT = 1e-2
#: a point's initial normal is looked at again (widened) where, with the scanner's viewpoint
#: given, the ray to it lies within this many degrees of the normal's plane (:func:`ray_sheets`):
#: a ring of a rotating scanner spread along its rays by range noise, 0.1-0.3 degrees; the
#: ground it scans meets the rays at 3.6-25 degrees
RAY_SHEET = 1.0
#: a widened neighbourhood is a surface when its points lie this close to their plane:
#: sqrt(lambda_min / lambda_mid) of their scatter at most this (a smooth patch of scan lines
#: is flat at its scale: 0.02-0.09 on the sphere above at 56-160 neighbours; a cube's
#: wireframe corner, three edges, is not)
FLAT_SHARE = 0.3
#: ... and does not lie along one curve in that plane: the RMS residual of a quartic fitted
#: across the curve's widest axis, over the spread across it, above this. A long arc of one
#: scan line spans its own plane, and with noise its short arc's PCA normal (the "before" the
#: turn test compares with) is any normal of the line: on a torus scanned along 16 parallels
#: with noise 0.06 of the spacing on its inner equator the arc of 40 nearest was taken (86
#: degrees off). One arc, noise 0.06: 0.05-0.28 (20-40 neighbours); uniform torus, 20-320
#: neighbours: 0.1st percentile 0.63; three lines: 0.53 and up.
CURVE_SHARE = 0.35


def ray_sheets(pts, normals, view) -> np.ndarray | None:
    """(N,) bool: the plane of a point's normal holds the ray from the scanner's viewpoint
    ``view`` (a (3,) tuple, or each point's own, (N, 3); None for any other orientation:
    ``EstimatePlan.mode``) within :data:`RAY_SHEET` degrees.
    A surface seen from a scanner meets its rays at an angle; range noise wider than the
    points are apart along a scan line spreads the line into a sheet along the rays (a
    rotating scanner's ground within 10 m: normals tilted by the ray's elevation, 15-25
    degrees, with the ray 0.1-0.3 degrees from their plane at 15-28 neighbours)."""
    if view is None or isinstance(view, str):
        return None
    ray = pts - np.asarray(view)
    with np.errstate(invalid="ignore", divide="ignore"):
        ray /= np.linalg.norm(ray, axis=1, keepdims=True)
        return np.abs(np.einsum("ij,ij->i", ray, np.nan_to_num(normals))) < np.sin(np.radians(RAY_SHEET))


def _thin_shapes(pts, normals, nb, k):
    """(spread, weighted, flat), (N,) each, of every point's ``k`` nearest, in one read of
    each row (:func:`core.kernels.spread.thin_shapes`; three passes before, the same bits):

    - spread: the plane spread (:func:`spreads`), below :data:`LINE_SPREAD` on a line;
    - weighted: the plane spread with each neighbour weighted as the PCA normal weighs it
      (eq. 14), below :data:`LINE_SPREAD` where a scan line's k nearest reach the next line by
      a few points: those are the farthest and weigh about 1e-3, so they span the plane but
      the normal is the line's alone (stripes 10 apart with noise 0.1: 86 % of the initial
      normals more than 5 degrees off, half of them not thin unweighted; honest samplings at
      15-28 neighbours, noise 0-0.5: below 0.3 at most 0.08 %);
    - flat: sqrt(lambda_min / lambda_mid) of the scatter, above :data:`core.tuning.FOLD_FLAT`
      where the k nearest are about as wide both ways across their plane: a noisy scan
      line's tube, whose PCA plane is any plane through the line (a sphere in rings with
      noise 0.1 of their spacing: normals 27 degrees off at the 90th percentile, 14 widened;
      corpus: 1 better, none worse). A fold or a corner is not flat either, but no widened
      neighbourhood of it is flat, so it keeps its normal."""
    out = np.empty((3, len(pts)))
    rows = nb.take(k)  # once: a graph served from another (one_sheet) copies it per call
    normals = np.ascontiguousarray(normals, dtype=np.float64)
    for start in range(0, len(pts), 131_072):
        idx, dist = (np.ascontiguousarray(a[start:start + 131_072]) for a in rows)
        stop = start + len(idx)
        thin_shapes(pts, normals, start, idx, dist, THETA_REACH, out[0, start:stop], out[1, start:stop], out[2, start:stop])
    return out[0], out[1], out[2]


def _surface(pts, idx, *, curve=True) -> np.ndarray:
    """(m,) bool: the points of each row of ``idx`` lie near one plane (:data:`FLAT_SHARE`)
    and (with ``curve``) not along one curve in it (:data:`CURVE_SHARE`)."""
    flat, along = np.empty(len(idx)), np.empty(len(idx))
    curve_shares(pts, np.ascontiguousarray(idx), flat, along)
    return (flat <= FLAT_SHARE) & ~(curve & (along <= CURVE_SHARE))
