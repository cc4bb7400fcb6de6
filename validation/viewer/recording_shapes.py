"""Plain geometry for the recordings (no Rerun here): link capsules, a colour ramp, histograms, bars."""

from __future__ import annotations

import numpy as np

from spherecal.correction.layout import ParamKind

#: Anchors of the error colour ramp, all readable on the viewer's dark background (blue: small, red: large).
RAMP = np.array([(60, 110, 240), (30, 190, 210), (90, 205, 90), (245, 215, 40), (235, 60, 40)], dtype=float)
#: Spheres of a colour scale, and which of them are labelled (every fifth: at 0, 25, 50, 75 and 100 %).
SCALE_STEPS, SCALE_LABELLED = 21, 5
#: Height of the tallest bar in the parameter panels (2D view units; the labels carry the values).
BAR_HEIGHT = 4.0
#: Outline of every parameter bar: a grey of no model's, the sign is the bar's direction. Negative bars were red and
#: positive ones blue, the colours that mean nominal and calibrated in every other view of the recording.
BAR_COLOUR = (165, 165, 180)


def capsules(strips: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Capsules along the segments of poly-lines (Rerun's capsules run along +z from their origin).

    Args:
        strips: (T, K, 3) points of T poly-lines [m].

    Returns:
        lengths (T, K-1) [m], translations (T, K-1, 3) (segment starts) [m] and quaternions
        (T, K-1, 4) (x, y, z, w) turning +z onto each segment (identity for a zero-length one).
    """
    start, end = strips[:, :-1], strips[:, 1:]
    vector = end - start
    lengths = np.linalg.norm(vector, axis=-1)
    unit = np.divide(vector, lengths[..., None], out=np.zeros_like(vector), where=lengths[..., None] > 1e-12)
    unit[lengths <= 1e-12] = (0.0, 0.0, 1.0)
    # half-way quaternion from z to u: (z x u, 1 + z.u), normalised; u = -z turns about x
    quat = np.stack([-unit[..., 1], unit[..., 0], np.zeros_like(lengths), 1.0 + unit[..., 2]], axis=-1)
    flipped = quat[..., 3] < 1e-9
    quat[flipped] = (1.0, 0.0, 0.0, 0.0)
    return lengths, start, quat / np.linalg.norm(quat, axis=-1, keepdims=True)


def colour_ramp(share: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 colours of values (N,) in [0, 1] (clipped) on the ramp :data:`RAMP`."""
    s = np.clip(np.asarray(share, dtype=float), 0.0, 1.0) * (len(RAMP) - 1)
    low = np.minimum(s.astype(int), len(RAMP) - 2)
    frac = (s - low)[:, None]
    return np.round(RAMP[low] * (1 - frac) + RAMP[low + 1] * frac).astype(np.uint8)


def scale_labels(low: float, high: float, text) -> list[str]:
    """Labels of the :data:`SCALE_STEPS` spheres of a colour scale whose values run from ``low`` (bottom) to ``high``
    (top): every :data:`SCALE_LABELLED`-th is ``text(value)``, the others empty."""
    values = np.linspace(low, high, SCALE_STEPS)
    return [text(v) if k % SCALE_LABELLED == 0 else "" for k, v in enumerate(values)]


def histogram(values: np.ndarray, bins: int = 30) -> tuple[np.ndarray, np.ndarray, float]:
    """Counts (bins,), bin left edges (bins,: Rerun's bar abscissa) and bin width of values from 0 to their maximum."""
    values = np.asarray(values, dtype=float)
    top = float(values.max()) if values.size and values.max() > 0 else 1.0
    counts, edges = np.histogram(values, bins=bins, range=(0.0, top))
    return counts, edges[:-1], float(edges[1] - edges[0])


def parameter_bars(
    names: list[str],
    kinds: list[ParamKind],
    change: np.ndarray,
    std: np.ndarray,
    truth: np.ndarray | None = None,
) -> dict[str, dict[str, np.ndarray | list]]:
    """2D shapes of a bar chart with error bars, one group per parameter kind (``lengths`` [mm],
    ``angles`` [deg], ``compliances`` [urad/Nm]: each kind's display unit from the parameter layout).

    Bar ``k`` spans x in [k - 0.35, k + 0.35]; heights are scaled so that the largest ``|value|`` of the
    group is :data:`BAR_HEIGHT` tall; y points down in Rerun's 2D views, so heights are negated.

    Args:
        names: (P,) parameter names.
        kinds: (P,) their kinds (``layout.kinds[layout.index(name)]``), which give the display unit.
        change, std: (P,) in each kind's unit [m, rad, rad/Nm].
        truth: (P,) in each kind's unit, or None.

    Returns:
        group -> ``mins`` (B, 2), ``sizes`` (B, 2), ``colours`` (B, 3) of the bars, ``names`` (B, 2) and
        ``labels`` (B,) of the parameter names beyond each bar's end, ``whiskers`` (B, 2, 2), ``zero``
        (2, 2), ``scale`` (2, 2) a bar of the tallest height left of the chart with ``scale_label``,
        ``unit`` the group's display unit, and with ``truth``, ``truth`` (B, 2).
    """
    change, std = np.asarray(change, dtype=float), np.asarray(std, dtype=float)
    if len(kinds) != len(names):
        raise ValueError(f"{len(names)} parameter names but {len(kinds)} kinds")
    groups = list(dict.fromkeys(kinds))  # in order of first appearance
    out = {}
    for kind in groups:
        group, scale, unit = f"{kind.name}s", kind.display_scale, kind.display_unit
        mask = np.array([k is kind for k in kinds], dtype=bool)
        value, spread = change[mask] * scale, std[mask] * scale
        true = None if truth is None else np.asarray(truth, dtype=float)[mask] * scale
        reach = max(np.max(np.abs(value) + spread), 0.0 if true is None else np.max(np.abs(true)), 1e-12)
        k = BAR_HEIGHT / reach
        x = np.arange(mask.sum(), dtype=float)
        y = -value * k
        shapes = {
            "mins": np.column_stack([x - 0.35, np.minimum(y, 0.0)]),
            "sizes": np.column_stack([np.full_like(x, 0.7), np.abs(y)]),
            "colours": np.tile(np.array(BAR_COLOUR, dtype=np.uint8), (len(x), 1)),
            "names": np.column_stack([x, y + np.where(y < 0, -0.45, 0.45)]),
            "labels": list(np.asarray(names)[mask]),
            "scale": np.array([[-1.2, 0.0], [-1.2, -BAR_HEIGHT]]),
            "scale_label": f"{reach:.3f} {unit}",
            "whiskers": np.stack([np.column_stack([x, y - spread * k]), np.column_stack([x, y + spread * k])], axis=1),
            "zero": np.array([[-1.4, 0.0], [x[-1] + 0.6, 0.0]]),
            "unit": unit,
        }
        if true is not None:
            shapes["truth"] = np.column_stack([x, -true * k])
        out[group] = shapes
    return out


def covered_axis_height(origins: np.ndarray, radius: float, steps: int = 2000, along: int = 41) -> float:
    """The height [m] up to which the arm's link capsules cover the base's z axis, the highest over the steps (not
    the top of the base column: that is :func:`validation.experiments.experiment.column_top`, a point of the
    kinematic chain at zero angles). At each step the links that start on that axis (the run of link origins from
    the base within ``radius`` of it: the Panda's first link, its upper arm when upright) and the link that leaves
    it (a capsule leaning off the axis still covers it for a while), the highest point of the axis inside one of
    their capsules; 0 when none starts on it (a base placed off the origin). The viewer's z arrow reaches beyond it.

    Args:
        origins: (T, n + 1, 3) link frame origins, base frame [m], the base's first; capsules of ``radius`` [m] join
            consecutive ones.
        steps: at most this many steps are looked at, evenly spread (a long self-motion moves little between them).
        along: points looked at along each link.

    Returns:
        The height [m] along the base's z axis, at least 0.
    """
    origins = np.asarray(origins, dtype=float)
    origins = origins[np.unique(np.linspace(0, len(origins) - 1, min(steps, len(origins))).astype(int))]
    starts, ends = origins[:, :-1], origins[:, 1:]  # (T, n, 3): one capsule each
    on_axis = np.linalg.norm(starts[..., :2], axis=-1) <= radius
    leading = np.cumprod(on_axis, axis=1).astype(bool)  # from the base, at each step
    if not leading.any():
        return 0.0
    t = np.linspace(0.0, 1.0, along)[:, None]
    points = starts[leading][:, None] + t * (ends[leading] - starts[leading])[:, None]  # (L, along, 3)
    reach = radius**2 - np.sum(points[..., :2] ** 2, axis=-1)  # where > 0, the capsule holds the axis ...
    top = np.where(reach >= 0.0, points[..., 2] + np.sqrt(np.clip(reach, 0.0, None)), -np.inf)  # ... this high
    return float(max(top.max(), 0.0))


def round_up(value: float) -> float:
    """The least of 1, 2 and 5 times a power of ten at least ``value`` (> 0)."""
    power = 10.0 ** np.floor(np.log10(value))
    return float(next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= value * (1 - 1e-12)))


def magnification(offsets: np.ndarray, radius: float) -> tuple[float, float]:
    """How much to magnify samples' offsets from their fixture's centre so that their scatter fills a sphere.

    A fixture's residual scatter is tenths of a millimetre: drawn where they are, its samples sit in one dot inside
    the fixture's sphere of ``radius``. Magnified ``gain`` times about the centre, the sphere's radius stands for a
    round ``reach`` (1, 2 or 5 times a power of ten) at least the 95th percentile of the offsets' lengths.

    Args:
        offsets: (N, 3) samples less their fixture's centre [m].
        radius: the sphere's radius in the view [m].

    Returns:
        ``(gain, reach)``: the magnification (at least 1: a scatter wider than the sphere is drawn as it is) and the
        offset [m] the sphere's radius stands for (``radius`` when ``gain`` is 1).
    """
    lengths = np.linalg.norm(np.asarray(offsets, dtype=float).reshape(-1, 3), axis=1)
    far = float(np.quantile(lengths, 0.95)) if lengths.size else 0.0
    if not far > 0 or far >= radius:
        return 1.0, radius
    reach = min(round_up(far), radius)
    return radius / reach, reach
