"""``zoetic repertoire blend``: a swim at a chosen speed, or a turn of a chosen radius or
turning rate, as a blend of two neighbouring learned entries (``behavior.parametric``)."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from zoetic.cli.options import Force
from zoetic.cli.output import console
from zoetic.cli.repertoire import repertoire_app


@repertoire_app.command("blend")
def blend_cmd(
    memory: Path = typer.Argument(..., help="Repertoire directory."),
    speed: float = typer.Option(
        None, help="Swim speed asked (m/s), within the learned straight swims' (--speeds)."
    ),
    radius: float = typer.Option(
        None, help="Left turn radius asked (body lengths), within the learned turns'."
    ),
    turn_rate: float = typer.Option(
        None, help="Left turning rate asked (deg/s), within the learned turns'."
    ),
    right: bool = typer.Option(False, "--right", help="Turn right (the mirrored blend)."),
    out: Path = typer.Option(
        None, help="Controller file to write (default runs/swim-SPEED.json, runs/turn-R.json)."
    ),
    json_out: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    force: Force = False,
) -> None:
    """Blend the two learned entries around a speed (straight swims), a radius or a turning
    rate (go-straight and the turns) into a controller that does it (at the weight read off
    measured blends), measure it from rest and write it; play it with zoetic simulate ANIMAL
    --controller FILE."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.errors import ZoeticError
    from zoetic.runs import repertoire_body

    asked = {"speed": speed, "radius": radius, "turn-rate": turn_rate}
    given = [k for k, v in asked.items() if v is not None]
    if len(given) != 1:
        raise ZoeticError(f"give one of --speed, --radius, --turn-rate (got {len(given)})")
    if right and speed is not None:
        raise ZoeticError("--right mirrors a turn: give --radius or --turn-rate with it")
    rep = Repertoire.load(memory)
    body = repertoire_body(memory, rep.animal)
    rep = Repertoire.load(memory, body)
    kind, value = given[0], asked[given[0]]
    stem = "swim" if kind == "speed" else "turn-rate" if kind == "turn-rate" else "turn-r"
    out = out or Path("runs") / f"{stem}-{value:g}{'-right' if right else ''}.json"
    if out.exists() and not force:
        raise ZoeticError(f"{out}: exists; give another --out or --force to replace it")
    show = _swim if kind == "speed" else _turn
    result, lines = show(body, rep, kind, value, right, out)
    if json_out:
        print(json.dumps(result, indent=1))
        return
    for line in lines:
        console.print(line)
    console.print(f"wrote {out} (zoetic simulate {rep.animal} --controller {out})")


def _measured(body, ctrl, seconds: float) -> dict[str, float]:
    """Return the controller's motion from rest over ``seconds`` (``gait_motion``)."""
    from zoetic.behavior.parametric import gait_motion

    return {q: float(v[0]) for q, v in gait_motion(body, [ctrl], seconds).items()}


def _save(ctrl, out: Path) -> None:
    from zoetic.control import save_controller

    out.parent.mkdir(parents=True, exist_ok=True)
    save_controller(ctrl, out)


def _swim(body, rep, kind: str, speed: float, right: bool, out: Path) -> tuple[dict, list]:
    """Blend a swim at ``speed`` m/s and write it; return the result and lines saying it."""
    from zoetic.behavior.parametric import GAIT_SECONDS, speed_nodes, swim_at

    nodes = speed_nodes(body, rep)
    ctrl, how = swim_at(rep, nodes, speed)
    motion = _measured(body, ctrl, GAIT_SECONDS)
    _save(ctrl, out)
    measured = motion["speed"]
    result = how | {
        "entries_m_s": {n: round(v, 4) for n, v in nodes.table().items()},
        "measured_m_s": round(measured, 4),
        "error_m_s": round(measured - speed, 4),
        "turn_deg": round(motion["turn"], 2),
        "roll_deg": round(motion["roll"], 2),
        "controller": str(out),
    }
    w = how["weight"]
    lines = [
        "learned straight swims (m/s, steady from rest): "
        + ", ".join(f"{n} {v:.3f}" for n, v in result["entries_m_s"].items()),
        f"swim at {speed:g} m/s: {1 - w:.2f} {how['from']} + {w:.2f} {how['to']}; "
        f"measured {measured:.3f} m/s (error {measured - speed:+.3f}); from rest over "
        f"{GAIT_SECONDS:g} s it turns {motion['turn']:+.1f} deg and rolls up to "
        f"{motion['roll']:.1f} deg",
    ]
    return result, lines


def _radius(curvature: float, turn: float) -> float | None:
    """Return the radius (body lengths) of a path of ``curvature`` (1/BL) that turned ``turn``
    degrees; None if straight (under a degree, as ``promises.arc_radius`` has it)."""
    return round(1.0 / abs(curvature), 3) if abs(turn) >= 1.0 and curvature else None


def _turn(body, rep, kind: str, value: float, right: bool, out: Path) -> tuple[dict, list]:
    """Blend a turn of radius ``value`` body lengths (``kind`` "radius") or turning rate
    ``value`` deg/s ("turn-rate"), mirrored if ``right``, and write it; return the result and
    lines saying it."""
    import numpy as np

    from zoetic.behavior.parametric import (
        TURN,
        TURN_SECONDS,
        check_reached,
        nodes_for,
        play_at,
        turn_of_radius,
    )
    from zoetic.learning.abstraction import mirror_abstract

    nodes = nodes_for(body, rep, TURN)
    if kind == "radius":
        ctrl, how = turn_of_radius(rep, nodes, value)
    else:
        ctrl, how = play_at(rep, nodes, value, "turn_rate")
        how = {"turn_rate_deg_s": how.pop("turn_rate")} | how
    if right:
        ctrl = mirror_abstract(ctrl, body.actuator_mirror)
    m = _measured(body, ctrl, TURN_SECONDS)
    radius = _radius(m["curvature"], m["turn"])
    way = -1.0 if right else 1.0  # a turn the other way than asked measures negative
    if kind == "radius":
        signed = None if radius is None else radius * np.sign(way * m["curvature"])
        check_reached("radius", value, signed, "body lengths", m["roll"])
    else:
        check_reached("turning rate", value, way * m["turn_rate"], "deg/s", m["roll"])
    _save(ctrl, out)
    entries = {
        n: {
            "radius_bl": _radius(nodes.table("curvature")[n], nodes.table("turn")[n]),
            "turn_rate_deg_s": round(nodes.table("turn_rate")[n], 2),
            "speed_m_s": round(nodes.table("speed")[n], 3),
        }
        for n in nodes.names
    }
    result = how | {
        "side": "right" if right else "left",
        "entries": entries,
        "measured_radius_bl": radius,
        "measured_radius_m": None if radius is None else round(radius * body.length, 3),
        "turn_rate_deg_s": round(m["turn_rate"], 2),
        "speed_m_s": round(m["speed"], 3),
        "roll_deg": round(m["roll"], 2),
        "controller": str(out),
    }
    measured = radius if kind == "radius" else abs(m["turn_rate"])
    error = "" if measured is None else f" (error {100.0 * (measured - value) / value:+.1f}%)"
    if measured is not None:
        result["error_pct"] = round(100.0 * (measured - value) / value, 2)
    w = how["weight"]
    lines = [
        f"learned turns (the arc from rest over {TURN_SECONDS:g} s): "
        + ", ".join(
            f"{n} "
            + (f"radius {e['radius_bl']} BL" if e["radius_bl"] else "straight")
            + f" at {e['turn_rate_deg_s']:g} deg/s"
            for n, e in entries.items()
        ),
        f"{result['side']} turn "
        + (f"of radius {value:g} BL: " if kind == "radius" else f"at {value:g} deg/s: ")
        + f"{1 - w:.2f} {how['from']} + {w:.2f} {how['to']}; measured radius {radius} BL "
        f"({result['measured_radius_m']} m), turning {abs(m['turn_rate']):.1f} deg/s at "
        f"{m['speed']:.3f} m/s, rolling up to {m['roll']:.1f} deg{error}",
    ]
    return result, lines
