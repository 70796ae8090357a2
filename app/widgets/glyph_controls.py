"""Glyph switches, density and length (bound to ``state.show_e1``, ``show_e2``,
``show_normals``, ``glyph_density``, ``glyph_length``)."""

from __future__ import annotations

from PySide6.QtCore import QEvent, Qt
from PySide6.QtWidgets import QCheckBox, QFormLayout, QHBoxLayout, QWidget
from superqt import QLabeledDoubleSlider, QLabeledSlider

from ..glyphs import GLYPH_POINTS
from ..legend import GLYPH_PLATE
from ..scene import GLYPH_COLOURS
from ..theme import current_theme
from ._bind import blocked

_SWITCHES = (("show_e1", "e1", "Max. principal direction"), ("show_e2", "e2", "Min. principal direction"),
             ("show_normals", "n", "Estimated normal"))


def _label_style(colour: str) -> str:
    """Bold, in the glyph's colour; on a light plate where the palette is dark, as the 3D
    legend's (e1's near-black and n's purple were unreadable on a dark panel)."""
    plate = f"background-color: {GLYPH_PLATE}; border-radius: 3px; padding: 0px 3px;" if current_theme().name == "dark" else ""
    return f"QCheckBox {{ color: {colour}; font-weight: bold; {plate} }}"


class GlyphControls(QWidget):
    """e1, e2 and normal glyphs as ± line segments (directions have no sign).

    Density is the fraction of the glyph positions that get a glyph: every point of a small
    cloud, at most :data:`app.glyphs.GLYPH_POINTS` spread evenly over a big one (a frame
    must not grow with the cloud); length is in units of the mean point spacing, so it
    means the same on any cloud.
    """

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        self.boxes: dict[str, QCheckBox] = {}
        row = QHBoxLayout()
        for key, text, tip in _SWITCHES:
            box = QCheckBox(text)
            box.setProperty("glyph_colour", GLYPH_COLOURS["normals" if key == "show_normals" else text])
            box.setStyleSheet(_label_style(box.property("glyph_colour")))
            box.setToolTip(tip)
            box.toggled.connect(lambda on, key=key: self._state.set(**{key: bool(on)}))
            self.boxes[key] = box
            row.addWidget(box)
        row.addStretch(1)
        self.density = QLabeledSlider(Qt.Orientation.Horizontal)
        self.density.setRange(1, 100)
        self.density.setToolTip(f"Percent of the points that get a glyph (of at most {GLYPH_POINTS:,} "
                                "evenly spread points on a big cloud)")
        self.length = QLabeledDoubleSlider(Qt.Orientation.Horizontal)
        self.length.setRange(0.5, 10.0)
        self.length.setSingleStep(0.5)
        self.length.setDecimals(1)
        self.length.setToolTip("Glyph length in mean point spacings")
        form = QFormLayout(self)
        form.setContentsMargins(0, 0, 0, 0)
        form.addRow("Show", row)
        form.addRow("Density %", self.density)
        form.addRow("Length ×h", self.length)
        self._sync()
        self.density.valueChanged.connect(lambda v: self._state.set(glyph_density=v / 100.0))
        self.length.valueChanged.connect(lambda v: self._state.set(glyph_length=float(v)))
        state.changed.connect(self._on_state)

    def changeEvent(self, event) -> None:  # noqa: N802
        """The palette turned dark or light: the labels' plates follow."""
        if event.type() in (QEvent.Type.PaletteChange, QEvent.Type.ApplicationPaletteChange):
            for box in self.boxes.values():
                style = _label_style(box.property("glyph_colour"))
                if box.styleSheet() != style:
                    box.setStyleSheet(style)
        super().changeEvent(event)

    def _sync(self) -> None:
        s = self._state
        with blocked(self.density, self.length, *self.boxes.values()):
            for key, box in self.boxes.items():
                box.setChecked(bool(s.get(key)))
            self.density.setValue(int(round(s.glyph_density * 100)))
            self.length.setValue(s.glyph_length)

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name.startswith("show_") or name.startswith("glyph_"):
            self._sync()
