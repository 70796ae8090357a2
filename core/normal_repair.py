"""Repair of a file's normals row by row: what a scanner left zero, NaN or unscaled.

Scanners and converters write (0, 0, 0) or NaN where they had no normal, and some store
normals that are not unit length. Refusing the whole file for a few such rows (or
trusting them) is wrong either way: rows that are merely unscaled are renormalised,
rows with no direction are estimated from their neighbours (weighted PCA, eqs. 13-14)
and given the sign that their neighbours' file normals agree on.
"""

from __future__ import annotations

import numpy as np

from ._validate import unit_rows
from .normals import pca_normals

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
    typical = np.median(length[length > 0]) if (length > 0).any() else 0.0
    usable = finite & (length > 0) & (length > MIN_LENGTH * typical)
    unscaled = usable & (np.abs(length - 1.0) > UNIT_TOL)
    unit = np.where(usable[:, None], unit, np.nan)
    counts = {"unusable": int(np.count_nonzero(~usable)), "renormalised": int(np.count_nonzero(unscaled))}
    return unit, usable, counts


def repair_normals(points, normals, idx, dist):
    """File normals with every unusable row estimated from its neighbours.

    Parameters
    ----------
    points : (N, 3) float array.
    normals : (N, 3) file normals, any length, NaN allowed.
    idx, dist : (N, K) neighbours of every point (the point first) and their distances.

    Returns
    -------
    normals : (N, 3) unit normals; NaN only where the neighbourhood has no normal either.
    counts : dict, :func:`split_normals`'s counts plus ``"estimated"``.
    """
    unit, usable, counts = split_normals(normals)
    rows = np.flatnonzero(~usable)
    if len(rows):
        est, ok = pca_normals(points, idx, dist)  # all rows: the kernel is indexed by row
        est, ok = est[rows], ok[rows]
        nb_nrm = np.nan_to_num(unit[idx[rows, 1:]])  # unusable neighbours vote 0
        vote = np.einsum("ij,ikj->i", est, nb_nrm)
        est[vote < 0] *= -1
        unit[rows] = np.where(ok[:, None], est, np.nan)
        counts["estimated"] = int(np.count_nonzero(ok))
    else:
        counts["estimated"] = 0
    return unit, counts
