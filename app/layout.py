"""The controls panel and the docks of the main window (composition only, GUI thread)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDockWidget, QGroupBox, QLabel, QScrollArea, QVBoxLayout, QWidget

from .widgets import (
    FieldPanel,
    GlyphControls,
    Histogram,
    MethodCombo,
    OrientationCombo,
    PointInspector,
    StateCheckBox,
    k_slider,
    noise_slider,
    passes_slider,
)

__all__ = ["build_controls"]

_MOVABLE = QDockWidget.DockWidgetFeature.DockWidgetMovable | QDockWidget.DockWidgetFeature.DockWidgetFloatable


def _group(title: str, *widgets) -> QGroupBox:
    box = QGroupBox(title)
    layout = QVBoxLayout(box)
    layout.setContentsMargins(6, 6, 6, 6)
    for w in widgets:
        layout.addWidget(w)
    return box


def _dock(window, title: str, widget: QWidget, area, closable: bool = True) -> QDockWidget:
    dock = QDockWidget(title, window)
    dock.setObjectName(title.lower().replace(" ", "_"))  # saveState/restoreState key
    dock.setWidget(widget)
    features = _MOVABLE | (QDockWidget.DockWidgetFeature.DockWidgetClosable if closable else _MOVABLE)
    dock.setFeatures(features)
    window.addDockWidget(area, dock)
    return dock


def build_controls(window) -> None:
    """Create the widgets bound to ``window.state`` and dock them (sets window attributes)."""
    s = window.state
    window.method_combo = MethodCombo(s)
    window.k_slider = k_slider(s)
    window.passes_slider = passes_slider(s)
    window.noise_slider = noise_slider(s)
    window.normals_check = StateCheckBox(
        s, "use_input_normals", "Use the cloud's normals",
        "Start from the normals stored in the file (or the shape's exact normals) instead of estimating them",
    )
    # the camera itself, not pyvista's getter (which renders a fresh renderer once)
    window.orientation_combo = OrientationCombo(
        s, lambda: window.plotter.renderer.GetActiveCamera().GetPosition())
    window.compare_combo = MethodCombo(s, key="compare_method")
    window.compare_combo.setToolTip("Show a second method side by side (linked cameras)")
    window.field_panel = FieldPanel(s)
    window.histogram = Histogram()
    window.glyph_controls = GlyphControls(s)
    window.inspector = PointInspector()

    panel = QWidget()
    layout = QVBoxLayout(panel)
    layout.setContentsMargins(4, 4, 4, 4)
    layout.addWidget(_group("Estimate", window.method_combo, window.k_slider, window.passes_slider,
                            window.noise_slider, window.normals_check, QLabel("Orientation"), window.orientation_combo,
                            QLabel("Compare with"), window.compare_combo))
    layout.addWidget(_group("Colour", window.field_panel))
    layout.addWidget(_group("Glyphs", window.glyph_controls))
    layout.addStretch(1)
    scroll = QScrollArea()
    scroll.setWidget(panel)
    scroll.setWidgetResizable(True)
    scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
    scroll.setMinimumWidth(panel.minimumSizeHint().width() + scroll.verticalScrollBar().sizeHint().width() + 4)
    window.controls_dock = _dock(window, "Controls", scroll, Qt.DockWidgetArea.RightDockWidgetArea, closable=False)
    window.histogram_dock = _dock(window, "Histogram", window.histogram, Qt.DockWidgetArea.LeftDockWidgetArea)
    window.inspector_dock = _dock(window, "Picked point", window.inspector, Qt.DockWidgetArea.LeftDockWidgetArea)
    window.resizeDocks([window.histogram_dock], [270], Qt.Orientation.Horizontal)
    window.resizeDocks([window.histogram_dock, window.inspector_dock], [260, 500], Qt.Orientation.Vertical)
