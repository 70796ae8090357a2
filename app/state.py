"""The one observable state object: the parameters the user set.

The estimate keys are the fields of :class:`app.request.EstimateRequest`
(:data:`app.request.ESTIMATE_KEYS`). Widgets bind to it both ways: a widget writes with ``state.set(name=value)`` (or
attribute assignment) and listens to :attr:`ViewerState.changed`, updating itself
with its own signals blocked (see :func:`app.widgets._bind.blocked`). Everything
here runs on the GUI thread.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from PySide6.QtCore import QObject, Signal

from core.tuning import AUTO_PASSES

__all__ = ["ViewerState", "ORIENTATIONS"]


@dataclass(frozen=True)
class _Field:
    default: Any
    coerce: Callable[[Any], Any] | None = None


def _opt_str(v):
    return None if v in (None, "", "none", "off") else str(v)


def _clim(v):
    if v is None:
        return None
    lo, hi = (float(x) for x in v)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ValueError(f"colour limits must be finite, got {v!r}")
    if hi < lo:
        lo, hi = hi, lo
    return (lo, hi)


def _opt_int(v):
    return None if v is None else int(v)


#: Orientation modes the viewer offers (core.estimate's ``orientation``); a viewpoint is an (x, y, z) tuple.
ORIENTATIONS = ("auto", "propagate", "keep")


def _orientation(v):
    """A mode of :data:`ORIENTATIONS`, or a viewpoint as a tuple of 3 finite floats (hashable)."""
    if isinstance(v, str):
        if v not in ORIENTATIONS:
            raise ValueError(f"orientation {v!r} is invalid; must be one of {', '.join(ORIENTATIONS)} or (x, y, z)")
        return v
    view = tuple(float(x) for x in v)
    if len(view) != 3 or not np.isfinite(view).all():
        raise ValueError(f"a viewpoint must be 3 finite numbers, got {v!r}")
    return view


class ViewerState(QObject):
    """Observable viewer parameters.

    Signals
    -------
    changed(name: str)
        Emitted once per changed attribute (after a :meth:`batch`, once per
        changed attribute); listeners read the new value from the state.

        The value is deliberately not sent through the signal: with the PySide6
        build in use, emitting Python ``True`` through a Python-declared signal
        drops a reference to ``True`` on every emit (the interpreter aborts with
        ``bool_dealloc`` after a few thousand toggles). Names only are safe.
    """

    changed = Signal(str)

    FIELDS: dict[str, _Field] = {
        # the cloud (an app.source.CloudSource; compared by identity)
        "source": _Field(None),
        # estimation
        "k": _Field(15, int),
        "k_auto": _Field(True, bool),  # core's k="auto" (NF/NR); the slider's k otherwise
        "method": _Field("nr", str),
        "passes": _Field(AUTO_PASSES, int),  # core's default with k="auto"
        "noise": _Field(0.0, float),  # sigma, % of the mean point spacing
        "use_input_normals": _Field(True, bool),
        "compare_method": _Field(None, _opt_str),
        "orientation": _Field("auto", _orientation),  # core's orientation, or a viewpoint (x, y, z)
        # display
        "field": _Field("mean", str),
        "clim_auto": _Field(True, bool),
        "clim": _Field(None, _clim),
        "clip_percent": _Field(2.0, float),
        "point_size": _Field(5.0, float),
        "show_e1": _Field(False, bool),
        "show_e2": _Field(False, bool),
        "show_normals": _Field(False, bool),
        "glyph_density": _Field(0.05, float),  # fraction of the glyph positions (app.glyphs.GLYPH_POINTS at most)
        "glyph_length": _Field(3.0, float),  # x mean point spacing
        "eye_dome": _Field(False, bool),  # eye-dome lighting (depth edges, for scans)
        "scanners": _Field(True, bool),  # markers at an E57 or PTX file's scanner positions
        # inspection
        "picked": _Field(None, _opt_int),
    }

    def __init__(self, parent: QObject | None = None, **values):
        super().__init__(parent)
        self._values = {name: f.default for name, f in self.FIELDS.items()}
        self._batch_depth = 0
        self._pending: dict[str, Any] = {}
        if values:
            self._values.update(self._coerced(values))

    # -- access -------------------------------------------------------------
    def __getattr__(self, name):
        values = self.__dict__.get("_values")
        if values is not None and name in values:
            return values[name]
        raise AttributeError(name)

    def __setattr__(self, name, value):
        if name in type(self).FIELDS:
            self.set(**{name: value})
        else:
            super().__setattr__(name, value)

    def get(self, name: str):
        return self._values[name]

    def as_dict(self) -> dict:
        return dict(self._values)

    def _coerced(self, values: dict) -> dict:
        out = {}
        for name, value in values.items():
            try:
                spec = self.FIELDS[name]
            except KeyError:
                raise AttributeError(f"ViewerState has no parameter {name!r}; valid: {', '.join(self.FIELDS)}") from None
            out[name] = spec.coerce(value) if (spec.coerce and value is not None) else value
        return out

    @staticmethod
    def _same(a, b) -> bool:
        if a is b:
            return True
        if type(a) is not type(b):
            return False
        if isinstance(a, (int, float, str, bool, tuple)):
            return a == b
        return False  # objects (the source) compare by identity

    def set(self, **values) -> None:
        """Set one or more parameters; emits :attr:`changed` for each that changed."""
        for name, value in self._coerced(values).items():
            if self._same(self._values[name], value):
                continue
            self._values[name] = value
            if self._batch_depth:
                self._pending[name] = value
            else:
                self.changed.emit(name)

    @contextlib.contextmanager
    def batch(self):
        """Apply several changes, then emit them (once each) when the block ends.

        Listeners that react to "any estimate parameter changed" are debounced, so
        a batch costs one estimate.
        """
        self._batch_depth += 1
        try:
            yield self
        finally:
            self._batch_depth -= 1
            if not self._batch_depth:
                pending, self._pending = self._pending, {}
                for name in pending:
                    self.changed.emit(name)
