"""The one frozen request an estimate is made from, built from the viewer state.

Its parameter fields are the state's estimate keys: :data:`ESTIMATE_KEYS` is derived
from this class once, so a parameter is listed in one place (issue 9). Pure data,
no Qt: a worker thread reads it safely.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from core.planning import plan

from .source import CloudSource

__all__ = ["EstimateRequest", "ESTIMATE_KEYS", "AUTO_METHODS"]

#: Methods for which core accepts k="auto" (core.estimate raises for the others).
AUTO_METHODS = frozenset({"nf", "nr"})

#: Fields of a request that are not user parameters (set by the controller).
_CONTROL = frozenset({"gen", "seed"})


@dataclass(frozen=True)
class EstimateRequest:
    """Everything one estimate needs; immutable so a worker can read it safely."""

    gen: int
    source: CloudSource
    k: int = 15
    k_auto: bool = False
    method: str = "nr"
    passes: int | None = None
    noise: float = 0.0  # sigma in % of mean spacing
    use_input_normals: bool = True
    compare_method: str | None = None
    orientation: str | tuple = "auto"  # core's mode, or a viewpoint (x, y, z) tuple (hashable)
    seed: int = 0

    @classmethod
    def from_state(cls, state, gen: int) -> "EstimateRequest":
        """The request for the state's current parameters (GUI thread)."""
        return cls(gen=gen, **{key: state.get(key) for key in ESTIMATE_KEYS})

    def k_for(self, method: str):
        """What core.estimate gets as k: "auto" where the method supports it."""
        return "auto" if self.k_auto and method in AUTO_METHODS else int(self.k)

    def k_needed(self, n_points: int) -> int:
        """Neighbours the request needs cached on ``n_points``: the library's plan says
        (``core.planning.plan(...).k_search``), for the method and the compared one.

        Raises ValueError (from the plan) when the request cannot run on ``n_points``.
        """
        methods = [self.method] + ([self.compare_method] if self.compare_method else [])
        return max(plan(n_points, k=self.k_for(m), method=m).k_search for m in methods)

    @property
    def cloud_key(self) -> tuple:
        """Identifies the (possibly noisy) point set the neighbours belong to."""
        return (self.source.uid, round(float(self.noise), 6), self.seed)

    @property
    def heavy(self) -> bool:
        """Whether some run uses automatic k (the expensive pipeline)."""
        return self.k_auto and self.method in AUTO_METHODS


#: Changing any of these state keys asks for a new estimate (debounced).
ESTIMATE_KEYS = frozenset(f.name for f in dataclasses.fields(EstimateRequest)) - _CONTROL
