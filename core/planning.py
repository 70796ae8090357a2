"""The plan of an estimate: every argument checked and every default resolved, once.

:func:`plan` (or :meth:`EstimatePlan.build`) turns what a user asked for into a frozen
:class:`EstimatePlan`; :func:`core.estimate` then only runs stages. A caller can ask the
plan the library's rules instead of re-deriving them (``plan.k_search``: how many
neighbours the request needs) and can fix, through it, the quantities an estimate
otherwise measures on the whole cloud (``noise``, ``crease_typical``), as an estimate
of one tile of a large cloud must.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from . import scale
from ._validate import check_int, word
from .methods import METHODS, Method, check_options, get_method
from .tuning import AUTO_PASSES, MAX_PASSES, PCA_K

_ORIENTATIONS = ("auto", "propagate", "outward", "keep")
#: the plan's ``orientation`` when each point faces a viewpoint of its own (an (N, 3) array
#: passed as :func:`core.estimate`'s ``orientation``, or the scanner positions a cloud
#: read from an E57 file carries): the array travels beside the points, not in the plan
PER_POINT = "viewpoints"
_INITIAL = ("auto", "pca", "jet")


class _Options(dict):
    """The plan's method options: a dict that refuses changes (and pickles, unlike a
    mappingproxy, so a plan can travel to worker processes)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("the options of an EstimatePlan are read-only; make a new plan")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):
        return _Options, (dict(self),)


@dataclass(frozen=True)
class EstimatePlan:
    """What an estimate of ``n_points`` points will do, all defaults resolved.

    Attributes
    ----------
    n_points : int, points after non-finite rows were dropped.
    method : the registered :class:`core.Method`.
    options : read-only mapping, the method's options with the user's merged in (and,
        with k="auto", the automatic pipeline's robust="tukey" and degree=3 unless given).
    auto : True when k is chosen per point (:mod:`core.scale`), False for the paper's
        pipeline at one k.
    k : the user's k (an int, or "auto").
    candidates : the sizes NR's fits pick from with k="auto" (the NF rule and the floors of
        :func:`core.stages.choose_scale`; ``(k,)`` for an integer k). The jet rule's sizes
        (:func:`core.scale.jet_candidates`, which add 15) are those up to ``candidates[-1]``.
    k_search : neighbours to search per point (the largest candidate, or k).
    k_initial : neighbours of the outlier scores and the initial normals (PCA_K with
        k="auto", before the noise widens the latter; k otherwise).
    passes : refinement passes after the first fit (a maximum when ``adaptive``).
    adaptive : undo, and stop at, a pass that smooths the shape (k="auto").
    tol : stop refining once a pass turns the normals by less (degrees), or None.
    initial : "pca" or "jet", how normals are estimated when none are given.
    orientation : "propagate", "outward", "keep", a viewpoint (x, y, z) or :data:`PER_POINT`
        (each point its own viewpoint).
    orientation_label : what the result reports ("viewpoint" for a viewpoint).
    noise : float or None. The noise ratio the initial scale grows with (k="auto"); None
        measures it on this cloud (``result.params["noise"]``).
    crease_typical : float or None. The typical normal-fit residual a crease must stand
        out against; None takes this cloud's median (``result.params["crease_typical"]``).
    fold_typical : float or None. The typical spread of the small initial normals over a
        point's wide initial neighbourhood, which a fold must fall below
        (:func:`core.initial_normals.unfolded`); None takes this cloud's median
        (``result.params["fold_typical"]``; None where the initial scale did not grow).
    """

    n_points: int
    method: Method
    options: Mapping
    auto: bool
    k: object
    candidates: tuple
    k_search: int
    k_initial: int
    passes: int
    adaptive: bool
    tol: float | None
    initial: str
    orientation: object
    orientation_label: str
    noise: float | None = None
    crease_typical: float | None = None
    fold_typical: float | None = None

    @property
    def decides_signs(self) -> bool:
        """Whether the spanning forest decides the signs ("outward", "propagate"), rather than
        the caller (normals kept, one viewpoint, or each point's own)."""
        return self.orientation in ("outward", "propagate")

    @property
    def faces_viewpoints(self) -> bool:
        """Whether the normals face a viewpoint: one (x, y, z), or each point's own."""
        return not isinstance(self.orientation, str) or self.orientation == PER_POINT

    def mode(self, views=None):
        """The orientation as :func:`core.orientation.orient` reads it: ``views`` (each point's
        viewpoint, in the points' order) where the plan faces them, else ``orientation``."""
        return views if self.orientation == PER_POINT else self.orientation

    @property
    def robust(self) -> bool:
        """Whether the fit is robust (outliers then sit out the fits and the choice of k)."""
        return self.options.get("robust") is not None

    @classmethod
    def build(cls, n_points, *, k="auto", method="nr", passes=None, tol=None, initial="auto",
              orientation="auto", options=None, normals_given=False, noise=None, crease_typical=None,
              fold_typical=None):
        """Check every argument (ValueError naming it, its value and what is allowed)
        and resolve the defaults; see :func:`core.estimate` for their meaning."""
        n = check_int(n_points, name="n_points", low=3)
        m = get_method(method)
        opts = check_options(m, options)
        k = word(k)
        auto = k == "auto"
        if auto:
            ks, passes = _auto_defaults(m, n, opts, options or {}, passes)
            k_initial = min(PCA_K, ks[-1])
        else:
            if isinstance(k, str):
                raise ValueError(f'k must be an integer or "auto", got {k!r}')
            k = check_int(k, name="k", low=m.min_k_for(opts), high=n)
            ks, k_initial = (k,), k
        passes = m.default_passes if passes is None else check_int(passes, name="passes", low=0, high=MAX_PASSES)
        view, label = orientation_mode(orientation, normals_given, n_points=n)
        return cls(
            n_points=n, method=m, options=_Options(opts), auto=auto, k="auto" if auto else k,
            candidates=ks, k_search=ks[-1], k_initial=k_initial, passes=passes, adaptive=auto,
            tol=_tol(tol), initial=_initial(initial, auto), orientation=view, orientation_label=label,
            noise=_measure("noise", noise), crease_typical=_measure("crease_typical", crease_typical),
            fold_typical=_measure("fold_typical", fold_typical),
        )


def plan(n_points, **kwargs) -> EstimatePlan:
    """:meth:`EstimatePlan.build`: the frozen plan of an estimate of ``n_points`` points.

    >>> plan(10_000, k="auto").k_search, plan(10_000, k=15).k_search
    (320, 15)
    """
    return EstimatePlan.build(n_points, **kwargs)


def _auto_defaults(m, n, opts, given, passes):
    """k="auto" (NF/NR only): the candidates, and a robust cubic normal field with
    adaptive passes unless the user set them."""
    if not m.auto_k:
        able = " and ".join(sorted(name for name, method in METHODS.items() if method.auto_k))
        raise ValueError(f'k="auto" is available for methods {able}, not {m.name!r}; pass an integer k')
    ks = scale.candidates(n)
    if "robust" not in given:
        opts["robust"] = "tukey"  # free on clean data, keeps 3 % outliers from spoiling their neighbours
    if "degree" not in given:  # a cubic normal field, unless the cloud is too small for it
        opts["degree"] = scale.AUTO_DEGREE if ks[0] >= scale.AUTO_KS[0] else 1
    if passes is None and m.default_passes:
        passes = AUTO_PASSES
    return ks, passes


def _tol(tol):
    if tol is not None and not (isinstance(tol, (int, float, np.integer, np.floating))
                                and not isinstance(tol, (bool, np.bool_)) and np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a positive number of degrees or None, got {tol!r}")
    return None if tol is None else float(tol)


def _initial(initial, auto):
    initial = word(initial)
    if not isinstance(initial, str) or initial not in _INITIAL:
        raise ValueError(f"initial {initial!r} is invalid; must be one of {list(_INITIAL)}")
    if initial == "auto":
        return "jet" if auto else "pca"
    return initial


def orientation_mode(orientation, normals_given, *, n_points=None):
    """(mode, label) of a valid ``orientation``: "auto" keeps given normals and orients
    estimated ones outward; a viewpoint is (x, y, z), "viewpoint"; an (``n_points``, 3)
    array of viewpoints, one per point, or :data:`PER_POINT` is :data:`PER_POINT`. Else a
    ValueError."""
    orientation = word(orientation)
    if isinstance(orientation, str):
        if orientation not in _ORIENTATIONS + (PER_POINT,):
            raise ValueError(f"orientation {orientation!r} is invalid; must be one of {list(_ORIENTATIONS)}, a (3,) "
                             f"viewpoint or an (N, 3) array of one viewpoint per point")
        if orientation == "auto":
            return ("keep" if normals_given else "outward"), orientation
        return orientation, orientation
    try:
        view = np.asarray(orientation, dtype=float)
    except (TypeError, ValueError):
        view = np.empty(0)
    if view.ndim == 2:
        per_point_views(view, n_points or len(view))
        return PER_POINT, PER_POINT
    if view.shape != (3,) or not np.isfinite(view).all():
        raise ValueError(f"orientation as a viewpoint must be 3 finite numbers, got {orientation!r}")
    return tuple(float(v) for v in view), "viewpoint"


def per_point_views(views, n_points) -> np.ndarray:
    """``views`` as an (``n_points``, 3) float64 array of finite viewpoints, one per point;
    else a ValueError naming the argument, what it got and what is allowed."""
    try:
        arr = np.asarray(views, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"orientation as viewpoints must be an ({n_points}, 3) array of numbers, got "
                         f"{type(views).__name__}") from None
    if arr.shape != (n_points, 3):
        raise ValueError(f"orientation as viewpoints must have shape ({n_points}, 3), one per point, got shape "
                         f"{arr.shape}")
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        raise ValueError(f"orientation as viewpoints must be finite: {int(bad.sum())} row(s) hold NaN or inf (first "
                         f"at row {int(np.flatnonzero(bad)[0])})")
    return arr


def _measure(name, value):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0 or None, got {value!r}")
    return float(value)
