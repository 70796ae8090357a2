"""Guard against a reference-counting bug of the PySide6 build in use (6.12.0).

That build drops one reference to ``None`` each time Python calls one of many
void Qt methods (``QLabel.setText``, ``QTimer.start``/``stop``, ``QWidget.update``,
``QCoreApplication.processEvents``...) or reads back an invalid ``QVariant``, and one
reference to ``True`` each time ``True`` is emitted through a Python-declared
signal. On CPython < 3.12, where these singletons are ordinary refcounted objects,
the interpreter aborts ("Fatal Python error: none_dealloc" / "bool_dealloc") once
the count reaches zero: after some ten thousand user actions, or sooner in a test
session that polls the event loop.

CPython 3.12 made ``None``, ``True`` and ``False`` immortal, which makes the bug
harmless. :func:`guard` does the same on older interpreters, and only when a probe
shows the bug: it adds a large constant to the three reference counts. They are
never deallocated anyway, so nothing else changes. The viewer's own code also
avoids the patterns (names, not values, through signals; no None item data).

GUI thread; call once a QCoreApplication exists (idempotent).

:func:`pinned_children` guards against a second fault, in the teardown of a widget tree,
and :func:`forget_surface` against a third, stale wrappers of GL surfaces: see there.
"""

from __future__ import annotations

import ctypes
import sys

import shiboken6
from PySide6.QtCore import QObject, QTimer, Signal

__all__ = ["probe", "guard", "pinned_children", "forget_surface"]

_EXTRA = 1 << 40
_done: dict = {}


def probe(n: int = 32) -> dict:
    """References to None and True lost per call of a void Qt method / a True emit."""
    class _Emitter(QObject):
        fired = Signal(object)

    timer = QTimer()
    emitter = _Emitter()
    none0 = sys.getrefcount(None)
    for _ in range(n):
        timer.stop()
    none_lost = none0 - sys.getrefcount(None)
    true0 = sys.getrefcount(True)
    for _ in range(n):
        emitter.fired.emit(True)
    true_lost = true0 - sys.getrefcount(True)
    # give back what the probe itself took
    _add(None, none_lost)
    _add(True, true_lost)
    emitter.deleteLater()
    return {"none": none_lost / n, "true": true_lost / n}


def _add(obj, count: int) -> bool:
    if count <= 0 or sys.implementation.name != "cpython" or sys.version_info >= (3, 12):
        return False
    if hasattr(sys, "gettotalrefcount"):  # debug build: a different object layout
        return False
    before = sys.getrefcount(obj)
    cell = ctypes.c_ssize_t.from_address(id(obj))  # ob_refcnt is the first field
    cell.value += count
    if sys.getrefcount(obj) != before + count:  # not the layout we expected: undo
        cell.value -= count
        return False
    return True


def guard() -> dict:
    """Probe once per process and, if references leak, make the singletons immortal."""
    if _done:
        return dict(_done)
    lost = probe()
    applied = False
    if lost["none"] > 0.5 or lost["true"] > 0.5:
        applied = all(_add(obj, _EXTRA) for obj in (None, True, False))
    _done.update(lost, applied=applied)
    return dict(_done)


def pinned_children(owner: QObject) -> list:
    """Strong references to the Python wrappers of every object created from Python under
    ``owner``; keep them until ``owner``'s wrapper goes, and Qt may delete the tree.

    PySide keeps such a wrapper alive by its own record of parents, which is not Qt's tree
    (the controls' group boxes, laid out in a panel inside a scroll area inside a dock, are
    recorded as children of the main window). When Qt deletes the tree it drops that
    record's reference, and a wrapper nothing else holds can be freed in the middle of its
    own ``Shiboken::Object::destroy``, which then reads it: the test suite's teardown
    segfaulted there (``BindingManager::releaseWrapper`` on a freed ``QGroupBox`` wrapper,
    reference count 0) in 2 of 5 runs of ``tests/app`` on a busy machine. With the wrappers
    pinned, ``destroy`` only ever lowers a count that stays above zero."""
    return [o for o in owner.findChildren(QObject) if shiboken6.createdByPython(o)]


def forget_surface(interactor) -> None:
    """Drop a closed render widget's wrapper of its GL surface from PySide's wrapper map.

    pyvistaqt's interactor keeps ``context().surface()``, a ``QSurface``: not a ``QObject``,
    so PySide is never told when Qt deletes it with the window, and its wrapper stays mapped
    to the address. An object Qt later makes there is handed back as that wrapper: the test
    suite saw ``QTableWidget.verticalHeader()`` return a ``QSurface`` (``AttributeError:
    setVisible``; every later window test erred), as ``toggleViewAction()`` and
    ``combo.model()`` once did (:class:`app.actions.DockToggle`). Called after the plotter is
    closed (its GL resources released); a later ``makeCurrent`` on it raises and is skipped,
    as pyvistaqt skips a context already gone."""
    surface = getattr(interactor, "_surface", None)
    if surface is not None and shiboken6.isValid(surface):
        shiboken6.invalidate(surface)
