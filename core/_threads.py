"""How numba's worker threads wait between parallel loops, chosen before the first loop runs.

numba runs its parallel loops on OpenMP (libgomp), which reads ``OMP_WAIT_POLICY`` once,
when it is loaded: at the first parallel kernel, after ``import core``. The environment's
own value wins (a user who wants spinning workers sets ``OMP_WAIT_POLICY=ACTIVE``); see
:data:`core.tuning.OMP_WAIT_POLICY` for what spinning cost. Only how threads wait changes,
never what they compute.
"""

from __future__ import annotations

import os

from .tuning import OMP_WAIT_POLICY


def configure() -> str:
    """Set ``OMP_WAIT_POLICY`` unless the environment has; returns the policy in force."""
    return os.environ.setdefault("OMP_WAIT_POLICY", OMP_WAIT_POLICY)
