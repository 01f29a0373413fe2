"""``zoetic reproduce``: the papers' claims, their status, and regenerating their numbers."""

from __future__ import annotations

import json

import typer

from zoetic.cli.apps import app
from zoetic.cli.options import Json
from zoetic.cli.output import console
from zoetic.errors import ZoeticError


@app.command("reproduce")
def reproduce(
    claim: str = typer.Argument(None, help="A claim's id: rerun its experiment (default: list)."),
    quick: bool = typer.Option(
        False,
        "--quick",
        help="Rerun at a small budget (minutes; figures under docs/figures/quick).",
    ),
    write_docs: bool = typer.Option(
        False, "--write-docs", help="Write docs/reproduction.md from the registry and runs."
    ),
    timeout: float = typer.Option(None, "--timeout", min=1, help="Stop a rerun after this many s."),
    as_json: Json = False,
) -> None:
    """List every checkable claim of the papers with its status, or regenerate one."""
    from zoetic.reproduce.docs import counts
    from zoetic.reproduce.docs import write_docs as write
    from zoetic.reproduce.regenerate import claim_row, lookup, run_experiment
    from zoetic.reproduce.registry import load_registry

    reg = load_registry()
    if claim is not None:
        c = reg.claim(claim)
        if c.experiment is None:
            raise ZoeticError(f"{c.id}: no experiment regenerates it: {c.absent}")
        exp = reg.experiments[c.experiment]
        console.print(f"{c.id}: running {c.experiment} ({'quick' if quick else 'full'}) ...")
        rec = run_experiment(exp, quick=quick, timeout=timeout)
        row = claim_row(reg, c)
        out = {
            "claim": c.id,
            "experiment": exp.name,
            "mode": rec["mode"],
            "wall_s": rec["wall_s"],
            "files": len(rec["files"]),
            "stale": row["stale"],
            # this run's numbers: a quick rerun's, even where a full record is the claim's best
            "values": {k: lookup(rec["numbers"], k) for k in c.keys},
        }
        print(json.dumps(out)) if as_json else console.print(out)
        if write_docs:
            console.print(f"wrote {write(reg)}")
        return
    rows = [claim_row(reg, c) for c in reg.claims]
    if write_docs:
        console.print(f"wrote {write(reg)}")
        return
    if as_json:
        print(json.dumps(rows))
        return
    _table(rows, counts(rows))


def _table(rows: list[dict], n: dict) -> None:
    from rich.table import Table

    from zoetic.reproduce.docs import fmt

    colour = {
        "reproduced": "green",
        "partly": "yellow",
        "contradicted": "red",
        "explained": "magenta",
        "absent": "dim",
    }
    t = Table(title="claims of the three papers", show_lines=False)
    t.add_column("claim", no_wrap=True)
    for col in ("where", "status", "stale", "ours / latest run"):
        t.add_column(col, overflow="fold")
    for r in rows:
        latest = ""
        if r["run"] is not None and r["run"]["values"]:
            latest = (
                "\n"
                + r["run"]["mode"]
                + ": "
                + "; ".join(
                    f"{'/'.join(k.split(':')[-1].split('/')[-2:])} {fmt(v)}"
                    for k, v in r["run"]["values"].items()
                )
            )
        ours = r["ours"] if len(r["ours"]) <= 80 else r["ours"][:77] + "..."
        t.add_row(
            r["id"],
            r["where"],
            f"[{colour[r['status']]}]{r['status']}[/]",
            "stale" if r["stale"] else "",
            ours + latest,
        )
    console.print(t)
    console.print(
        ", ".join(f"{k} {v}" for k, v in n.items() if k not in ("total",)) + f" of {n['total']}"
    )
