"""The viewer's script ships built (git and the wheel), and is the build of today's sources.

``npm run build`` in web/ (``./run.sh build-viewer``) writes ``viewer.js`` and, beside it,
``viewer.sources.json``: the SHA-256 of the bundle and of every file under web/ but
node_modules/. Without npm, the stamp tells whether a source changed since the last build; with
npm (which the tests need anyway for the glTF validator), a rebuild must give the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WEB = ROOT / "web"
STATIC = ROOT / "src" / "zoetic" / "web" / "static"
REBUILD = "run ./run.sh build-viewer (npm run build in web/) and commit src/zoetic/web/static/"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _sources() -> dict[str, str]:
    """Every file under web/ but node_modules/, by its path from the repository root."""
    return {
        p.relative_to(ROOT).as_posix(): _sha256(p)
        for p in WEB.rglob("*")
        if p.is_file() and "node_modules" not in p.relative_to(WEB).parts
    }


def _stamp(folder: Path) -> dict:
    return json.loads((folder / "viewer.sources.json").read_text())


def test_the_shipped_bundle_is_the_one_its_stamp_names() -> None:
    assert _stamp(STATIC)["bundle"] == _sha256(STATIC / "viewer.js"), (
        f"src/zoetic/web/static/viewer.js was changed by hand: {REBUILD}"
    )


def test_no_viewer_source_changed_since_the_bundle_was_built() -> None:
    stamped, now = _stamp(STATIC)["sources"], _sources()
    assert "web/viewer.js" in now and "web/package-lock.json" in now
    changed = sorted(k for k in stamped.keys() | now.keys() if stamped.get(k) != now.get(k))
    assert not changed, f"changed since the viewer was bundled: {changed}; {REBUILD}"


def test_a_rebuild_gives_the_shipped_bytes(tmp_path: Path) -> None:
    node = shutil.which("node")
    assert node and (WEB / "node_modules" / "esbuild").exists(), (
        "esbuild is installed by ./run.sh (npm ci in web/; needs Node.js and npm)"
    )
    out = tmp_path / "viewer.js"
    subprocess.run([node, str(WEB / "build.mjs"), "--outfile", str(out)], check=True, cwd=WEB)
    assert out.read_bytes() == (STATIC / "viewer.js").read_bytes(), REBUILD
    assert _stamp(tmp_path) == _stamp(STATIC)
