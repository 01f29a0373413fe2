"""What every command does alike: bad input is one message and exit 2 (never a traceback),
--out is a directory that must be empty (--force replaces a run), Ctrl-C exits 130 saying how
to go on, --version and -h, --help panels, numbers rounded for people."""

from __future__ import annotations

import json

import pytest
import typer

from zoetic.cli import _register, app, main
from zoetic.cli.apps import PANELS
from zoetic.cli.output import emit, fmt, number
from zoetic.errors import ZoeticError
from zoetic.io import LIMITS, load_json, load_toml, text_depth
from zoetic.outdir import prepare_out


def _leaves(command, path=()):
    """Yield (path, click command) for every runnable command of the Typer app."""
    subs = getattr(command, "commands", None)
    if subs is None:
        yield path, command
        return
    for name, sub in subs.items():
        yield from _leaves(sub, (*path, name))


_register()
COMMANDS = sorted(_leaves(typer.main.get_command(app)), key=lambda pc: pc[0])
# what a command names a thing by: given a bad file in its place, it must say so
NAMING = {"task", "trick", "creature", "prey", "predator", "network", "memory", "resume"}


def _bad_inputs(tmp_path):
    """The bad values every command is given: a missing file, malformed JSON, a directory that
    is not a run, a directory that does not exist."""
    bad = tmp_path / "bad.json"
    bad.write_text('{"kind": "time", "nodes": [1, 2,')
    empty = tmp_path / "empty"
    empty.mkdir()
    return {
        "missing": str(tmp_path / "missing.json"),
        "malformed": str(bad),
        "not-a-run": str(empty),
        "no-dir": str(tmp_path / "no" / "such" / "run"),
    }


def _argv(command, value: str) -> list[str] | None:
    """The command's arguments with ``value`` for every required parameter and every option
    that names a thing; None when the command has neither (nothing to give a bad file)."""
    args, named = [], False
    for p in command.params:
        if p.param_type_name == "argument":
            args.append(value)
            named = True
        elif p.param_type_name == "option" and (p.required or p.name in NAMING):
            args += [p.opts[0], value]
            named = True
    return args if named else None


def _bad_number_argv(command) -> list[str] | None:
    """The command's first numeric option given a word instead of a number."""
    for p in command.params:
        kind = getattr(getattr(p, "type_descriptor", None), "annotation", None)
        if p.param_type_name == "option" and kind in (int, float):
            return [p.opts[0], "many"]
    return None


@pytest.mark.parametrize("path, command", COMMANDS, ids=[" ".join(p) for p, _ in COMMANDS])
def test_every_command_refuses_bad_input_with_a_message_and_exit_2(
    path, command, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)  # a default --out lands here, never in the checkout
    cases = {k: _argv(command, v) for k, v in _bad_inputs(tmp_path).items()}
    cases["bad-number"] = _bad_number_argv(command)
    cases["bad-option"] = ["--no-such-option"]
    ran = 0
    for case, extra in cases.items():
        if extra is None:
            continue
        code = main([*path, *extra])
        out, err = capsys.readouterr()
        where = f"zoetic {' '.join(path)} ({case}: {extra})"
        assert code == 2, f"{where} exited {code}:\n{out}\n{err}"
        assert "Traceback" not in out + err, where
        assert err.strip(), f"{where} said nothing on stderr"
        ran += 1
    assert ran >= 1


def test_the_enumeration_sees_every_group():
    names = {p[0] for p, _ in COMMANDS}
    assert {"learn", "simulate", "san", "bench", "repertoire", "view", "export"} <= names
    assert ("san", "show") in {p for p, _ in COMMANDS}
    assert len(COMMANDS) >= 25


def test_version_and_h_on_the_root_and_subcommands(capsys):
    from importlib.metadata import version

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"zoetic {version('zoetic')}"
    for argv in (["-h"], ["learn", "-h"], ["san", "show", "-h"], ["bench", "jax", "-h"]):
        assert main(argv) == 0
        text = capsys.readouterr().out
        assert "Usage" in text and "--help" in text, argv


def test_help_groups_every_command_into_its_panel(capsys):
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    top = {p[0] for p, _ in COMMANDS}
    assert top == {name for names in PANELS.values() for name in names}
    places = [text.index(f"─ {panel} ") for panel in PANELS]
    assert places == sorted(places)  # learn, use, look, papers, bench, in that order
    assert "─ Commands " not in text  # none left outside a panel


def test_did_you_mean_for_tasks_tricks_species_and_entries(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    cases = [
        (["learn", "shark", "--task", "swim-straigt"], "'swim-straight'"),
        (["stunt", "dolphin", "--memory", "m", "--trick", "somersalt"], "'somersault'"),
        (["aquarium", "--prey", "minow"], "'minnow'"),
        (["simulate", "sharc"], "'shark'"),
        (["san", "search", "cartt"], "'cart'"),
    ]
    for argv, hint in cases:
        assert main(argv) == 2, argv
        assert f"did you mean {hint}" in capsys.readouterr().err, argv
    from zoetic.behavior.training import parse_sequence

    class Rep:
        names = ("straight", "wide-left", "wide-right")
        controllers = dict.fromkeys(names)
        durations = dict.fromkeys(names, 1.0)

    with pytest.raises(ZoeticError, match="did you mean 'wide-left'"):
        parse_sequence("straight,wide-lft", Rep())


def test_numbers_are_rounded_for_people_and_kept_whole_in_json(capsys):
    assert number(12.649999999999999) == "12.6"
    assert number(-0.83452) == "-0.835"
    assert number(3.0) == "3" and number(0.1) == "0.1" and number(1234.5) == "1234"
    assert number(0.000123) == "0.000123" and number(2.5e-7) == "2.50e-07"
    assert fmt(0.30000000000000004, "m") == "0.3 m" and fmt(True, "m") == "True"
    assert fmt([1.23456, 2]) == "[1.23, 2]" and fmt(float("nan")) == "nan"
    emit({"speed_m_s": 12.649999999999999}, as_json=False)
    assert capsys.readouterr().out.split() == ["speed_m_s", "12.6", "m/s"]
    emit({"speed_m_s": 12.649999999999999}, as_json=True)
    assert json.loads(capsys.readouterr().out) == {"speed_m_s": 12.649999999999999}


# ---------------------------------------------------------------------- deep nesting


@pytest.mark.parametrize("levels", [LIMITS.depth + 5, 5_000, 200_000])
def test_deeply_nested_files_are_refused_before_parsing(tmp_path, levels):
    deep = tmp_path / "deep.json"
    deep.write_text('{"kind": "time", "a": ' + "[" * levels + "]" * levels + "}")
    with pytest.raises(ZoeticError, match=r"deep\.json: nested more than 24 levels"):
        load_json(deep, "controller file")
    toml = tmp_path / "deep.toml"
    toml.write_text("a = " + "[" * levels + "]" * levels + "\n")
    with pytest.raises(ZoeticError, match=r"deep\.toml: nested more than 24 levels"):
        load_toml(toml, "animal file")


def test_text_depth_skips_strings_and_comments():
    assert text_depth('{"a": [1, [2]], "b": "[[[[", "c": "\\"[["}') == 3
    assert text_depth('x = "[[[["  # [[[[\n[[t]]\ny = [[1]]\n', "TOML") == 2
    assert text_depth("x = '''[[[\n[['''\n", "TOML") == 0


def test_a_deep_controller_file_exits_2_naming_it(tmp_path, capsys):
    deep = tmp_path / "deep.json"
    deep.write_text('{"kind": "sequence", "parts": ' + "[" * 50_000 + "]" * 50_000 + "}")
    argv = ["simulate", "shark", "--controller", str(deep), "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "deep.json" in err and "nested more than" in err and "Traceback" not in err


# ---------------------------------------------------------------------- --out


def _old_run(path):
    path.mkdir(parents=True)
    (path / "record.npz").write_bytes(b"old")
    (path / "stale.png").write_bytes(b"old")
    (path / "sub").mkdir()
    (path / "sub" / "x").write_text("old")
    return path


def test_a_non_empty_out_is_refused_and_force_replaces_a_run(tmp_path, capsys):
    out = _old_run(tmp_path / "run")
    argv = ["simulate", "shark", "--seconds", "0.2", "--no-video", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert str(out) in err and "--force" in err and "stale.png" in err
    assert (out / "stale.png").exists()  # refused: nothing touched
    assert main([*argv, "--force"]) == 0
    assert not (out / "stale.png").exists() and not (out / "sub").exists()
    assert (out / "record.npz").stat().st_size > 100  # the new run's record


def test_force_empties_only_a_zoetic_run_and_never_what_links_point_to(tmp_path, monkeypatch):
    keep = tmp_path / "keep.txt"
    keep.write_text("mine")
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "todo.txt").write_text("mine")
    with pytest.raises(ZoeticError, match="does not look like a zoetic run"):
        prepare_out(notes, force=True)
    assert (notes / "todo.txt").read_text() == "mine"
    run = _old_run(tmp_path / "run")
    (run / "link").symlink_to(keep)
    (run / "dirlink").symlink_to(notes)
    assert prepare_out(run, force=True) == run and list(run.iterdir()) == []
    assert keep.read_text() == "mine" and (notes / "todo.txt").exists()
    monkeypatch.chdir(run)
    (run / "record.npz").write_bytes(b"x")
    with pytest.raises(ZoeticError, match="will not empty it"):
        prepare_out(tmp_path / "run", force=True)  # it holds the working directory
    assert prepare_out(tmp_path / "fresh") == tmp_path / "fresh"  # missing: used as it is


def test_learn_refuses_a_non_empty_out_naming_resume(tmp_path, capsys):
    out = _old_run(tmp_path / "run")
    assert main(["learn", "shark", "--budget", "8", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"zoetic learn --resume {out}" in err and "--force" in err


def test_san_show_out_is_a_directory(tmp_path, capsys):
    import numpy as np

    from zoetic.san import load_creature
    from zoetic.san.network import random_network, save_network

    cart = load_creature("cart")
    net = tmp_path / "net.json"
    save_network(random_network(cart, np.random.default_rng(0)), net, cart)
    argv = ["san", "show", str(net), "--seconds", "0.3"]
    assert main([*argv, "--out", str(tmp_path / "x.mp4")]) == 2
    assert "a directory" in capsys.readouterr().err
    assert main([*argv, "--out", str(tmp_path / "x")]) == 0
    assert (tmp_path / "x" / "show-net.mp4").stat().st_size > 1000
    assert main([*argv, "--out", str(tmp_path / "x")]) == 2  # now it holds a video
    assert "--force" in capsys.readouterr().err


# ---------------------------------------------------------------------- Ctrl-C and --resume


def test_ctrl_c_during_learn_saves_says_how_to_resume_and_exits_130(tmp_path, monkeypatch, capsys):
    from zoetic.learning.run import Run

    def interrupt(self, evaluator):
        raise KeyboardInterrupt

    monkeypatch.setattr(Run, "step", interrupt)
    out = tmp_path / "run"
    assert main(["learn", "shark", "--budget", "40", "--nodes", "4", "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert f"zoetic learn --resume {out}" in err and "Traceback" not in err
    assert (out / "checkpoint.npz").exists() and (out / "config.toml").exists()


def test_ctrl_c_in_any_command_is_one_line_and_exit_130(tmp_path, monkeypatch, capsys):
    import zoetic.runs

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(zoetic.runs, "simulate_run", interrupt)
    assert main(["simulate", "shark", "--out", str(tmp_path / "o")]) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_resume_takes_a_new_budget_and_refuses_other_settings(tmp_path, capsys):
    import tomllib

    out = tmp_path / "run"
    base = ["--nodes", "4", "--popsize", "8", "--no-video"]
    assert main(["learn", "shark", "--budget", "16", *base, "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["learn", "--resume", str(out), "--optimizer", "anneal"]) == 2
    err = capsys.readouterr().err
    assert "--optimizer anneal differs from the run's cmaes" in err and "--budget" in err
    assert (
        main(["learn", "--resume", str(out), "--budget", "32", "--nodes", "4", "--no-video"]) == 0
    )
    said = capsys.readouterr().out
    assert "budget 16 -> 32" in said
    assert tomllib.loads((out / "config.toml").read_text())["run"]["budget"] == 32
    rows = (out / "history.csv").read_text().strip().splitlines()
    assert len(rows) - 1 == 32  # one row per evaluation, all of the new budget


def test_a_bug_is_one_line_exit_1_and_debug_shows_the_traceback(tmp_path, monkeypatch, capsys):
    import zoetic.runs

    def broken(*args, **kwargs):
        raise TypeError("a bug")

    monkeypatch.setattr(zoetic.runs, "simulate_run", broken)
    assert main(["simulate", "shark", "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert "internal error: TypeError: a bug" in err and "--debug" in err
    assert "Traceback" not in err
    with pytest.raises(TypeError, match="a bug"):
        main(["--debug", "simulate", "shark", "--out", str(tmp_path / "o")])
