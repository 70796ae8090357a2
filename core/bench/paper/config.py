"""The paper experiment's settings: methods per figure, surfaces, noise levels, quantities."""

from __future__ import annotations

import numpy as np

from ... import shapes

#: every method run with estimated normals (columns of the tables)
METHODS = ("qp", "qn", "cf", "cn", "ct", "nf", "nr")
FIG2_4 = ("qp", "qn", "cf", "cn")
FIG2_4_EXACT = ("qp", "qn", "cf", "cn")
FIG5 = ("cf", "ct", "nf", "nr")
FIG5_EXACT = ("cf", "nf", "nr")
#: (key of metrics.summary, short name, axis label)
QUANTITIES = (
    ("gaussian", "K", "mean |K − K_true|  (1/length²)"),
    ("mean", "H", "mean |H − H_true|  (1/length)"),
    ("direction_deg", "e1", "mean angle(e1, e1_true)  (degrees)"),
)
QUANTITY_TITLES = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H = (k1 + k2)/2",
                   "direction_deg": "principal direction e1"}
DEFAULT_LEVELS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4)
QUICK = dict(points=1000, levels=(0.0, 0.4), repeats=1)
SURFACES = {
    "torus": ("torus (R = 2, r = 1)", lambda n, seed: shapes.torus(n, R=2.0, r=1.0, seed=seed)),
    "saddle": ("saddle surface (Goldfeather stand-in)", lambda n, seed: shapes.saddle(n, seed=seed)),
}
EXACT_ROW = "σ=0, exact n"
NOISE_UNIT = "σ of isotropic Gaussian noise, as a fraction of the mean point spacing"


def _seed(*parts) -> int:
    return int(np.random.SeedSequence([int(p) for p in parts]).generate_state(1)[0])
