"""The one layout of every spherecal recording (demo, validate, plan): a Rerun blueprint.

A large 3D view of the robot and the fixtures on the left (the self-motion plays on ``time``); on
the right one tab per kind of result that was logged, each view named in plain words:

* **Errors**: each model's workspace tool points coloured by their error (a colour scale labelled in
  mm right of them, the same in every view, and above them what the error is a distance to), nominal and
  calibrated side by side from one camera (a millimetre on the screen is the same in both), their histograms
  below in the models' colours;
* **Residuals**: histograms of the calibration residuals before and after;
* **Parameter changes**: bars with +-1 std whiskers, lengths [mm] and angles [deg];
* **Joint coverage**: per fixture, the share of each joint's range visited [%] (one turn at most: a full turn of a
  joint limited to +-2 pi reads 100 %);
* **Socket spread**: per held-out socket, the predicted tool points of both models [mm], each model's spread a wire
  sphere around its mean point and named in a legend above and below them;
* **Tables**: the printed tables as printed (monospace, unwrapped: a wide one scrolls sideways), the provenance last.

Histograms and bars are static, so they show whatever the timeline selector is on.
"""

from __future__ import annotations

from itertools import product

import numpy as np

#: Tab names, in order, for each section of :attr:`validation.recording.Recording.contents`.
TABS = {
    "errors": "Errors",
    "residuals": "Residuals",
    "parameters": "Parameter changes",
    "coverage": "Joint coverage",
    "sockets": "Socket spread",
    "tables": "Tables",
}


#: Where the default cameras look from: the unit direction from what they look at to the eye (front right, above).
EYE_DIRECTION = np.array([1.0, -1.3, 0.8]) / np.linalg.norm([1.0, -1.3, 0.8])
#: Vertical field of view of Rerun's 3D views [rad]: the viewer's default, 55 deg (a screenshot's scale confirms it).
FIELD_OF_VIEW = np.radians(55.0)
#: Width over height of an Errors view in the default window (1600 x 1000 points: the result panel's two views side
#: by side, a fifth of the width each, above their histograms), a little less for the headers.
ERRORS_ASPECT = 0.45
#: Width over height of the 3D view of the robot: three fifths of the default window beside the result tabs (960 x
#: 920 points), the whole window (1.6) when there are no tabs; a little less for the headers.
WORLD_ASPECT, WORLD_ALONE_ASPECT = 0.95, 1.5


def view_axes() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors of the default cameras' picture: right and up on the screen, and back towards the eye
    (:data:`EYE_DIRECTION`); right is horizontal, as the cameras keep z up."""
    right = np.cross(-EYE_DIRECTION, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    return right, np.cross(right, -EYE_DIRECTION), EYE_DIRECTION


def union_box(boxes) -> np.ndarray:
    """The (2, 3) bounding box of (2, 3) bounding boxes [m]."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 2, 3)
    return np.array([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])


def fit_distance(box, aspect: float, margin: float = 0.9) -> float:
    """Least distance [m] from a (2, 3) box's centre along :data:`EYE_DIRECTION` at which every corner of the box
    lies within ``margin`` of the picture of a view ``aspect`` as wide as tall (a pinhole of :data:`FIELD_OF_VIEW`)."""
    box = np.asarray(box, dtype=float)
    corners = np.array(list(product(*box.T))) - box.mean(axis=0)
    right, up, back = view_axes()
    tall = margin * np.tan(FIELD_OF_VIEW / 2)
    across = np.maximum(np.abs(corners @ right) / (aspect * tall), np.abs(corners @ up) / tall)
    return float(np.max(corners @ back + across))


def eye_distance(box, least: float = 0.05, distance: float = 1.2, aspect: float | None = None) -> float:
    """How far [m] the default camera of :func:`camera` stands from the centre of a (2, 3) bounding box [m]."""
    box = np.asarray(box, dtype=float)
    size = max(float(np.linalg.norm(box[1] - box[0])), least)
    return max(distance * size, 0.0 if aspect is None else fit_distance(box, aspect))


def _world_camera(tabs: bool) -> tuple[float, float, float]:
    """``(least, distance, aspect)`` of the main 3D view's default camera (:func:`camera`); ``tabs``: whether the
    result tabs stand beside the view. Far enough that the whole box fits the view: at 0.9 of its diagonal alone,
    plan's rows of candidates on a 0.5 x 0.9 m table ran out of the bottom of the picture."""
    return 1.0, 0.9, WORLD_ASPECT if tabs else WORLD_ALONE_ASPECT


def world_eye_distance(box, tabs: bool) -> float:
    """How far [m] the main 3D view's default camera stands from the centre of its (2, 3) bounding box [m]; ``tabs``:
    whether the result tabs stand beside the view (:func:`build_blueprint`)."""
    return eye_distance(box, *_world_camera(tabs))


def camera(box, least: float = 0.05, distance: float = 1.2, aspect: float | None = None):
    """``rerun.blueprint.EyeControls3D`` looking at a (2, 3) bounding box [m] from the front right, above
    (:data:`EYE_DIRECTION`), from ``distance`` times as far as the box is wide (at least ``least`` [m]), and with
    ``aspect`` (a view's width over height) at least as far as the whole box fits in the view (:func:`fit_distance`)."""
    import rerun.blueprint as rrb  # Rerun: heavy, only when a recording is written

    box = np.asarray(box, dtype=float)
    centre, far = box.mean(axis=0), eye_distance(box, least, distance, aspect)
    return rrb.EyeControls3D(position=centre + far * EYE_DIRECTION, look_target=centre, eye_up=(0, 0, 1))


def build_blueprint(
    contents: dict[str, dict[str, str]], title: str, bounds: dict | None = None, active_tab: int | None = None
):
    """The blueprint of a recording.

    Args:
        contents: section -> {key: view name} of what was logged (see :class:`Recording`).
        title: name of the main 3D view.
        bounds: view origin -> (2, 3) bounding box of its contents [m]: the 3D views' cameras.
        active_tab: the result tab in front (default: "Socket spread" when there is one, else the first).

    Returns:
        A ``rerun.blueprint.Blueprint``.
    """
    import rerun.blueprint as rrb  # Rerun: heavy, only when a recording is written

    bounds = bounds or {}
    hidden = rrb.PlotLegend(visible=False)  # a bar chart's legend names its entity path; the view's name says more

    def eye(origin, least=0.05, distance=1.2, aspect=None):
        return camera(bounds[origin], least, distance, aspect) if origin in bounds else None

    def area(origin):
        if origin not in bounds:
            return None
        (x0, y0, _), (x1, y1, _) = bounds[origin]
        return rrb.VisualBounds2D(x_range=(x0, x1), y_range=(y0, y1))

    tabs = []
    for section, tab in TABS.items():
        views = contents.get(section) or {}
        if not views:
            continue
        if section == "errors":
            # one camera for every model, far enough for the narrow views: the same millimetre on the screen in each
            # (framed on its own box as for a square view, a socket's 0.2 mm cluster fell outside the picture)
            boxes = [bounds[f"errors/{k}"] for k in views if f"errors/{k}" in bounds]
            shared = camera(union_box(boxes), aspect=ERRORS_ASPECT) if boxes else None
            top = [rrb.Spatial3DView(origin=f"errors/{k}", contents="$origin/**", name=n, eye_controls=shared)
                   for k, n in views.items()]
            bottom = [rrb.BarChartView(origin=f"errors/{k}/histogram", name=f"{k.capitalize()}: error histogram [mm]",
                                       plot_legend=hidden) for k in views]
            tabs.append(rrb.Vertical(rrb.Horizontal(*top), rrb.Horizontal(*bottom), row_shares=[3, 1], name=tab))
        elif section == "residuals":
            tabs.append(rrb.Vertical(*[rrb.BarChartView(origin=f"residuals/{k}", name=n, plot_legend=hidden)
                                       for k, n in views.items()], name=tab))
        elif section == "parameters":
            tabs.append(rrb.Vertical(*[rrb.Spatial2DView(origin=f"parameters/{k}", name=n,
                                                         visual_bounds=area(f"parameters/{k}"))
                                       for k, n in views.items()], name=tab))
        elif section == "coverage":
            # no legend: it named the entity path ('/coverage/P2') over the tallest bars, the view's name says more
            tabs.append(rrb.Grid(*[rrb.BarChartView(origin=f"coverage/{k}", name=n, plot_legend=hidden)
                                   for k, n in views.items()], name=tab))
        elif section == "sockets":
            # nearer than a workspace's camera: the points, spheres and legend fill the view, and a calibrated cluster
            # of a few tenths of a mm beside several of nominal spread shows as a cluster (six sockets in a grid too)
            near = {k: eye(f"sockets/{k}", distance=0.8) for k in views}
            tabs.append(rrb.Grid(*[rrb.Spatial3DView(origin=f"sockets/{k}", name=n, eye_controls=near[k])
                                   for k, n in views.items()], name=tab))
        else:  # the results first, the provenance (behind them, it hid the table a reviewer opens the tab for) last
            order = sorted(views, key=lambda k: k == "provenance")
            # monospace and unwrapped, scrolled sideways: wrapped, a table wider than the panel lost its columns
            table = rrb.archetypes.TextDocumentFormat(monospace=True, word_wrap=False)
            tabs.append(rrb.Tabs(*[rrb.TextDocumentView(origin=f"tables/{k}", name=views[k], format_options=table)
                                   for k in order], name=tab))
    world = rrb.Spatial3DView(origin="world", contents="$origin/**", name=title,
                              eye_controls=eye("world", *_world_camera(bool(tabs))))  # the fixtures' labels follow it
    if active_tab is None:
        shown = [section for section in TABS if contents.get(section)]
        active_tab = shown.index("sockets") if "sockets" in shown else 0
    root = rrb.Horizontal(world, rrb.Tabs(*tabs, active_tab=active_tab), column_shares=[3, 2]) if tabs else world
    return rrb.Blueprint(
        root,
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="time", play_state="playing"),
        auto_views=False,
        auto_layout=False,
    )
