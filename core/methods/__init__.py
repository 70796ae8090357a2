"""The registry of curvature estimators (scipy ``integrate.solve_ivp``-style METHODS).

Each method fits, per point, the normal at p and its derivatives in the local frame of
a :class:`core.patch.Chunk`, returning a :class:`MethodFit` ``(mu, W, ok, diag)`` for the
shared :func:`core.frame.darboux_frame`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from .._validate import word
from . import cubic, jet, normal_fit, quadric, tensor
from ._result import MethodFit

__all__ = ["METHODS", "Method", "MethodFit", "get_method", "check_options"]


@dataclass(frozen=True)
class Method:
    """A registered estimator.

    Attributes
    ----------
    name : registry key, e.g. ``"nr"``.
    title : short label for menus.
    description : one paragraph, with the paper's equations.
    fit : ``fit(chunk, **options) -> MethodFit``.
    default_passes : normal refinement passes run by default (NR: 1).
    options : default values of the method's options.
    min_k : smallest neighbourhood that determines the fit.
    min_k_of : optional ``min_k_of(**options) -> int`` where the options change it.
    check : optional ``check(**options)`` raising ValueError on a value the fit refuses.
    auto_k : whether k="auto" (a per-point k, :mod:`core.scale`) applies: the ICI rule
        reads the confidence intervals of the normal fit, so NF and NR only.
    """

    name: str
    title: str
    description: str
    fit: Callable
    default_passes: int = 0
    options: dict = field(default_factory=dict)
    min_k: int = 3
    min_k_of: Callable | None = None
    check: Callable | None = None
    auto_k: bool = False

    def min_k_for(self, options: dict) -> int:
        """Smallest neighbourhood that determines the fit with these options."""
        return max(self.min_k, self.min_k_of(**options)) if self.min_k_of else self.min_k

    @property
    def uses_passes(self) -> bool:
        """Whether refinement passes make sense (methods that refine the normal)."""
        return self.name in ("nf", "nr", "jet")


def _registry():
    nf_opts = dict(normal_fit.DEFAULTS)
    entries = [
        Method("nr", "NR – normal fitting + refinement", normal_fit.NR_DOC, normal_fit.fit, 1, nf_opts, 4, normal_fit.min_k,
               normal_fit.check, auto_k=True),
        Method("nf", "NF – normal fitting", normal_fit.NF_DOC, normal_fit.fit, 0, nf_opts, 4, normal_fit.min_k,
               normal_fit.check, auto_k=True),
        Method("ct", "CT – curvature tensor", tensor.DOC, tensor.fit, 0, {}, 3),
        Method("qp", "QP – quadric fit to points", quadric.QP_DOC, quadric.fit_points, 0, {}, 4),
        Method("qn", "QN – quadric fit to normals", quadric.QN_DOC, quadric.fit_normals, 0, {}, 3),
        Method("cf", "CF – cubic fit to points + normals", cubic.CF_DOC, cubic.fit_points_normals, 0, {}, 4),
        Method("cn", "CN – cubic fit to normals", cubic.CN_DOC, cubic.fit_normals, 0, {}, 5),
        Method("jet", "Jet – osculating jet (Cazals–Pouget)", jet.DOC, jet.fit, 0, dict(jet.DEFAULTS), 10,
               check=jet.check),
    ]
    return {m.name: m for m in entries}


METHODS: dict[str, Method] = _registry()


def get_method(method) -> Method:
    """Look a method up by name (case-insensitive); unknown names list the valid ones."""
    if isinstance(method, Method):
        return method
    name = word(method)
    if isinstance(name, str) and name in METHODS:
        return METHODS[name]
    raise ValueError(f"method {method!r} is unknown; valid methods are: {', '.join(METHODS)}")


def check_options(method: Method, options) -> dict:
    """Merge user options over the method's defaults; unknown keys and values the method
    refuses are an error (ValueError naming the option, the value and what is allowed)."""
    if options is not None and not isinstance(options, dict):
        raise ValueError(f"options must be a dict of method options or None, got {options!r}")
    options = dict(options or {})
    unknown = sorted(set(options) - set(method.options))
    if unknown:
        allowed = ", ".join(sorted(method.options)) or "none"
        raise ValueError(
            f"option(s) {unknown} do not apply to method {method.name!r}; its options are: {allowed}"
        )
    merged = {**method.options, **{key: word(value) for key, value in options.items()}}
    if method.check is not None:
        method.check(**merged)
    return merged
