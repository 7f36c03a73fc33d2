"""Screen overlays in fixed regions that never cover the scene or each other.

A view's part of the window (its *region*) is split into a header band on top (title,
time), a panel on the right (legend, colour bars, the followed walker's info) and the
scene viewport (the 3-D renderer) in the rest. The overlay is a second renderer under
the scene's, covering the whole region; text and colour bars go only into the header and
panel boxes, which the scene viewport does not overlap, so nothing is drawn over the
scene and every overlay has its own slot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
from vtkmodules.vtkRenderingCore import vtkProp, vtkRenderer, vtkTextActor

__all__ = ["Layout", "Overlay"]


@dataclass(frozen=True)
class Layout:
    """Where a view's parts go, as fractions of the window (x0, y0, x1, y1), y up.

    Parameters
    ----------
    region : (float, float, float, float)
        The view's part of the window.
    header : float
        Height of the header band, fraction of the region.
    panel : float
        Width of the right panel, fraction of the region.
    """

    region: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0)
    header: float = 0.1
    panel: float = 0.24

    @property
    def scene(self) -> tuple[float, float, float, float]:
        """The 3-D viewport (window fractions)."""
        x0, y0, x1, y1 = self.region
        return (x0, y0, x1 - self.panel * (x1 - x0), y1 - self.header * (y1 - y0))

    def panel_x(self) -> float:
        """Left edge of the panel in the region's own coordinates (0..1)."""
        return 1.0 - self.panel


class Overlay:
    """Text and colour bars in a view's header and panel.

    Parameters
    ----------
    plotter : pyvista.Plotter
    layout : Layout
    scene_renderer : vtkRenderer
        Moved to ``layout.scene`` on top of the overlay.
    """

    def __init__(self, plotter, layout: Layout, scene_renderer) -> None:
        self.layout = layout
        self.plotter = plotter
        self.renderer = vtkRenderer()
        self.renderer.SetViewport(*layout.region)
        self.renderer.SetBackground(1.0, 1.0, 1.0)
        self.renderer.SetLayer(0)
        self.renderer.InteractiveOff()
        window = plotter.ren_win
        window.SetNumberOfLayers(max(window.GetNumberOfLayers(), 2))
        window.AddRenderer(self.renderer)
        scene_renderer.SetViewport(*layout.scene)
        scene_renderer.SetLayer(1)
        scene_renderer.SetPreserveColorBuffer(0)  # it clears (and paints) its own viewport
        self._actors: dict[str, vtkProp] = {}

    @property
    def pixels(self) -> tuple[int, int]:
        """Width and height of the region [px]."""
        w, h = self.plotter.window_size
        x0, y0, x1, y1 = self.layout.region
        return max(1, round(w * (x1 - x0))), max(1, round(h * (y1 - y0)))

    def font(self, lines_per_height: float = 44.0, chars_per_panel: float = 28.0) -> int:
        """A font size [px] that fits ``lines_per_height`` lines in the region and
        ``chars_per_panel`` characters across the panel."""
        w, h = self.pixels
        return int(max(7, min(h / lines_per_height,
                              self.layout.panel * w / (0.55 * chars_per_panel))))

    def text(self, name: str, text: str, position: tuple[float, float], *, size: int,
             color=(0.1, 0.1, 0.1), bold: bool = False, right: bool = False,
             top: bool = True, mono: bool = False) -> vtkTextActor:
        """Place or update the text ``name`` at ``position`` (region fractions, y up)."""
        actor = self._actors.get(name)
        if actor is None:
            actor = vtkTextActor()
            actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
            self.renderer.AddActor(actor)
            self._actors[name] = actor
        prop = actor.GetTextProperty()
        prop.SetFontSize(int(size))
        prop.SetColor(*color[:3])
        prop.SetBold(bold)
        prop.SetFontFamilyToCourier() if mono else prop.SetFontFamilyToArial()
        prop.SetJustificationToRight() if right else prop.SetJustificationToLeft()
        prop.SetVerticalJustificationToTop() if top else prop.SetVerticalJustificationToBottom()
        actor.GetPositionCoordinate().SetValue(*position)
        actor.SetInput(text)
        return actor

    def color_bar(self, name: str, lookup_table, title: str, box: tuple[float, float, float,
                  float], *, size: int, fmt: str = "%.3g", title_x: float | None = None) -> None:
        """A horizontal colour bar with its title above (from ``title_x``) and labels
        below, inside ``box`` (x0, y0, x1, y1 region fractions)."""
        self.remove(name)
        x0, y0, x1, y1 = box
        h = y1 - y0
        _, height_px = self.pixels
        title_h = 1.5 * size / height_px
        self.text(f"{name} title", title, (x0 if title_x is None else title_x, y1), size=size)
        bar = vtkScalarBarActor()
        bar.SetLookupTable(lookup_table)
        bar.SetOrientationToHorizontal()
        bar.SetTextPositionToSucceedScalarBar()
        bar.SetNumberOfLabels(3)
        bar.SetLabelFormat(fmt)
        bar.SetTitle("")
        bar.UnconstrainedFontSizeOn()
        bar.SetBarRatio(0.45)
        bar.SetTextPad(2)
        labels = bar.GetLabelTextProperty()
        labels.SetFontSize(int(size * 0.9))
        labels.SetColor(0.1, 0.1, 0.1)
        labels.ShadowOff()
        labels.ItalicOff()
        labels.BoldOff()
        bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        bar.GetPositionCoordinate().SetValue(x0, y0)
        bar.GetPosition2Coordinate().SetCoordinateSystemToNormalizedViewport()
        bar.GetPosition2Coordinate().SetValue(x1 - x0, max(h - title_h, 0.02))
        self.renderer.AddActor(bar)
        self._actors[name] = bar

    def remove(self, name: str) -> None:
        """Remove the overlay ``name`` (and its title) when present."""
        for key in (name, f"{name} title"):
            actor = self._actors.pop(key, None)
            if actor is not None:
                self.renderer.RemoveActor(actor)

    def names(self) -> list[str]:
        """Names of the overlays shown."""
        return list(self._actors)

    def actor(self, name: str):
        """The VTK actor of overlay ``name``."""
        return self._actors[name]

    def boxes_px(self) -> dict[str, np.ndarray]:
        """Window pixel boxes (x0, y0, x1, y1; y up) of every overlay as drawn (after a
        render), for checking that none overlaps the scene or another."""
        out = {}
        for name, actor in self._actors.items():
            if isinstance(actor, vtkTextActor):
                bbox = [0.0] * 4  # relative to the anchor: xmin, xmax, ymin, ymax
                actor.GetBoundingBox(self.renderer, bbox)
                x, y = actor.GetPositionCoordinate().GetComputedDisplayValue(self.renderer)
                out[name] = np.array([x + bbox[0], y + bbox[2], x + bbox[1], y + bbox[3]])
            else:
                p1 = actor.GetPositionCoordinate().GetComputedDisplayValue(self.renderer)
                p2 = actor.GetPosition2Coordinate().GetComputedDisplayValue(self.renderer)
                out[name] = np.array([p1[0], p1[1], p2[0], p2[1]], dtype=float)
        return out
