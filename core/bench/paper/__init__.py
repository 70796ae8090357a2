"""The paper's experiment: Cheng & Zhang (2009), §3 and §5, Figures 2–5.

Random points on a torus (R = 2, r = 1) and on a closed surface with saddles (standing in
for Goldfeather & Interrante's surface), k = 15 neighbours, isotropic Gaussian noise of
increasing standard deviation. For every method the mean absolute error of the Gaussian
curvature K, of the mean curvature H and of the principal direction e1 (degrees) is
averaged over ``repeats`` independent samples.

* Figures 2–4 (§3): the same surface fitted to points or to normals — QP, QN, CF, CN with
  normals estimated by weighted PCA, plus QPE, QNE, CFE, CNE: noise-free points with the
  exact normals.
* Figure 5 (§5): CF, CT, NF, NR with estimated normals, plus CFE, NFE, NRE.

Modules: :mod:`.config`, :mod:`.experiment` (the runs), :mod:`.tables`, :mod:`.plots`,
:mod:`.verdicts` (the paper's claims checked), :mod:`.report` (paper.md), :mod:`.cli`.
``python -m core bench paper`` calls :func:`main`; :func:`run` returns the numbers.
"""

from .cli import main, parser
from .config import (DEFAULT_LEVELS, EXACT_ROW, FIG2_4, FIG2_4_EXACT, FIG5, FIG5_EXACT, METHODS, NOISE_UNIT, QUANTITIES,
                     QUICK, SURFACES)
from .experiment import PaperRun, SurfaceTable, run
from .plots import plot
from .report import markdown
from .tables import table_rows, text_tables
from .verdicts import reading

__all__ = ["run", "main", "parser", "PaperRun", "SurfaceTable", "METHODS", "FIG2_4", "FIG2_4_EXACT", "FIG5",
           "FIG5_EXACT", "QUANTITIES", "DEFAULT_LEVELS", "QUICK", "SURFACES", "EXACT_ROW", "NOISE_UNIT", "plot",
           "markdown", "table_rows", "text_tables", "reading"]
