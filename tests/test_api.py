"""The Python API: ``import zoetic`` is light, and the README's examples run as written."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

import zoetic

README = Path(__file__).resolve().parents[1] / "README.md"


def _section_code(title: str) -> list[str]:
    text = README.read_text()
    start = text.index(f"## {title}\n")
    end = text.find("\n## ", start + 1)
    section = text[start : end if end > 0 else None]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


@pytest.mark.filterwarnings("ignore:.*Box observation space:UserWarning")
def test_the_readme_python_api_examples_run(tmp_path, monkeypatch, capsys):
    blocks = _section_code("Python API")
    assert len(blocks) >= 3
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    for block in blocks:
        exec(compile(block, str(README), "exec"), scope)  # noqa: S102
    # what the examples claim
    assert scope["traj"].positions.shape[1:] == (201, scope["shark"].n_nodes, 3)
    result = scope["result"]
    assert len(result.history) >= 96 and result.best_E == min(result.history)
    assert result.controller.animal == "shark" and result.run_dir is None
    assert scope["touches"] > 0 and scope["scene"].ball_velocities[0, 0, 0] == 0.0
    assert scope["scene"].time == 0.0  # restored to "now"
    assert scope["run"].final.time == 2.0
    tank = scope["tank"]
    assert len(tank.tank.fishes) == 4 and abs(tank.life.times[-1] - 3.0) < 1e-6
    out = capsys.readouterr().out
    assert "(1, 61, 23, 3)" in out and "(64, 20) (240, 320, 3)" in out


def test_import_zoetic_is_light_and_names_load_lazily():
    code = (
        "import sys, zoetic; heavy = [m for m in ('jax', 'matplotlib', 'numba', 'mujoco') "
        "if m in sys.modules]; print(heavy); zoetic.load_animal('snake'); "
        "print([m for m in ('jax', 'matplotlib') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split("\n")[:2] == ["[]", "[]"]
    for name in zoetic.__all__:
        assert getattr(zoetic, name) is not None
    import zoetic.learning.run as run_module  # the subpackage and the call have their own names

    assert inspect.isfunction(zoetic.learn) and zoetic.learning.run is run_module
    assert type(sys.modules["zoetic"]) is types.ModuleType  # no module-class swap


def test_learn_can_keep_its_run_directory(tmp_path):
    result = zoetic.learn(
        "snake", "crawl-straight", optimizer="anneal", budget=12, seed=1, out=tmp_path / "run"
    )
    assert result.run_dir == tmp_path / "run"
    assert (tmp_path / "run" / "controller.json").exists()
    assert np.isfinite(result.best_E)
