"""What the viewer remembers between runs (QSettings): parameters and the dock layout.

GUI thread. The parameters of :data:`REMEMBERED` are saved when the window closes
and restored at the next start, unless given on the command line. Values read back
are validated through the state's own coercion; a corrupt entry is ignored.
"""

from __future__ import annotations

import logging

from PySide6.QtCore import QByteArray, QSettings

import core

from .fields import FIELDS

__all__ = ["REMEMBERED", "save_state", "restore_state", "save_layout", "restore_layout"]

LOG = logging.getLogger(__name__)

#: State keys remembered between runs, with the check a stored value must pass.
REMEMBERED = {
    "method": lambda v: v in core.METHODS,
    "field": lambda v: v in FIELDS,
    "k": lambda v: 3 <= int(v) <= 1000,
    "k_auto": lambda v: True,
    "passes": lambda v: 0 <= int(v) <= 20,
}

_GROUP = "viewer"


def _as(key: str, raw):
    """Stored text back to the state's type (ini files store everything as text)."""
    if key == "k_auto":
        return str(raw).lower() in ("1", "true", "yes")
    if key in ("k", "passes"):
        return int(raw)
    return str(raw)


def save_state(state, settings: QSettings) -> None:
    for key in REMEMBERED:
        settings.setValue(f"{_GROUP}/{key}", str(state.get(key)))


def restore_state(state, settings: QSettings, *, skip=()) -> dict:
    """Apply the remembered values (except ``skip``); returns what was applied."""
    values = {}
    for key, valid in REMEMBERED.items():
        name = f"{_GROUP}/{key}"
        if key in skip or not settings.contains(name):
            continue
        try:
            value = _as(key, settings.value(name))
            if valid(value):
                values[key] = value
        except (TypeError, ValueError):
            LOG.info("ignoring the remembered %s: %r", key, settings.value(name))
    state.set(**values)
    return values


def save_layout(window, settings: QSettings) -> None:
    settings.setValue(f"{_GROUP}/geometry", window.saveGeometry())
    settings.setValue(f"{_GROUP}/docks", window.saveState())


def restore_layout(window, settings: QSettings) -> bool:
    """Restore the docks (and window geometry) saved by :func:`save_layout`."""
    ok = False
    if settings.contains(f"{_GROUP}/docks"):
        docks = settings.value(f"{_GROUP}/docks")
        ok = isinstance(docks, QByteArray) and window.restoreState(docks)
    if settings.contains(f"{_GROUP}/geometry"):
        geometry = settings.value(f"{_GROUP}/geometry")
        if isinstance(geometry, QByteArray):
            window.restoreGeometry(geometry)
    return bool(ok)
