"""The Teach dock's widgets (GUI thread): overlay switches, the direction theta, the
picked point in words, Gauss-Bonnet, the Euler plot and the Gauss map, figure export."""

from __future__ import annotations

from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtWidgets import (
    QCheckBox,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSlider,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from .examples import DEFAULT_OVERLAYS, OVERLAYS
from .plots import EulerPlot, GaussMapPlot

__all__ = ["TeachSettings", "TeachPanel"]


class TeachSettings(QObject):
    """What the Teach mode shows: ``enabled``, ``overlays`` (a frozenset of names from
    :data:`OVERLAYS`) and ``theta`` (degrees from e1). ``changed(name)`` after each change."""

    changed = Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.enabled = False
        self.overlays = frozenset(DEFAULT_OVERLAYS)
        self.theta = 30.0

    def set(self, **values) -> None:
        for name, value in values.items():
            if name == "overlays":
                value = frozenset(value)
                unknown = value - set(OVERLAYS)
                if unknown:
                    raise ValueError(f"overlays {sorted(unknown)} unknown; valid: {', '.join(OVERLAYS)}")
            elif name == "theta":
                value = float(value) % 180.0
            elif name == "enabled":
                value = bool(value)
            else:
                raise ValueError(f"{name!r} is not a teach setting; valid: enabled, overlays, theta")
            if getattr(self, name) != value:
                setattr(self, name, value)
                self.changed.emit(name)

    def toggle(self, overlay: str, on: bool) -> None:
        self.set(overlays=(self.overlays | {overlay}) if on else (self.overlays - {overlay}))


class TeachPanel(QWidget):
    """The dock's content. ``export_requested`` when the export button is pressed."""

    export_requested = Signal()

    def __init__(self, settings: TeachSettings, parent=None):
        super().__init__(parent)
        self.settings = settings
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        self.point_label = QLabel("Pick a point (click on the cloud).")
        self.point_label.setWordWrap(True)
        self.point_label.setTextFormat(Qt.TextFormat.RichText)
        self.cloud_label = QLabel("")
        self.cloud_label.setWordWrap(True)
        self.cloud_label.setTextFormat(Qt.TextFormat.RichText)
        self.example_label = QLabel("")
        self.example_label.setWordWrap(True)
        self.example_label.hide()
        layout.addWidget(self.example_label)
        layout.addWidget(self.point_label)
        layout.addWidget(self._overlay_box())
        layout.addWidget(self._theta_row())
        self.tabs = QTabWidget()
        self.euler = EulerPlot()
        self.gauss_map = GaussMapPlot()
        self.tabs.addTab(self.euler, "Euler's formula")
        self.tabs.addTab(self.gauss_map, "Gauss map")
        layout.addWidget(self.tabs, 1)
        layout.addWidget(self.cloud_label)
        export = QPushButton("Export figures for slides…")
        export.setToolTip("High-resolution PNG of the 3D view, the Euler plot as SVG and PDF, the Gauss map")
        export.clicked.connect(self.export_requested)
        layout.addWidget(export)
        settings.changed.connect(self._sync)

    def _overlay_box(self) -> QGroupBox:
        box = QGroupBox("Show")
        col = QVBoxLayout(box)
        col.setContentsMargins(6, 4, 6, 4)
        self.checks = {}
        for name, text in OVERLAYS.items():
            check = QCheckBox(text)
            check.setChecked(name in self.settings.overlays)
            check.toggled.connect(lambda on, n=name: self.settings.toggle(n, on))
            col.addWidget(check)
            self.checks[name] = check
        return box

    def _theta_row(self) -> QWidget:
        row = QWidget()
        h = QHBoxLayout(row)
        h.setContentsMargins(0, 0, 0, 0)
        h.addWidget(QLabel("Direction θ"))
        self.theta_slider = QSlider(Qt.Orientation.Horizontal)
        self.theta_slider.setRange(0, 179)
        self.theta_slider.setValue(int(round(self.settings.theta)))
        self.theta_slider.setToolTip("Sweep the normal section around n: k_n(θ) = k1 cos²θ + k2 sin²θ")
        self.theta_slider.valueChanged.connect(lambda v: self.settings.set(theta=v))
        self.theta_label = QLabel(f"{self.settings.theta:.0f}°")
        self.theta_label.setMinimumWidth(36)
        h.addWidget(self.theta_slider, 1)
        h.addWidget(self.theta_label)
        return row

    def _sync(self, name: str) -> None:
        """Settings -> widgets, without echoing back."""
        if name == "theta":
            self.theta_slider.blockSignals(True)
            self.theta_slider.setValue(int(round(self.settings.theta)))
            self.theta_slider.blockSignals(False)
            self.theta_label.setText(f"{self.settings.theta:.0f}°")
        elif name == "overlays":
            for key, check in self.checks.items():
                check.blockSignals(True)
                check.setChecked(key in self.settings.overlays)
                check.blockSignals(False)

    def show_example(self, text: str | None) -> None:
        self.example_label.setText(text or "")
        self.example_label.setVisible(bool(text))
