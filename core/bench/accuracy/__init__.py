"""The accuracy race (issue 4): NR against MeshLab's APSS and jet fitting on analytic shapes.

Random points on a torus, the saddle surface and an ellipsoid (umbilics included), isotropic
Gaussian noise of 0, 0.05, 0.1 and 0.2 of the mean spacing, several seeds. For every case
the mean absolute error of K, H and the principal direction e1 (``core.metrics.summary``)
of:

* **NR k=15** — the paper's setting; **NR auto** — ``core.estimate(points)`` with no
  parameter set (``k="auto"``);
* **NR best k**, **jet2/jet3 best k** — the same estimators at the k of a grid that has
  the smallest error, chosen per (shape, noise level, quantity) *with the ground truth*:
  an oracle that no user has;
* **APSS best** — MeshLab's APSS curvature (pymeshlab, optional; :mod:`core.bench.apss`)
  given our weighted-PCA normals oriented outward (the normals NR starts from) at the best
  of a grid of PCA k, and the best of a grid of filter scales, chosen the same way.

Reference rows at σ = 0 give NF and APSS the exact normals. Two more tables: robustness
(3 % of the points moved far off the surface, error on the other points) and NR's
options (weights, symmetry constraint, refinement passes) on the torus and the saddle.

Modules: :mod:`.config` (settings), :mod:`.cases` (samples, sweeps), :mod:`.experiment`
(the runs), :mod:`.tables`, :mod:`.verdicts` (targets, summary), :mod:`.plots`,
:mod:`.report` (accuracy.md), :mod:`.cli`. ``python -m core bench accuracy`` calls
:func:`main`; :func:`run` returns the numbers.
"""

from .cases import AccuracyRun, Case, ShapeTable, _sweep
from .cli import main, parser
from .config import (APSS, APSSE, AUTO, JET2, JET3, LABELS, NFE, NR15, NRBEST, QUANTITIES, SHAPES)
from .experiment import run
from .plots import plot
from .report import markdown
from .tables import text_tables
from .verdicts import reading, targets

__all__ = ["run", "main", "parser", "AccuracyRun", "Case", "ShapeTable", "QUANTITIES", "SHAPES", "LABELS", "NR15",
           "AUTO", "NRBEST", "JET2", "JET3", "APSS", "NFE", "APSSE", "text_tables", "reading", "targets", "plot",
           "markdown", "_sweep"]
