"""One HTML page per run: the viewer script (three.js bundled by esbuild) and the data inline.

The script ``static/viewer.js`` is built from ``web/viewer.js`` and the ``three`` npm package by
``./run.sh`` (``npm ci && npm run build`` in ``web/``); it is not kept in git. The page needs
nothing else: no network, no server, so it can be mailed and opened from disk.
"""

from __future__ import annotations

import base64
import json
import os
from pathlib import Path

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.io import atomic_write_bytes
from zoetic.viz.gltf import scene_glb, to_gltf_axes
from zoetic.viz.scene import Scene

_STATIC = Path(__file__).parent / "static"

_STYLE = """
html, body { margin: 0; height: 100%; overflow: hidden; background: #222;
  font: 13px system-ui, sans-serif; color: #eee; }
#zoetic { position: absolute; inset: 0 0 44px 0; }
#zoetic canvas { display: block; }
#panel { position: absolute; top: 8px; left: 8px; width: 230px; padding: 8px 10px;
  background: rgba(20, 24, 32, 0.72); border-radius: 6px; }
#panel .title { font-weight: 600; margin-bottom: 2px; }
#panel .time { font-variant-numeric: tabular-nums; margin-bottom: 4px; }
#panel .sub { margin-top: 6px; color: #bcd; }
#panel table { border-collapse: collapse; width: 100%; }
#panel td:last-child { text-align: right; font-variant-numeric: tabular-nums; }
.bar { display: flex; align-items: center; gap: 6px; margin: 1px 0; }
.bar span { width: 110px; overflow: hidden; white-space: nowrap; font-size: 11px; }
.bar .track { flex: 1; height: 8px; background: #444; border-radius: 2px; }
.bar .fill { height: 100%; background: #e8a33c; border-radius: 2px; }
#controls { position: fixed; left: 0; right: 0; bottom: 0; height: 44px; display: flex;
  align-items: center; gap: 10px; padding: 0 12px; background: #1a1d24; box-sizing: border-box; }
#timeline { flex: 1; }
#error { position: absolute; top: 40%; left: 10%; color: #f88; white-space: pre-wrap; }
"""


def bundle_path() -> Path:
    """Return the built viewer script; a ZoeticError says how to build it when it is missing."""
    path = _STATIC / "viewer.js"
    if not path.exists():
        raise ZoeticError(
            f"{path}: the viewer's script is not built; run ./run.sh from a zoetic checkout "
            "(it runs `npm ci && npm run build` in web/, which needs Node.js and npm)"
        )
    return path


def _round(a: np.ndarray, digits: int) -> list:
    return np.round(np.asarray(a, np.float64), digits).ravel().tolist()


def scene_data(scene: Scene) -> dict:
    """Return what the page's script reads: the .glb in base64 and the run's figures."""
    if scene.animals:
        first = scene.animals[0].positions[0]
    else:  # rigid links: their frames' origins and far ends
        first = np.concatenate([[ln.translations[0], ln.translations[0] + ln.vertices.max(0)]
                                for ln in scene.creatures[0].links])  # fmt: skip
    first = first[np.isfinite(first).all(axis=1)]
    extent = float(np.linalg.norm(first - first.mean(0), axis=1).max()) if len(first) else 1.0
    sea = abs(scene.medium.water_level) < 1e8
    side_view = any(ln.axis == "z" for c in scene.creatures for ln in c.links)  # planar SANs
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
        "glb": base64.b64encode(scene_glb(scene)).decode("ascii"),
    }  # fmt: skip


def _inline(text: str) -> str:
    """Return text safe inside a <script> element (no closing tag can appear in it)."""
    return text.replace("</", "<\\/")


def scene_html(scene: Scene) -> str:
    """Return the self-contained HTML page that plays the scene."""
    script = bundle_path().read_text(encoding="utf-8")
    data = json.dumps(scene_data(scene), separators=(",", ":")).replace("<", "\\u003c")
    title = scene.title.replace("&", "&amp;").replace("<", "&lt;")
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>{title} · zoetic</title><style>{_STYLE}</style></head><body>"
        "<div id='zoetic'></div>"
        f"<script id='zoetic-data' type='application/json'>{data}</script>"
        f"<script>{_inline(script)}</script></body></html>\n"
    )


def write_html(scene: Scene, path: str | os.PathLike) -> Path:
    """Write the scene's page to ``path`` (atomically); returns the path."""
    return atomic_write_bytes(path, scene_html(scene).encode("utf-8"))
