"""Every broken file in tests/data/bad/ is refused cleanly by the real CLI.

Refused cleanly: exit code 2, the file (or run directory) named in the message, a message of a
few short lines, no traceback, and nothing written to --out. The corpus runs in-process (one
``main`` call per file, fast); a few files also go through a real ``zoetic`` subprocess.
Files too big to keep in the repository (a 2-million-element array, 10 001 nodes) and a
directory posing as a file are made here.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from zoetic.cli import main

BAD = Path(__file__).parent / "data" / "bad"
sys.path.insert(0, str(Path(__file__).parents[1] / "scripts"))
import make_bad_corpus as corpus  # noqa: E402


def _cases() -> list[tuple[str, str]]:
    out = []
    for kind in ("animal", "creature", "controller", "network"):
        out += [(kind, p.name) for p in sorted((BAD / kind).iterdir()) if p.is_file()]
    for kind in ("repertoire", "rundir"):
        out += [(kind, p.name) for p in sorted((BAD / kind).iterdir()) if p.is_dir()]
    return out


CASES = _cases()


def _argv(kind: str, target: Path, out: Path) -> list[str]:
    t, o = str(target), str(out)
    return {
        "animal": ["simulate", t, "--seconds", "0.1", "--no-video", "--out", o],
        "creature": [
            "san",
            "search",
            t,
            "--trials",
            "1",
            "--top",
            "1",
            "--workers",
            "1",
            "--no-video",
            "--out",
            o,
        ],
        "controller": [
            "simulate",
            "shark",
            "--controller",
            t,
            "--seconds",
            "0.1",
            "--no-video",
            "--out",
            o,
        ],
        "network": ["san", "show", t, "--out", str(out / "show.mp4")],
        "repertoire": [
            "sequence",
            "shark",
            "--memory",
            t,
            "--entries",
            "go-straight:1",
            "--no-video",
            "--out",
            o,
        ],
        "rundir": ["learn", "--resume", t, "--no-video"],
    }[kind]


def _check_refusal(code: int, err: str, name: str, out: Path) -> None:
    assert code == 2, err
    assert "Traceback" not in err
    assert name in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) <= 6 and len(err) < 1500, err
    assert not out.exists() or not any(out.iterdir()), list(out.iterdir())


def test_the_corpus_is_large_and_covers_every_format():
    files = [p for p in BAD.rglob("*") if p.is_file()]
    assert len(files) >= 60
    kinds = {k for k, _ in CASES}
    assert kinds == {"animal", "creature", "controller", "network", "repertoire", "rundir"}


def test_every_bad_file_is_refused_cleanly(tmp_path, capsys):
    work = tmp_path / "bad"
    shutil.copytree(BAD, work)  # nothing may be written beside the corpus
    failures = []
    for i, (kind, name) in enumerate(CASES):
        out = tmp_path / f"out{i}"
        code = main(_argv(kind, work / kind / name, out))
        err = capsys.readouterr().err
        try:
            _check_refusal(code, err, name, out)
        except AssertionError as exc:
            failures.append(f"{kind}/{name}: exit {code}: {exc}")
    assert not failures, "\n".join(failures)


def test_the_good_files_the_corpus_is_made_from_are_accepted(tmp_path, capsys):
    animal = tmp_path / "tri.toml"
    animal.write_text(corpus.ANIMAL)
    assert main(_argv("animal", animal, tmp_path / "a")) == 0, capsys.readouterr().err
    ctrl = tmp_path / "c.json"
    ctrl.write_text(json.dumps(corpus._constant()))
    assert main(_argv("controller", ctrl, tmp_path / "c")) == 0, capsys.readouterr().err
    from zoetic.san import load_creature
    from zoetic.san.creature_file import creature_from_dict
    from zoetic.san.network import check_fits, network_from_dict

    assert creature_from_dict(tomllib.loads(corpus.CREATURE)).n_actuators == 1
    from zoetic.runs import check_run_dir

    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "config.toml").write_text(corpus.CONFIG)
    check_run_dir(tmp_path / "run")  # the run configurations break only where they differ
    check_fits(network_from_dict(corpus._network()), load_creature("twolink"))


def _generated(tmp_path: Path) -> list[tuple[str, Path]]:
    big = json.loads(json.dumps(corpus._constant()))
    big["values"] = [0.5] * 2_000_000
    (tmp_path / "huge-array.json").write_text(json.dumps(big))
    head, _ = corpus.ANIMAL.split("[[nodes]]", 1)
    nodes = "".join(f"[[nodes]]\npos = [{i * 0.01}, 0, 0]\nmass = 1.0\n" for i in range(10_001))
    (tmp_path / "many-nodes.toml").write_text(head + nodes)
    (tmp_path / "dir.toml").mkdir()
    (tmp_path / "dir.json").mkdir()
    return [
        ("controller", tmp_path / "huge-array.json"),
        ("animal", tmp_path / "many-nodes.toml"),
        ("animal", tmp_path / "dir.toml"),
        ("controller", tmp_path / "dir.json"),
    ]


def test_huge_and_odd_files_are_refused_with_short_messages(tmp_path, capsys):
    for i, (kind, path) in enumerate(_generated(tmp_path)):
        out = tmp_path / f"out{i}"
        code = main(_argv(kind, path, out))
        _check_refusal(code, capsys.readouterr().err, path.name, out)


SUBPROCESS = [
    ("animal", "utf16.toml"),
    ("controller", "deep-nesting.json"),
    ("rundir", "string-budget"),
]


@pytest.mark.parametrize("kind, name", SUBPROCESS)
def test_a_real_subprocess_exits_2_without_traceback(tmp_path, kind, name):
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "zoetic", *_argv(kind, BAD / kind / name, out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    _check_refusal(proc.returncode, proc.stderr, name, out)


def test_debug_shows_the_traceback(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "zoetic",
            "--debug",
            *_argv("animal", BAD / "animal" / "nan-mass.toml", tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode != 0 and "Traceback" in proc.stderr and "BodyError" in proc.stderr
