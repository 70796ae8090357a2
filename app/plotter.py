"""The 3D views' plotters: pyvistaqt's ``QtInteractor``, one sample a pixel, and each
render the interactor asks for drawn once, by the widget's next paint (GUI thread).

pyvistaqt's widget renders VTK in its ``paintGL``, and a finished render schedules that
paint: every render the interactor style asked for (each step of a drag or a zoom, and
its end) drew the frame twice, one turn of the event loop apart in the worst case in the
same one (0.02-0.07 s a frame at 60k points with llvmpipe). As VTK's own C++
``QVTKOpenGLNativeWidget`` does, the interactor renders nothing itself: its render event
asks the widget for a paint, and the paint renders. Explicit ``render()`` calls (pyvista's)
go to the render window and are not touched.
"""

from __future__ import annotations

from pyvistaqt import QtInteractor

__all__ = ["MULTI_SAMPLES", "make_plotter", "render_in_paint"]

#: Samples per pixel of the 3D views' frame buffer: one. pyvista's default of 8 made every
#: llvmpipe frame cost 1.7-1.9x (bunny and a 100k-sphere still frame of 1M, 760x850 and
#: 1100x850, 2 and 8 samples alike; measured in one run, app.bench), and a frame that renders
#: on the GUI thread is what the GUI stall is made of. It smoothed only true edges (sphere
#: seams, glyphs, the bar's ends), not a sphere's outline, cut out per pixel (an impostor).
MULTI_SAMPLES = 0


def make_plotter(parent=None) -> QtInteractor:
    """A 3D view of the viewer: rendered only when asked (no auto-update timer), one sample
    a pixel (:data:`MULTI_SAMPLES`), the interactor's renders drawn by the next paint."""
    plotter = QtInteractor(parent, auto_update=False, multi_samples=MULTI_SAMPLES)
    render_in_paint(plotter)
    return plotter


def render_in_paint(plotter) -> None:
    """The interactor's ``Render()`` becomes a request for a paint of ``plotter``; inside the
    widget's own paint (which renders through the interactor) it renders."""
    iren = getattr(getattr(plotter, "iren", None), "interactor", None)
    if iren is None or not hasattr(plotter, "_in_paint"):  # (not pyvistaqt's FBO widget: left as it is)
        return
    window = plotter.render_window

    def on_render(*_args) -> None:
        if getattr(plotter, "_closed", False):
            return
        if plotter._in_paint:
            window.Render()
        else:
            plotter.update()

    iren.EnableRenderOff()
    iren.AddObserver("RenderEvent", on_render)
