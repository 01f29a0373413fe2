"""One HTML page per run: the viewer script (three.js bundled by esbuild) and the data inline
(built by ``zoetic.viz.viewer`` from the run record).

The script ``static/viewer.js`` is built from ``web/viewer.js`` and the ``three`` npm package by
``./run.sh build-viewer`` (``npm run build`` in ``web/``) and shipped built, in git and in the
wheel, so ``pip install`` needs no npm. The page needs nothing else: no network, no server, so it
can be mailed and opened from disk.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from zoetic.errors import ZoeticError
from zoetic.io import atomic_write_bytes

_STATIC = Path(__file__).parent / "static"

_STYLE = """
html, body { margin: 0; height: 100%; overflow: hidden; background: #222;
  font: 13px system-ui, sans-serif; color: #eee; }
#zoetic { position: absolute; inset: 0 0 44px 0; }
#zoetic canvas { display: block; }
#panel { position: absolute; top: 8px; left: 8px; width: 230px; padding: 8px 10px; z-index: 2;
  background: rgba(20, 24, 32, 0.72); border-radius: 6px; }
#panel .title { font-weight: 600; margin-bottom: 2px; }
#panel .time { font-variant-numeric: tabular-nums; margin-bottom: 4px; }
#panel .sub { margin-top: 6px; color: #bcd; }
#panel .events, #panel .states { white-space: pre-line; font-size: 11px; }
#panel table { border-collapse: collapse; width: 100%; }
#panel details { margin-top: 2px; max-height: 60vh; overflow-y: auto; }
#panel summary { cursor: pointer; color: #bcd; }
#panel td:last-child { text-align: right; font-variant-numeric: tabular-nums; }
#controls { position: fixed; left: 0; right: 0; bottom: 0; height: 44px; display: flex;
  align-items: center; gap: 10px; padding: 0 12px; background: #1a1d24; box-sizing: border-box; }
#timeline { flex: 1; }
#side { position: absolute; top: 0; right: 0; bottom: 44px; width: 320px; overflow-y: auto;
  padding: 4px 8px; box-sizing: border-box; background: #1a1d24; font-size: 11px; }
body.with-side #zoetic { right: 320px; }
#side > div { margin-bottom: 8px; }
#side .head { display: flex; gap: 6px; align-items: center; margin-bottom: 3px; }
#side .head .name { font-weight: 600; color: #cde; }
#side select { flex: 1; font-size: 11px; }
#side canvas { display: block; margin-top: 2px; }
#side .legend { display: flex; flex-wrap: wrap; gap: 1px 8px; color: #bcd; font-size: 10px; }
#side .legend span { padding-left: 3px; }
#plots .chips { display: flex; flex-wrap: wrap; gap: 2px 8px; margin-bottom: 3px; }
#plots .chip { white-space: nowrap; color: #bcd; }
#plots .chip input { margin: 0 2px 0 0; vertical-align: middle; }
#zoetic .label { position: absolute; transform: translate(-50%, -100%); padding: 1px 4px;
  background: rgba(20, 24, 32, 0.7); border-radius: 3px; font-size: 11px; white-space: nowrap;
  pointer-events: none; }
@media (max-width: 600px) { #side { display: none; } body.with-side #zoetic { right: 0; } }
#error { position: absolute; top: 40%; left: 10%; color: #f88; white-space: pre-wrap; }
"""


def bundle_path() -> Path:
    """Return the built viewer script; a ZoeticError says how to build it when it is missing."""
    path = _STATIC / "viewer.js"
    if not path.exists():
        raise ZoeticError(
            f"{path}: the viewer's script is missing; reinstall zoetic, or in a checkout run "
            "./run.sh build-viewer (npm run build in web/, which needs Node.js and npm)"
        )
    return path


def _inline(text: str) -> str:
    """Return text safe inside a <script> element (no closing tag can appear in it)."""
    return text.replace("</", "<\\/")


def page_html(data: dict) -> str:
    """Return the self-contained HTML page that plays a run: ``data`` is what the script reads
    (``zoetic.viz.viewer.viewer_data``: the run's .glb in base64, its title and figures)."""
    script = bundle_path().read_text(encoding="utf-8")
    text = json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
    title = str(data["title"]).replace("&", "&amp;").replace("<", "&lt;")
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>{title} · zoetic</title><style>{_STYLE}</style></head><body>"
        "<div id='zoetic'></div>"
        f"<script id='zoetic-data' type='application/json'>{text}</script>"
        f"<script>{_inline(script)}</script></body></html>\n"
    )


def write_html(data: dict, path: str | os.PathLike) -> Path:
    """Write the run's page (:func:`page_html`) to ``path`` (atomically); returns the path."""
    return atomic_write_bytes(path, page_html(data).encode("utf-8"))
