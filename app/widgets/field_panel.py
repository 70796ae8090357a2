"""Displayed field, colour limits and point size (bound to ``state.field``,
``clim_auto``, ``clim``, ``clip_percent``, ``point_size``)."""

from __future__ import annotations

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


class FieldPanel(QWidget):
    """Which field colours the cloud, and how.

    Limits are robust by default (the ``clip`` % most extreme values are ignored;
    signed fields are centred on 0). Editing a limit switches to manual limits;
    choosing another field switches back to automatic ones.
    """

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        self.combo = QComboBox()
        for name, spec in FIELDS.items():
            self.combo.addItem(spec.title, name)
        self.auto = QCheckBox("Robust")
        self.auto.setToolTip("Automatic limits from percentiles (signed fields centred on 0)")
        self.clip = _spin(0.0, 25.0, 1, 0.5)
        self.clip.setSuffix(" % clip")
        self.clip.setToolTip("Percent of the most extreme values left out of the automatic limits")
        self.lo, self.hi = _spin(), _spin()
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
        self.lo.valueChanged.connect(self._on_limits)
        self.hi.valueChanged.connect(self._on_limits)
        self.point_size.valueChanged.connect(lambda v: self._state.set(point_size=float(v)))
        state.changed.connect(self._on_state)

    # user -> state
    def _on_field(self, index: int) -> None:
        self._state.set(field=self.combo.itemData(index), clim_auto=True)

    def _on_limits(self, _value=None) -> None:
        self._state.set(clim_auto=False, clim=(self.lo.value(), self.hi.value()))

    # state -> widgets
    def _sync_all(self) -> None:
        s = self._state
        with blocked(self.combo, self.auto, self.clip, self.point_size):
            self.combo.setCurrentIndex(max(self.combo.findData(s.field), 0))
            self.auto.setChecked(s.clim_auto)
            self.clip.setValue(s.clip_percent)
            self.clip.setEnabled(s.clim_auto)
            self.point_size.setValue(s.point_size)
        if s.clim is not None:
            self.show_limits(*s.clim)

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name in ("field", "clim_auto", "clip_percent", "point_size", "clim"):
            self._sync_all()

    def show_limits(self, lo: float, hi: float) -> None:
        """Display the limits in use (called by the window after a recolour)."""
        span = abs(hi - lo) or 1.0
        step = 10 ** (int(f"{span:e}".split("e")[1]) - 1)
        decimals = max(2, min(8, 2 - int(f"{span:e}".split("e")[1]) + 1))
        with blocked(self.lo, self.hi):
            for box, v in ((self.lo, lo), (self.hi, hi)):
                box.setDecimals(decimals)
                box.setSingleStep(step)
                box.setValue(v)

    def set_available(self, names) -> None:
        """Grey out fields the current cloud cannot provide (e.g. errors without truth)."""
        model = self.combo.model()
        for row in range(self.combo.count()):
            item = model.item(row)
            item.setEnabled(self.combo.itemData(row) in names)
        if self.combo.currentData() not in names:
            self.combo.setToolTip("This field is not available for the current cloud")
        else:
            self.combo.setToolTip("")
