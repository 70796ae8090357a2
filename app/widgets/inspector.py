"""Panel with the Darboux frame and curvatures of the picked point."""

from __future__ import annotations

import html

import numpy as np
from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QLabel, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget

from ..glyphs import FRAME_COLOURS

#: Rows shown, in order: key in the info dict -> label.
ROWS = (
    ("index", "index"),
    ("no_estimate", "no estimate"),
    ("position", "position p"),
    ("normal", "normal n"),
    ("k1", "k1"),
    ("k2", "k2"),
    ("e1", "e1"),
    ("e2", "e2"),
    ("gaussian", "K = k1·k2"),
    ("mean", "H = (k1+k2)/2"),
    ("shape_index", "shape index"),
    ("curvedness", "curvedness"),
    ("valid", "valid"),
    ("true_k1", "true k1"),
    ("true_k2", "true k2"),
    ("true_mean", "true H"),
    ("true_gaussian", "true K"),
)


def _fmt(value) -> str:
    if value is None:
        return "—"
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no (NaN)"
    if isinstance(value, (int, np.integer)):
        return f"{int(value):,}"
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return "nan" if not np.isfinite(arr) else f"{float(arr):+.5g}"
    return " ".join("nan" if not np.isfinite(v) else f"{v:+.3f}" for v in arr)


class PointInspector(QWidget):
    """Read-only table: click a point in the view to fill it."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.header = QLabel("Click a point in the view to inspect it.")
        self.header.setWordWrap(True)
        self.table = QTableWidget(0, 2)
        self.table.setHorizontalHeaderLabels(["quantity", "value"])
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setSectionResizeMode(0, QHeaderView.ResizeMode.ResizeToContents)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setWordWrap(False)
        self.table.verticalHeader().setDefaultSectionSize(22)
        self.table.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.header)
        layout.addWidget(self.table)
        self.values: dict[str, str] = {}

    def show_point(self, info: dict) -> None:
        """Fill the table from ``info`` (key -> number, vector or bool; missing keys are skipped),
        then a row for each of ``info["file"]`` (label -> value: the file's own fields)."""
        rows = [(label, _fmt(info[key])) for key, label in ROWS if key in info]
        self.values = {key: _fmt(info[key]) for key, _ in ROWS if key in info}
        extra = [(label, _fmt(value)) for label, value in info.get("file", {}).items()]
        rows += extra
        self.values.update(extra)
        self.table.setRowCount(len(rows))
        for r, (label, text) in enumerate(rows):
            self.table.setItem(r, 0, QTableWidgetItem(label))
            self.table.setItem(r, 1, QTableWidgetItem(text))
        index = info.get("index")
        if "no_estimate" in info:  # a cloud core refused as a whole (app.presenter.point_info)
            self.header.setText(f"<b>Point {index:,}</b>: no estimate — {html.escape(info['no_estimate'])}")
            return
        self.header.setText(
            f"<b>Point {index:,}</b>: e1 <span style='color:{FRAME_COLOURS['e1']}'>black</span>, "
            f"e2 <span style='color:{FRAME_COLOURS['e2']}'>green</span>, "
            f"n <span style='color:{FRAME_COLOURS['n']}'>purple</span>; "
            f"its k neighbours in <span style='color:#c9a100'>yellow</span>."
            if isinstance(index, (int, np.integer)) else "Point"
        )

    def clear(self) -> None:
        self.values = {}
        self.table.setRowCount(0)
        self.header.setText("Click a point in the view to inspect it.")
