"""``python -m core bench holdout``: the automatic scale on surfaces it was not tuned on (issue 15).

About 6000 points on each analytic surface of a set (:mod:`.surfaces`: ``holdout`` are
surfaces that are not in :mod:`core.shapes` and that no constant of the rule was tuned on;
``tuning`` the core.shapes families it may be tuned on; ``private`` four more surfaces with
exact truth, a check of a mechanism before it meets the hold-out), noise of 0/0.1/0.2/0.5 mean spacing,
the open patches' borders left out, errors of K, H and e1 on the same 1500 points for every
method. Each (surface, noise, quantity) cell compares the default, ``estimate(points)``, with
the best peer *at its best setting, picked with the truth*: jets of degree 2 and 3 on k =
15..240 neighbours, APSS (MeshLab) at filter scales 2..16 with PCA normals oriented by the
truth, NR at k = 15. Printed: the ratio default / best per cell, and the number of cells
lost (ratio > 1), far lost (> 1.10), the worst and the geometric mean ratio (issue 15's
targets: at most 8 of 84 hold-out cells lost, none over 1.10).

The oracles do not depend on the rule: ``--cache FILE`` keeps their errors between runs,
so a change of the rule is re-measured in about a minute. ``--probe`` (:mod:`.probe`) prints,
instead of the race, where the default's principal direction comes from with noise and
what the alternatives would give.
"""

from .cli import main, parser
from .harness import score
from .surfaces import HOLDOUT, PRIVATE, SETS, TUNING

__all__ = ["main", "parser", "score", "HOLDOUT", "TUNING", "PRIVATE", "SETS"]
