"""Every code block of README.md runs: ```sh blocks command by command through the CLI in a temp
dir, with tiny budgets; ```python blocks (all in "Python API") with exec in tests/test_api.py.

The conventions (zoetic.bench.readme): ``[~12 s]`` in a command's comment states its CPU time
(``zoetic bench readme`` measures it); ``<!-- test: slow -->`` before a fence puts the block in
the slow tier.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from zoetic.bench.readme import MARK, QUICK_START, Block, read_readme
from zoetic.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BLOCKS = read_readme(README)

# what the tests change so that each command takes seconds: option -> value (None: a flag)
TINY: dict[str, dict[str, str | None]] = {
    "demo": {"--budget": "24"},
    "simulate": {"--seconds": "1"},
    "learn": {"--budget": "24"},
    "repertoire train": {"--budget": "16"},
    "stunt": {"--budget": "32"},
    "macro": {"--budget": "16"},
    "san search": {"--trials": "6", "--top": "2", "--seconds": "1"},
    "san tune": {"--trials": "6"},
    "san evolve": {"--trials": "6"},
    "aquarium": {"--seconds": "1"},
    "pursue": {"--seconds": "1"},
    "san show": {"--seconds": "1"},
}
# videos take most of a tiny run's time; other tests check them
NO_VIDEO = {"demo", "simulate", "learn", "stunt", "macro", "sequence", "track", "aquarium"}
NO_VIDEO |= {"pursue", "san search", "san tune", "san evolve"}


def tiny(argv: tuple[str, ...]) -> list[str]:
    """The CLI arguments of a README command with the TINY options set (replaced or added)."""
    args = list(argv[1:])
    key = " ".join(args[:2]) if args[0] in ("san", "repertoire") else args[0]
    extra: dict[str, str | None] = {"--no-video": None} if key in NO_VIDEO else {}
    for option, value in (TINY.get(key, {}) | extra).items():
        if value is None:
            args += [] if option in args else [option]
        elif option in args:
            args[args.index(option) + 1] = value
        else:
            args += [option, value]
    return args


def _params(blocks: list[Block]) -> list:
    """One test per sh block, named by its section and place in it (``1995-2``)."""
    out, seen = [], {}
    for b in blocks:
        if b.lang == "sh":
            name = b.section.split(":")[0].lower().replace(" ", "-")
            seen[name] = seen.get(name, 0) + 1
            marks = [pytest.mark.slow] if b.slow else []
            out.append(pytest.param(b, marks=marks, id=f"{name}-{seen[name]}"))
    return out


SH = _params(BLOCKS)


def test_the_readme_holds_only_blocks_the_tests_run() -> None:
    """sh blocks run here; python blocks run in tests/test_api.py, which reads its section."""
    assert {b.lang for b in BLOCKS} <= {"sh", "python"}
    assert {b.section for b in BLOCKS if b.lang == "python"} == {"Python API"}
    assert sum(b.lang == "sh" for b in BLOCKS) >= 4 and any(b.lang == "python" for b in BLOCKS)


def test_the_quick_start_is_six_timed_commands_at_most() -> None:
    quick = [c for b in BLOCKS if b.section == QUICK_START for c in b.commands()]
    assert 1 <= len(quick) <= 6
    assert all(c.stated_s is not None for c in quick), [c.text for c in quick]


def test_every_time_the_readme_states_is_a_command_the_bench_times() -> None:
    text = README.read_text()
    timed = [c for b in BLOCKS if b.lang == "sh" for c in b.commands() if c.stated_s is not None]
    assert len(MARK.findall(text)) == len(timed)


def test_ci_runs_the_readmes_test_command() -> None:
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    steps = [s for s in ci if s.strip() and not s.startswith(("#", "set ", "cd "))]
    assert steps == ["./run.sh test"] and "`./run.sh test`" in README.read_text()


@pytest.mark.parametrize("block", SH)
def test_a_sh_block_runs(block: Block, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for cmd in block.commands():
        assert main(tiny(cmd.argv)) == 0, f"README.md:{cmd.line}: {cmd.text}"
