"""Displayed field, colour limits and point size (bound to ``state.field``,
``clim_auto``, ``clim``, ``clip_percent``, ``point_size``). The Field box lists the
estimate's fields, then the loaded file's own (its colours, intensity, ...)."""

from __future__ import annotations

import math
import re
import sys

from PySide6.QtGui import QStandardItemModel, QValidator
from PySide6.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QHBoxLayout, QWidget

from ..fields import FIELDS
from ._bind import blocked


def _spin(lo=-1e9, hi=1e9, decimals=4, step=0.1) -> QDoubleSpinBox:
    s = QDoubleSpinBox()
    s.setRange(lo, hi)
    s.setDecimals(decimals)
    s.setSingleStep(step)
    s.setKeyboardTracking(False)  # one valueChanged when typing is done
    return s


#: What a number being typed can look like ("-", "1e", "2.5e-").
_PARTIAL = re.compile(r"[+-]?(\d*\.?\d*)([eE][+-]?\d*)?")


class LimitBox(QDoubleSpinBox):
    """A colour limit: any finite value, shown with 6 significant digits (scientific when
    large or small), and kept exactly: a box left as it was does not round its value."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setDecimals(323)  # Qt rounds a value to this many decimals: the most it allows keeps any double
        self.setRange(-sys.float_info.max, sys.float_info.max)
        self.setKeyboardTracking(False)  # one valueChanged when typing is done

    def textFromValue(self, value: float) -> str:  # noqa: N802 - Qt's name
        return f"{value:.6g}"

    def valueFromText(self, text: str) -> float:  # noqa: N802
        if text.strip() == self.textFromValue(self.value()):
            return self.value()  # what is shown of the value, not a new one
        return float(text)

    def validate(self, text: str, pos: int):
        try:
            ok = math.isfinite(float(text))
        except ValueError:
            partial = _PARTIAL.fullmatch(text.strip())
            return (QValidator.State.Intermediate if partial else QValidator.State.Invalid), text, pos
        return (QValidator.State.Acceptable if ok else QValidator.State.Invalid), text, pos


class FieldPanel(QWidget):
    """Which field colours the cloud, and how.

    Limits are robust by default (the ``clip`` % most extreme values are ignored;
    signed fields are centred on 0). Editing a limit switches to manual limits;
    choosing another field switches back to automatic ones.
    """

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        # the combo's model, held from here: fetched with combo.model() it once came back as a
        # stale wrapper of another, deleted object (a QSurface) at the same address
        self._items = QStandardItemModel(self)
        self.combo = QComboBox()
        self.combo.setModel(self._items)
        for name, spec in FIELDS.items():
            self.combo.addItem(spec.title, name)
        self.auto = QCheckBox("Robust")
        self.auto.setToolTip("Automatic limits from percentiles (signed fields centred on 0)")
        self.clip = _spin(0.0, 25.0, 1, 0.5)
        self.clip.setSuffix(" % clip")
        self.clip.setToolTip("Percent of the most extreme values left out of the automatic limits")
        self.lo, self.hi = LimitBox(), LimitBox()
        self._limits = (self.lo.value(), self.hi.value())  # the limits in use (show_limits)
        self.lo.setToolTip("Lower colour limit")
        self.hi.setToolTip("Upper colour limit")
        self.point_size = _spin(1.0, 30.0, 1, 1.0)
        self.point_size.setSuffix(" px")

        auto_row = QHBoxLayout()
        auto_row.addWidget(self.auto)
        auto_row.addWidget(self.clip)
        lim_row = QHBoxLayout()
        lim_row.addWidget(self.lo)
        lim_row.addWidget(self.hi)
        form = QFormLayout(self)
        form.setContentsMargins(0, 0, 0, 0)
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        form.addRow("Field", self.combo)
        form.addRow("Limits", auto_row)
        form.addRow("", lim_row)
        form.addRow("Point size", self.point_size)

        self._sync_all()
        self.combo.currentIndexChanged.connect(self._on_field)
        self.auto.toggled.connect(lambda on: self._state.set(clim_auto=bool(on)))
        self.clip.valueChanged.connect(lambda v: self._state.set(clip_percent=float(v)))
        self.lo.valueChanged.connect(lambda v: self._on_limits(float(v), self._limits[1]))
        self.hi.valueChanged.connect(lambda v: self._on_limits(self._limits[0], float(v)))
        self.point_size.valueChanged.connect(lambda v: self._state.set(point_size=float(v)))
        state.changed.connect(self._on_state)

    # user -> state
    def _on_field(self, index: int) -> None:
        self._state.set(field=self.combo.itemData(index), clim_auto=True)

    def _on_limits(self, lo: float, hi: float) -> None:
        """One box edited: the other limit stays the one in use, whatever its box shows."""
        self._state.set(clim_auto=False, clim=(lo, hi))

    # state -> widgets
    def _sync_all(self) -> None:
        s = self._state
        with blocked(self.combo, self.auto, self.clip, self.point_size):
            self.combo.setCurrentIndex(max(self.combo.findData(s.field), 0))
            self.auto.setChecked(s.clim_auto)
            self.clip.setValue(s.clip_percent)
            self.clip.setEnabled(s.clim_auto and self.auto.isEnabled())
            self.point_size.setValue(s.point_size)
        if s.clim is not None:
            self.show_limits(*s.clim)

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name in ("field", "clim_auto", "clip_percent", "point_size", "clim"):
            self._sync_all()

    def show_limits(self, lo: float, hi: float, *, editable: bool = True) -> None:
        """Display the limits in use (called by the window after a recolour); not ``editable``
        where no limits apply (a file's own colours, drawn as they are)."""
        span = abs(hi - lo) or 1.0
        step = 10.0 ** (math.floor(math.log10(span)) - 1) if math.isfinite(span) else 1.0
        self._limits = (float(lo), float(hi))
        with blocked(self.lo, self.hi):
            for box, v in ((self.lo, lo), (self.hi, hi)):
                box.setSingleStep(step)
                box.setValue(v)
        for widget in (self.auto, self.lo, self.hi):
            widget.setEnabled(editable)
        self.clip.setEnabled(editable and self._state.clim_auto)

    def set_file_fields(self, titles: dict) -> None:
        """List the loaded file's own fields (name -> combo text) after the estimate's, behind
        a separator, instead of the previous file's. The box keeps naming the state's field."""
        with blocked(self.combo):
            for row in reversed(range(len(FIELDS), self.combo.count())):
                self.combo.removeItem(row)
            if titles:
                self.combo.insertSeparator(self.combo.count())
            for name, title in titles.items():
                self.combo.addItem(title, name)
        self._sync_all()

    def set_available(self, names) -> None:
        """Grey out fields the current cloud cannot provide (e.g. errors without truth)."""
        for row in range(self.combo.count()):
            item = self._items.item(row)
            if self.combo.itemData(row) is not None:  # (not the separator)
                item.setEnabled(self.combo.itemData(row) in names)
        if self.combo.currentData() not in names:
            self.combo.setToolTip("This field is not available for the current cloud")
        else:
            self.combo.setToolTip("")
