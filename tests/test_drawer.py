"""The figure process of ``zoetic repertoire train``: it draws what this process would."""

from __future__ import annotations

import numpy as np
import pytest

from zoetic.errors import ZoeticError
from zoetic.viz import drawer as drawer_module
from zoetic.viz.abstraction import plot_repertoire
from zoetic.viz.drawer import Drawer


def _figure_args(path):
    t = np.linspace(0.0, 2.0, 50)
    u = 0.5 + 0.5 * np.sin(np.outer(t, [1.0, 2.0]) * 2 * np.pi)
    com = np.stack([t, 0.1 * t, np.sin(t)], axis=1)
    return ({"a": (t, u), "b": (t, u[:, ::-1])}, {"a": com, "b": -com}, ("m1", "m2"), path, "x")


def test_the_second_process_draws_the_figure_this_one_would(tmp_path, monkeypatch):
    here = plot_repertoire(*_figure_args(tmp_path / "here.png"))

    def not_here(name):
        raise AssertionError(f"{name} drawn in this process, not the second")

    monkeypatch.setattr(drawer_module, "_function", not_here)
    with Drawer() as d:
        d.draw("plot_repertoire", *_figure_args(tmp_path / "there.png"))
        there = d.wait()
    assert there == tmp_path / "there.png"
    assert there.read_bytes() == here.read_bytes()


def test_a_figure_the_second_process_does_not_answer_is_drawn_here(tmp_path):
    with Drawer() as d:
        d.close()  # the process has gone before the figure was asked for
        d.draw("plot_repertoire", *_figure_args(tmp_path / "late.png"))
        late = d.wait()
    assert late.read_bytes() == plot_repertoire(*_figure_args(tmp_path / "ref.png")).read_bytes()


def test_a_drawing_that_fails_raises_in_this_process(tmp_path):
    (tmp_path / "file").write_text("not a directory")
    with Drawer() as d:
        d.draw("plot_repertoire", *_figure_args(tmp_path / "file" / "bad.png"))
        with pytest.raises(ZoeticError, match="not a directory"):
            d.wait()
