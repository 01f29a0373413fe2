"""The dolphin's heading stability with and without a dorsal fin (docs/animals.md, "The dorsal
fin (tried, not kept)").

Builds the zoo dolphin and the same body with ``scripts/make_zoo.py``'s ``DORSAL_FIN``, learns
move-forward on each with the defaults of ``zoetic learn`` (seed 0), and prints one JSON line
per body: the hand-made wave from each of move-forward's starts (rest, cruising) with a yaw push
(0.1 rad/s about the vertical) and without, and the learned gait without: heading change after
4 s and 10 s and the speed sustained over the second half of 10 s (``bench.skills``); and the
learned gait's burst toward the surface with the flippers up (``bench.skills.burst``).

    python experiments/dolphin_yaw.py            # about 3 minutes on a shared 2-core machine
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import tomli_w

from zoetic.behavior.handmade import handmade_repertoire
from zoetic.behavior.tracking import body_length
from zoetic.bench.skills import burst, learn_skill, sustained_speed
from zoetic.bodies import Body, load_animal
from zoetic.control import Controller
from zoetic.learning.objective import heading_angles
from zoetic.physics import State, simulate
from zoetic.tasks import load_task, start_state

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
import make_zoo  # noqa: E402


def build(**changes) -> Path:
    """Write the zoo dolphin with ``changes`` (make_zoo.dolphin's parameters) to a temporary
    file and return its path."""
    with contextlib.redirect_stdout(io.StringIO()):
        doc = make_zoo.dolphin(**changes)
    path = Path(tempfile.mkdtemp()) / "dolphin.toml"
    path.write_text(tomli_w.dumps(doc))
    return path


def pushed(state: State, body: Body, yaw_rate: float) -> State:
    """Return ``state`` with a yaw rate (rad/s about the vertical through the centre of mass)."""
    w = body.mass / body.total_mass
    pos, vel = state.positions.copy(), state.velocities.copy()
    r = pos[0] - w @ pos[0]
    vel[0] += np.cross(np.array([0.0, yaw_rate, 0.0]), r)
    return State(pos, vel)


def heading_and_roll(body: Body, ctrl: Controller, state: State, seconds: float) -> tuple:
    """Return the heading change (degrees, left positive) after ``seconds`` from ``state``, and
    the largest roll (degrees: the tilt of ring 2's top-to-bottom axis out of the vertical
    plane through the body axis) over them."""
    steps = int(round(seconds / body.dt))
    tr = simulate(body, ctrl.table(steps, body.dt), state=state,
                  record_every=max(1, int(round(0.05 / body.dt))))  # fmt: skip
    h = heading_angles(body, tr.positions)[0]
    names = list(body.node_names)
    top = [names.index(n) for n in ("r2_0", "r2_3")]
    bottom = [names.index(n) for n in ("r2_1", "r2_2")]
    p = tr.positions[0]
    up = p[:, top].mean(axis=1) - p[:, bottom].mean(axis=1)
    fwd = p[:, body.head] - p[:, bottom + top].mean(axis=1)
    side = np.cross(fwd, [0.0, 1.0, 0.0])  # horizontal, across the body
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    tilt = np.arcsin(np.clip(np.abs(np.sum(up * side, axis=1)) / np.linalg.norm(up, axis=1), 0, 1))
    return round(float(np.degrees(h[-1] - h[0])), 1), round(float(np.degrees(tilt.max())), 1)


def figures(body: Body, ctrl: Controller, push: float | None) -> dict:
    task = load_task("move-forward")
    out: dict = {}
    for k, name in enumerate(task.start_names()):
        st = start_state(task, body, index=k)
        if push:
            st = pushed(st, body, push)
        h4, roll4 = heading_and_roll(body, ctrl, st, 4.0)
        out[name] = {
            "heading_4s_deg": h4,
            "max_roll_4s_deg": roll4,
            "heading_10s_deg": heading_and_roll(body, ctrl, st, 10.0)[0],
            "sustained_bl_s": sustained_speed(body, ctrl, state=st),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--push", type=float, default=0.1, help="yaw rate of the wave's push")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    task = load_task("move-forward")
    bodies = (("dolphin", {}), ("dolphin+dorsal_fin", {"dorsal": make_zoo.DORSAL_FIN}))
    for label, changes in bodies:
        path = build(**changes)
        body = load_animal(path)
        wave = handmade_repertoire(body).controllers["go-straight"]
        learned, wall = learn_skill(str(path), task, args.seed)
        row: dict = {"body": label, "nodes": body.n_nodes,
                     "mass_kg": round(float(body.total_mass), 2),
                     "length_m": round(body_length(body), 3)}  # fmt: skip
        row["wave_pushed"] = figures(body, wave, args.push)
        row["wave"] = figures(body, wave, None)
        row["learned"] = figures(body, learned, None)
        row["learned_burst"] = burst(body, learned)
        row["learn_wall_s"] = round(wall, 1)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
