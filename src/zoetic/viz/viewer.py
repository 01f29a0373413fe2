"""What the web viewer's page reads of a run: its glTF in base64, the centre-of-mass paths,
activations, events and figures, built from a Scene (``zoetic.viz.scene``)."""

from __future__ import annotations

import base64

import numpy as np

from zoetic.viz.gltf import scene_glb, to_gltf_axes
from zoetic.viz.scene import Scene

MAX_EVENTS = 2000  # events listed in the page (a long aquarium run has many)


def _round(a: np.ndarray, digits: int) -> list:
    return np.round(np.asarray(a, np.float64), digits).ravel().tolist()


def viewer_data(scene: Scene) -> dict:
    """Return what the page's script reads: the .glb in base64, the run's figures, events."""
    if scene.animals:
        first = scene.animals[0].positions[0]
    else:  # rigid links: their frames' origins and far ends
        first = np.concatenate([[ln.translations[0], ln.translations[0] + ln.vertices.max(0)]
                                for ln in scene.creatures[0].links])  # fmt: skip
    first = first[np.isfinite(first).all(axis=1)]
    extent = float(np.linalg.norm(first - first.mean(0), axis=1).max()) if len(first) else 1.0
    sea = abs(scene.medium.water_level) < 1e8
    side_view = any(ln.axis == "z" for c in scene.creatures for ln in c.links)  # planar SANs
    events = sorted(scene.events, key=lambda e: e.t)[:MAX_EVENTS]
    numbers = {k: v for k, v in scene.numbers.items() if k != "distance_m"}
    if "distance_m" in scene.numbers:
        numbers["final distance (m)"] = scene.numbers["distance_m"]
    return {
        "title": scene.title, "kind": scene.kind, "medium": scene.medium.name,
        "fps": scene.fps, "frames": len(scene.times), "duration": scene.duration,
        "extent": max(extent, 0.05), "elevation": 12.0 if sea else 25.0, "numbers": numbers,
        "azimuth": 80.0 if side_view else 40.0,
        "animals": [{
            "name": a.name,
            "com": _round(to_gltf_axes(np.nan_to_num(a.com)), 4),
            "actuators": list(a.actuators),
            "activations": None if a.activations is None else _round(a.activations, 3),
        } for a in scene.movers],
        "states": scene.states,
        "events": [[round(e.t, 3), e.who, e.what, e.detail] for e in events],
        "glb": base64.b64encode(scene_glb(scene)).decode("ascii"),
    }  # fmt: skip


