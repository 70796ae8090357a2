"""How estimated normals are oriented (bound to ``state.orientation``).

"Outward" is not defined for a scan of a scene (a floor with objects, a sphere in front
of a wall): there the normals should face the scanner. The user places the camera where
the scanner was and chooses "toward the current view"; the camera position at that moment
becomes the viewpoint (a tuple, so the request stays hashable).
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtGui import QStandardItemModel
from PySide6.QtWidgets import QComboBox

from core.interop import facing

from ..presenter import orientation_text
from ._bind import blocked

#: (label, state value or "view" for the camera's position, tooltip), in the order shown.
CHOICES = (
    ("outward (default)", "auto", "Keep the cloud's normals if used; orient estimated ones away from the centre"),
    ("up (+z)", "propagate", "Each connected part's highest point faces +z (a floor, a terrain)"),
    ("toward the current view", "view",
     "Every normal faces the camera position at the moment this is chosen (place it where the scanner was; "
     "choose again after moving the camera)"),
    ("keep the file's normals", "keep", "Keep the signs of the cloud's normals (only when they are used)"),
)
VIEW = "view"
#: the default's label and tooltip on a cloud that came with each point's scanner (an E57 file's)
SCANNERS = ("toward the scanners (default)", "Each point faces the scanner that saw it (the file's scanner positions)")
_TIP = Qt.ItemDataRole.ToolTipRole


class OrientationCombo(QComboBox):
    """The four orientation choices; ``camera_position()`` gives the viewpoint of "toward the current view".

    "keep the file's normals" is enabled only while the cloud has normals and they are used;
    a state left on "keep" without them falls back to the default.
    """

    def __init__(self, state, camera_position, parent=None):
        super().__init__(parent)
        self._items = QStandardItemModel(self)  # held here: see FieldPanel (a stale wrapper from model())
        self.setModel(self._items)
        self._state = state
        self._camera_position = camera_position
        for label, value, tooltip in CHOICES:
            self.addItem(label, value)
            self.setItemData(self.count() - 1, tooltip, _TIP)
        self.setToolTip("How the estimated normals are oriented (which side is positive curvature)")
        self._sync()
        self.activated.connect(self._on_activated)  # also when the same entry is chosen again
        state.changed.connect(self._on_state)

    def keep_allowed(self) -> bool:
        """Whether the cloud has normals and they are used."""
        source = self._state.source
        return source is not None and source.normals is not None and bool(self._state.use_input_normals)

    def scanners_default(self) -> bool:
        """Whether the default faces the scanners, as :func:`core.interop.facing` decides for
        the estimate: the cloud carries their positions and no normals are used."""
        source = self._state.source
        if source is None:
            return False
        normals = source.normals if self._state.use_input_normals else None
        return not isinstance(facing(source, normals, "auto"), str)

    def _on_activated(self, index: int) -> None:
        value = self.itemData(index)
        if value == VIEW:
            value = tuple(float(v) for v in self._camera_position())
        self._state.set(orientation=value)
        self._sync()  # a viewpoint equal to the last one changes nothing: show it anyway

    def _on_state(self, name: str) -> None:
        if name in ("source", "use_input_normals") and self._state.source is not None \
                and self._state.orientation == "keep" and not self.keep_allowed():
            self._state.set(orientation="auto")  # nothing to keep: the default
        if name in ("orientation", "source", "use_input_normals"):
            self._sync()

    def _sync(self) -> None:
        """Select the state's choice, enable "keep" as allowed, tell the viewpoint in the tooltip."""
        value = self._state.orientation
        index = self.findData(VIEW if isinstance(value, tuple) else value)
        keep = self.findData("keep")
        auto = self.findData("auto")
        label, tip = SCANNERS if self.scanners_default() else CHOICES[auto][::2]
        with blocked(self):
            self._items.item(keep).setEnabled(self.keep_allowed() or value == "keep")
            self.setItemText(auto, label)
            self.setItemData(auto, tip, _TIP)
            self.setCurrentIndex(max(index, 0))
        view = self.findData(VIEW)
        tip = CHOICES[view][2] + (f"\nNow: {orientation_text(value)}" if isinstance(value, tuple) else "")
        self.setItemData(view, tip, _TIP)
