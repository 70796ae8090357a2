"""What every method's ``fit`` returns."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class MethodFit(NamedTuple):
    """The fit of a chunk of M points, for :func:`core.frame.darboux_frame`.

    mu : (M, 2) normal components at p in the local frame; W : (M, 2, 2) the normal's
    derivatives (eq. 21) in units of 1/h; ok : (M,) bool; diag : dict of per-point
    diagnostics ("var", "rms", "spread" for the normal fit) or None.
    """

    mu: np.ndarray
    W: np.ndarray
    ok: np.ndarray
    diag: dict | None = None
