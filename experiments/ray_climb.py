"""How far can the ray rise or sink in 3 s? A measurement (swim-up and swim-down promise 0.5 m).

Plays hand-made flaps on the zoo ray from the swim-up task's two starts (rest and cruising):
the built-in 2 Hz flap with the wings held up or down (an offset between elevators and
depressors, which tilts the flap's thrust and so pitches the disc) and with a fast or slow
downstroke (a stroke asymmetry, which pushes more water one way). For each it prints the rise
of the centre of mass after 3 s and 6 s and the pitch reached: the disc pitches at about
5 degrees/s at most, so the ray's rise in 3 s stays under a tenth of a metre.

Then two bounds that hold whatever the flap: (1) the ray set at a pitch of 0, 45 or 90 degrees
from the first instant (from rest and at the level ray's cruising speed), swimming the flap or
the gaits in the controller files given on the command line: its rise and path in 3 s. It
keeps its pitch and swims along its axis, so the rise is at most the path, and from rest the
path in 3 s is under the promised 0.5 m. (2) How fast a pitch rate dies away (the disc's
pitch damping), and so the pitching moment a steady 30 degrees/s would take.

Last, what a body change would give: the ray with a pair of fins (flat plates of 0.015 m², the
shark's, or 0.04 m² each, at the front or the rear body station, turning +-0.5 rad), flapping
with the fins held at either end of their range: its rise and pitch in 3 s.

Run: python experiments/ray_climb.py [controller.json ...]  (about a minute)
"""

from __future__ import annotations

import sys
import tempfile
import tomllib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import tomli_w

from zoetic import bodies
from zoetic.bodies import load_animal
from zoetic.control.files import load_controller
from zoetic.control.measure import motion_scalars
from zoetic.physics import State, get_medium, simulate
from zoetic.tasks import cruise_speed, load_task, parse_task, start_states

SECONDS = 6.0
OFFSETS = (-1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 1.0)  # elevators minus depressors (+: wings up)
DOWNSTROKE = (0.3, 0.5, 0.7)  # fraction of the cycle spent on the downstroke


def flap(body, offset: float, down: float) -> np.ndarray:
    """Return the activation table (T, 4) of a 2 Hz flap with the given offset and stroke."""
    t = np.arange(int(round(SECONDS / body.dt))) * body.dt
    ph = (t * body.wave_frequency) % 1.0
    s = np.where(ph < down, np.sin(np.pi * ph / down), -np.sin(np.pi * (ph - down) / (1.0 - down)))
    dep = np.clip(0.5 + 0.5 * s - offset / 2, 0.0, 1.0)
    ele = np.clip(0.5 - 0.5 * s + offset / 2, 0.0, 1.0)
    cols = {"elevator": ele, "depressor": dep}
    return np.stack([cols[n.split("_")[0]] for n in body.actuator_names], axis=1)


def main() -> None:
    body = load_animal("ray")
    starts = start_states(load_task("swim-up"), body)
    cases = [(o, d) for o in OFFSETS for d in DOWNSTROKE]
    table = np.stack([flap(body, o, d) for o, d in cases])
    every = int(round(0.05 / body.dt))
    print("start     offset  down  rise@3s  rise@6s  pitch@3s  pitch@6s (deg)")
    for i, name in enumerate(("rest", "cruising")):
        pos = np.repeat(starts.positions[i : i + 1], len(cases), axis=0)
        vel = np.repeat(starts.velocities[i : i + 1], len(cases), axis=0)
        tr = simulate(body, table, state=State(pos, vel), record_every=every)
        com = tr.com(body)
        pitch = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))["pitch"]
        k3 = int(np.searchsorted(tr.times, 3.0))
        rise = com[:, :, 1] - com[:, :1, 1]
        for j, (o, d) in enumerate(cases):
            print(
                f"{name:9s} {o:+5.1f}  {d:4.1f}  {rise[j, k3]:+7.3f}  {rise[j, -1]:+7.3f}"
                f"  {pitch[j, k3]:+7.1f}  {pitch[j, -1]:+7.1f}"
            )
        best = int(np.argmax(np.abs(rise[:, k3])))
        print(f"{name}: largest change of depth in 3 s {rise[best, k3]:+.3f} m {cases[best]}")
    gaits = {"flap": flap(body, 0.0, 0.5)}
    gaits |= {
        path: load_controller(path, body).table(len(table[0]), body.dt) for path in sys.argv[1:]
    }
    pitched_bound(body, gaits)
    pitch_damping(body, flap(body, 0.0, 0.5))
    for station in (0, 3):
        for area in (0.015, 0.04):
            with_fins(finned(station, area), flap(body, 0.0, 0.5), f"station {station}, {area} m2")


def pitched_bound(body, gaits: dict[str, np.ndarray], pitches=(0.0, 45.0, 90.0)) -> None:
    """Print the rise and path of the centre of mass in 3 s of each gait from rest and from the
    level ray's cruising speed along its axis, pitched by ``pitches`` (deg) at the first instant."""
    task = load_task("swim-up")
    level = cruise_speed(body)  # the level ray's (a pitched start would measure its own)
    starts = [
        {"name": f"{name} {p:g}", "pitch": float(np.radians(p)), "speed": speed}
        for name, speed in (("rest", 0.0), ("cruising", level))
        for p in pitches
    ]
    st = start_states(parse_task({**task.to_dict(), "starts": starts}, task.source), body)
    n3 = int(round(3.0 / body.dt))
    for label, tab in gaits.items():
        tables = np.repeat(tab[None, :n3], len(starts), axis=0)
        tr = simulate(body, tables, state=st, record_every=n3)
        d = tr.com(body)[:, -1] - tr.com(body)[:, 0]
        rows = (
            f"{s['name']} deg: rise {r[1]:+.3f} path {np.linalg.norm(r):.3f}"
            for s, r in zip(starts, d, strict=True)
        )
        print(f"{label} (3 s, m): " + "; ".join(rows))


def pitch_damping(body, gait: np.ndarray, rates=(30.0, 60.0)) -> None:
    """Print how a nose-up pitch rate given at the first instant dies away while the ray flaps
    (from rest and cruising), the disc's moment of inertia about its pitch axis, and the
    moment a steady pitch rate of 30 deg/s would take (inertia over decay time)."""
    starts = start_states(load_task("swim-up"), body)
    n = int(round(1.0 / body.dt))
    for i, name in enumerate(("rest", "cruising")):
        p0 = starts.positions[i]
        r = p0 - body.mass @ p0 / body.total_mass
        inertia = float(body.mass @ (r[:, 0] ** 2 + r[:, 1] ** 2))
        spin = np.stack([-r[:, 1], r[:, 0], 0 * r[:, 0]], axis=1)
        vel = np.stack([starts.velocities[i] + np.radians(w) * spin for w in rates])
        pos = np.repeat(p0[None], len(rates), axis=0)
        tables = np.repeat(gait[None, :n], len(rates), axis=0)
        tr = simulate(body, tables, state=State(pos, vel), record_every=1)
        pitch = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))["pitch"]
        gained = pitch[:, -1] - pitch[:, 0]
        decay = float(np.mean(np.radians(gained) / np.radians(rates)))  # s: gained = rate * tau
        print(
            f"{name}: pitch gained after a kick of {rates} deg/s: {np.round(gained, 1)} deg; decay"
            f" time {decay:.3f} s; I = {inertia:.4f} kg m^2; a steady 30 deg/s takes about"
            f" {inertia * np.radians(30.0) / decay:.3f} N m"
        )


def add_fin_pair(doc: dict, nodes: Callable[[str], list[str]], area: float) -> dict:
    """Add to the ray document ``doc`` a left/right fin pair of ``area`` m² each, turning
    +-0.5 rad; ``nodes(side)`` names the lattice nodes a side's fin is attached to ("L"/"R")."""
    pair = (("L", "left", "right"), ("R", "right", "left"))
    doc["actuators"] += [
        {"name": f"fin_{side}", "kind": "fin", "side": side, "mirror": f"fin_{other}"}
        for _, side, other in pair
    ]
    doc["fins"] = [
        {
            "name": f"fin_{side}",
            "actuator": f"fin_{side}",
            "nodes": nodes(s),
            "forward": ["s0_TL", "s3_TL"],
            "span": ["s0_TL", "s0_TR"],
            "area": area,
            "angle_range": [-0.5, 0.5],
        }
        for s, side, _ in pair
    ]
    return doc


def finned(station: int, area: float):
    """Return the zoo ray with a fin pair (``area`` m² each) on the body box of ``station``."""
    doc = tomllib.loads((Path(bodies.__file__).parent / "zoo" / "ray.toml").read_text())
    add_fin_pair(doc, lambda s: [f"s{station}_T{s}", f"s{station}_B{s}"], area)
    path = Path(tempfile.mkdtemp()) / "ray_fins.toml"
    path.write_text(tomli_w.dumps(doc))
    return load_animal(path)


def with_fins(body, muscles: np.ndarray, label: str) -> None:
    """Print the rise (m) and pitch (deg) in 3 s of the flap with the fins held at 0 or 1."""
    starts = start_states(load_task("swim-up"), body)
    n3 = int(round(3.0 / body.dt))
    tables = np.zeros((2, n3, body.n_actuators))
    tables[:, :, :4] = muscles[:n3]
    tables[1, :, 4:] = 1.0
    for i, name in enumerate(("rest", "cruising")):
        pos = np.repeat(starts.positions[i : i + 1], 2, axis=0)
        vel = np.repeat(starts.velocities[i : i + 1], 2, axis=0)
        tr = simulate(body, tables, state=State(pos, vel), record_every=n3)
        rise = tr.com(body)[:, -1, 1] - tr.com(body)[:, 0, 1]
        pitch = motion_scalars(body, tr.positions, tr.times, get_medium(body.medium))["pitch"]
        print(
            f"fins at {label}, {name}: fins at 0: rise {rise[0]:+.3f} pitch {pitch[0, -1]:+.1f};"
            f" fins at 1: rise {rise[1]:+.3f} pitch {pitch[1, -1]:+.1f}"
        )


if __name__ == "__main__":
    main()
