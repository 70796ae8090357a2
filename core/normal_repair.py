"""Repair of a file's normals row by row: what a scanner left zero, NaN or unscaled.

Scanners and converters write (0, 0, 0) or NaN where they had no normal, and some store
normals that are not unit length. Refusing the whole file for a few such rows (or
trusting them) is wrong either way: rows that are merely unscaled are renormalised,
rows with no direction are estimated from their neighbours (weighted PCA, eqs. 13-14)
and given the sign that their neighbours' file normals agree on; rows that no file
normal decides (no neighbour has one: a file of zeros, a region of zeros) are oriented as
estimated normals are, consistently with the rows that keep their file sign.
"""

from __future__ import annotations

import numpy as np

from ._validate import unit_rows
from .normals import pca_normals
from .orientation import orient

#: shorter than this share of the file's median normal length a row has no direction
#: (float32 files store ~1e-7 noise where they had none). Relative, so that a file whose
#: normals are all scaled by 1e-9 (or 1e300) is merely unscaled, not empty.
MIN_LENGTH = 1e-6
#: a length farther than this from 1 counts as unscaled (float32 rounding is ~1e-7)
UNIT_TOL = 1e-3


def split_normals(normals):
    """Sort file normals into usable (after renormalising) and unusable rows.

    Returns
    -------
    unit : (N, 3) float64 unit normals, NaN rows where unusable; the input is not modified.
    usable : (N,) bool.
    counts : dict with ``"unusable"`` (zero-length, NaN or inf) and ``"renormalised"``.
    """
    arr = np.array(normals, dtype=np.float64, copy=True)
    finite = np.isfinite(arr).all(axis=1)
    arr[~finite] = 0.0
    unit, length = unit_rows(arr)
    typical = _lower_median(length[length > 0])
    usable = finite & (length > 0) & (length > MIN_LENGTH * typical)
    unscaled = usable & (np.abs(length - 1.0) > UNIT_TOL)
    unit = np.where(usable[:, None], unit, np.nan)
    counts = {"unusable": int(np.count_nonzero(~usable)), "renormalised": int(np.count_nonzero(unscaled))}
    return unit, usable, counts


def _lower_median(a: np.ndarray) -> float:
    """The lower middle value of ``a`` (0 when empty): a median without the mean of the two
    middle values, which overflows for lengths near 1e308 (normals written at that scale
    are merely unscaled)."""
    if not len(a):
        return 0.0
    mid = (len(a) - 1) // 2
    return float(np.partition(a, mid)[mid])


def repair_normals(points, normals, idx, dist, *, orientation=None, trust=False):
    """File normals with every unusable row estimated from its neighbours.

    Parameters
    ----------
    points : (N, 3) float array.
    normals : (N, 3) file normals, any length, NaN allowed.
    idx, dist : (N, K) neighbours of every point (the point first) and their distances.
    orientation : how estimated normals are oriented (:func:`core.orientation.orient`'s
        mode, e.g. "outward"), or None. A repaired row takes the sign its neighbours' file
        normals agree on; where none of its neighbours has one (a file whose normals are
        all zero, a region of zeros) no file normal decides it, and with ``orientation``
        it is oriented as estimated normals are (:func:`orient_undecided`). Without, its
        sign is the eigenvector's (arbitrary).
    trust : :func:`core.orientation.orient`'s ``trust``.

    Returns
    -------
    normals : (N, 3) unit normals; NaN only where the neighbourhood has no normal either.
        The usable rows keep their sign exactly.
    counts : dict, :func:`split_normals`'s counts plus ``"estimated"`` and, when
        ``orientation`` oriented some, ``"oriented"``: the estimated rows whose sign no file
        normal decided.
    """
    unit, usable, counts = split_normals(normals)
    rows = np.flatnonzero(~usable)
    counts["estimated"] = 0
    if not len(rows):
        return unit, counts
    est, ok = pca_normals(points, idx, dist)  # all rows: the kernel is indexed by row
    est, ok = est[rows], ok[rows]
    nb_nrm = np.nan_to_num(unit[idx[rows, 1:]])  # unusable neighbours vote 0
    vote = np.einsum("ij,ikj->i", est, nb_nrm)
    est[vote < 0] *= -1
    unit[rows] = np.where(ok[:, None], est, np.nan)
    counts["estimated"] = int(np.count_nonzero(ok))
    undecided = np.zeros(len(unit), dtype=bool)
    undecided[rows[ok & (vote == 0)]] = True
    if orientation is not None and undecided.any():
        orient_undecided(points, unit, undecided, idx, orientation, trust=trust)
        counts["oriented"] = int(np.count_nonzero(undecided))
    return unit, counts


def orient_undecided(points, normals, undecided, idx, mode, *, trust=False) -> None:
    """Orient (in place) the rows of ``normals`` (N, 3 unit, NaN rows allowed) marked
    ``undecided`` as estimated normals are, consistently with the other rows, whose signs
    are kept exactly: :func:`core.orientation.orient` with ``mode`` orients every row;
    in each of its components the undecided rows take its signs, flipped if the decided
    rows of the component mostly disagree with it (the decided signs carried through the
    neighbour graph). A component with no decided row keeps ``mode``'s signs ("outward":
    facing away from the cloud's centre)."""
    has = np.isfinite(normals).all(axis=1)
    out = orient(points, normals, idx, mode, ok=has, trust=trust)
    agree = np.sign(np.einsum("ij,ij->i", np.nan_to_num(out.normals), np.nan_to_num(normals)))
    labels = out.labels
    decided = has & ~undecided & (labels >= 0)
    n_labels = int(labels.max()) + 1 if (labels >= 0).any() else 0
    tally = np.bincount(labels[decided], agree[decided], minlength=n_labels)
    rows = np.flatnonzero(undecided & has & (labels >= 0))
    flip = np.where(tally[labels[rows]] < 0, -1.0, 1.0)
    normals[rows] = out.normals[rows] * flip[:, None]
