"""The paper experiment's settings: methods per figure, surfaces, noise levels, quantities."""

from __future__ import annotations

from ... import shapes
from .._common import NOISE_UNIT, QUANTITIES, QUANTITY_TITLES, seed_of

#: every method run with estimated normals (columns of the tables)
METHODS = ("qp", "qn", "cf", "cn", "ct", "nf", "nr")
FIG2_4 = ("qp", "qn", "cf", "cn")
FIG2_4_EXACT = ("qp", "qn", "cf", "cn")
FIG5 = ("cf", "ct", "nf", "nr")
FIG5_EXACT = ("cf", "nf", "nr")
DEFAULT_LEVELS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4)
QUICK = dict(points=1000, levels=(0.0, 0.4), repeats=1)
SURFACES = {
    "torus": ("torus (R = 2, r = 1)", lambda n, seed: shapes.torus(n, R=2.0, r=1.0, seed=seed)),
    "saddle": ("saddle surface (Goldfeather stand-in)", lambda n, seed: shapes.saddle(n, seed=seed)),
}
EXACT_ROW = "σ=0, exact n"


_seed = seed_of
