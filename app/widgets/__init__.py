"""One small widget per file, each bound both ways to :class:`app.state.ViewerState`.

Pattern (napari's layer controls): the widget writes to the state when the user
acts, and listens to ``state.changed`` to update itself with its own signals
blocked, so a state change never echoes back as a user action.
"""

from .check_box import StateCheckBox
from .compare_view import CompareView
from .elided_label import ElidedLabel
from .field_panel import FieldPanel
from .glyph_controls import GlyphControls
from .histogram import Histogram
from .inspector import PointInspector
from .method_combo import MethodCombo
from .orientation_combo import OrientationCombo
from .progress import EstimateProgress
from .recent_menu import RecentFilesMenu
from .shape_dialog import ShapeDialog
from .state_slider import KSlider, StateSlider, k_slider, noise_slider, passes_slider

__all__ = [
    "CompareView",
    "ElidedLabel",
    "EstimateProgress",
    "FieldPanel",
    "GlyphControls",
    "Histogram",
    "KSlider",
    "MethodCombo",
    "OrientationCombo",
    "PointInspector",
    "RecentFilesMenu",
    "ShapeDialog",
    "StateCheckBox",
    "StateSlider",
    "k_slider",
    "noise_slider",
    "passes_slider",
]
