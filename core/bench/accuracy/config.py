"""The accuracy race's settings: shapes, noise levels, grids, column keys, labels and styles."""

from __future__ import annotations

import numpy as np

from ... import shapes
from .._table import style

#: (key of metrics.summary, short name, axis label)
QUANTITIES = (
    ("gaussian", "K", "mean |K − K_true|  (1/length²)"),
    ("mean", "H", "mean |H − H_true|  (1/length)"),
    ("direction_deg", "e1", "mean angle(e1, e1_true)  (degrees)"),
)
QUANTITY_TITLES = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H = (k1 + k2)/2",
                   "direction_deg": "principal direction e1"}
SHAPES = {
    "torus": ("torus (R = 2, r = 1)", lambda n, seed: shapes.torus(n, R=2.0, r=1.0, seed=seed)),
    "saddle": ("saddle surface", lambda n, seed: shapes.saddle(n, seed=seed)),
    "ellipsoid": ("ellipsoid (1.5, 1, 0.75; four umbilics)", lambda n, seed: shapes.ellipsoid(n, seed=seed)),
}
DEFAULT_LEVELS = (0.0, 0.05, 0.1, 0.2, 0.5, 1.0)
PAPER_K = 15
#: k grid of the oracle columns (NR, jet): about x1.4 apart
K_GRID = (15, 20, 30, 45, 60, 90, 130, 180)
#: APSS: MeshLab filter scales (x local spacing; MeshLab's default is 2) and PCA k of its normals
APSS_SCALES = (4.0, 6.0, 8.0, 11.0, 16.0)
APSS_PCA_K = (15, 30)
#: points evaluated per case (the same random subset for every method; APSS only
#: evaluates those, which keeps it affordable at large filter scales)
EVALUATE = 2000
OUTLIER_FRACTION = 0.03
#: noise level of the "why auto beats the k grid" check
COUPLING_LEVEL = 0.1
ROBUST_LEVELS = (0.1,)
OPTIONS_SHAPES = ("torus", "saddle")
OPTIONS_LEVELS = (0.1, 0.2)
QUICK = dict(points=1000, levels=(0.1,), seeds=1, k_grid=(15, 30, 60), apss_scales=(6.0, 8.0),
             apss_pca_k=(15,), evaluate=1000, options_levels=(0.1,), options_passes=(1, 2))
NOISE_UNIT = "σ of isotropic Gaussian noise, as a fraction of the mean point spacing"

# column keys, labels and plot styles
NR15, AUTO, NRBEST, JET2, JET3, APSS = "nr15", "auto", "nr_best", "jet2", "jet3", "apss"
LABELS = {NR15: "NR k=15", AUTO: "NR auto (default)", NRBEST: "NR best k", JET2: "jet2 best k",
          JET3: "jet3 best k", APSS: "APSS best"}
NFE, APSSE = "nfe", "apsse"
REF_LABELS = {NFE: "NF k=15, exact n", APSSE: "APSS best, exact n"}
ORACLES = (NRBEST, JET2, JET3, APSS)
#: jet3 has 10 coefficients: the smallest k of its grid
METHODSMIN_JET3 = 15


def _styles():
    s = {
        NR15: style("nr"),
        AUTO: dict(style("nr"), color="#d62728", marker="o", markersize=7),
        NRBEST: dict(style("nr"), linestyle="--", marker="*", markersize=9, markerfacecolor="white"),
        JET2: dict(style("jet"), marker="x"),
        JET3: dict(style("jet"), color="#2ca02c", marker="+", markersize=9),
        APSS: dict(style("apss"), color="#1f77b4", linestyle="-.", marker="s", markersize=6),
        NFE: style("nf", exact=True),
        APSSE: dict(style("apss", exact=True), color="#1f77b4"),
    }
    return s


def _seed(*parts) -> int:
    return int(np.random.SeedSequence([int(p) for p in parts]).generate_state(1)[0])


def _nanmean(x) -> float:
    x = np.asarray(x, dtype=float)
    x = x[np.isfinite(x)]
    return float(x.mean()) if len(x) else float("nan")
