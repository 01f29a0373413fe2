"""What the web viewer's page reads of a run: its glTF in base64, the centre-of-mass paths,
activations, events and figures, built from a Scene (``zoetic.viz.scene``), and the time
plots of its per-period scalars, taken from the record itself."""

from __future__ import annotations

import base64

import numpy as np

from zoetic.record import Record
from zoetic.viz.gltf import scene_glb, to_gltf_axes
from zoetic.viz.scene import Scene

MAX_EVENTS = 2000  # events listed in the page (a long aquarium run has many)
MAX_POINTS = 2000  # samples per plotted scalar: more than a strip chart's pixels
# the motion every record carries (``control.measure``), plotted before the other scalars
FIRST = ("speed", "depth", "height", "heading", "pitch", "roll")


def _round(a: np.ndarray, digits: int) -> list:
    return np.round(np.asarray(a, np.float64), digits).ravel().tolist()


def _series(values: np.ndarray) -> list:
    """Return plotted values as a JSON list: rounded, with null where not finite."""
    v = np.round(np.asarray(values, np.float64), 4)
    return [float(x) if np.isfinite(x) else None for x in v]


def plots_data(rec: Record) -> dict:
    """Return the record's numeric per-period scalars for the page's time plots: the period
    times (s from the record's start), each quantity's unit, and per animal its series (one
    per column of a quantity with several); integer-coded ones (an intention) are left to
    the labelled states."""
    periods = np.asarray(rec.period_times, float)
    if not len(periods) or not rec.scalars:
        return {}
    keep = np.arange(0, len(periods), int(np.ceil(len(periods) / MAX_POINTS)))
    order = {q: i for i, q in enumerate(FIRST)}
    animals: dict = {}
    for who, quantities in rec.scalars.items():
        series: dict = {}
        for what in sorted(quantities, key=lambda q: (order.get(q, len(FIRST)), q)):
            values = np.asarray(quantities[what])
            if what in rec.labels or values.ndim > 2:
                continue
            if values.ndim == 1:
                series[what] = _series(values[keep])
            else:
                for j in range(values.shape[1]):
                    series[f"{what} {j + 1}"] = _series(values[keep, j])
        if series:
            animals[who] = series
    if not animals:
        return {}
    return {
        "times": _round(periods[keep] - float(rec.times[0]), 4),
        "units": {k: str(v) for k, v in rec.units.items()},
        "animals": animals,
    }


def viewer_data(scene: Scene, rec: Record | None = None) -> dict:
    """Return what the page's script reads: the .glb in base64, the run's figures, events,
    and (given the record the scene came from) the time plots of its scalars."""
    if scene.animals:
        first = scene.animals[0].positions[0]
    else:  # rigid links: their frames' origins and far ends
        first = np.concatenate(
            [
                [ln.translations[0], ln.translations[0] + ln.vertices.max(0)]
                for ln in scene.creatures[0].links
            ]
        )
    first = first[np.isfinite(first).all(axis=1)]
    extent = float(np.linalg.norm(first - first.mean(0), axis=1).max()) if len(first) else 1.0
    sea = abs(scene.medium.water_level) < 1e8
    side_view = any(ln.axis == "z" for c in scene.creatures for ln in c.links)  # planar SANs
    events = sorted(scene.events, key=lambda e: e.t)[:MAX_EVENTS]
    numbers = {k: v for k, v in scene.numbers.items() if k != "distance_m"}
    if "distance_m" in scene.numbers:
        numbers["final distance (m)"] = scene.numbers["distance_m"]
    return {
        "title": scene.title,
        "kind": scene.kind,
        "medium": scene.medium.name,
        "fps": scene.fps,
        "frames": len(scene.times),
        "duration": scene.duration,
        "extent": max(extent, 0.05),
        "elevation": 12.0 if sea else 25.0,
        "numbers": numbers,
        "azimuth": 80.0 if side_view else 40.0,
        "animals": [
            {
                "name": a.name,
                "com": _round(to_gltf_axes(np.nan_to_num(a.com)), 4),
                "actuators": list(a.actuators),
                "activations": None if a.activations is None else _round(a.activations, 3),
            }
            for a in scene.movers
        ],
        "states": scene.states,
        "events": [[round(e.t, 3), e.who, e.what, e.detail] for e in events],
        "plots": {} if rec is None else plots_data(rec),
        "glb": base64.b64encode(scene_glb(scene)).decode("ascii"),
    }
