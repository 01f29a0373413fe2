"""Which body changes let the ray climb? Builds ray variants and measures what they change.

Each variant is the zoo ray (``scripts/make_zoo.py``'s ``ray``) with one more change than the
row before: stronger muscles that shorten further, a streamlined leading edge (a drag
coefficient on the nose fan's faces, as the dolphin's head has), and a pair of control
surfaces (fins of ``FIN_AREA`` m², turning +-0.5 rad) on the rear of the body or on the rear
of the wings. For each it prints the lattice's highest frequency and stable step, the 10 %
rule's strain (any one muscle actuator fully on for 3 s), the built-in flap's sustained speed
(BL/s over 4-8 s, 2 Hz), its distance in 3 s from rest, and the water's drag on the gliding ray at
0.5 m/s. It writes each variant to ``OUT/<name>.toml`` so that learning can be tried on it:

    zoetic learn OUT/fins_on_wing.toml --task swim-up --seed 3 --budget 3000 --out runs/up

(seed 3 and 3000 evaluations are what ``zoetic repertoire train`` gives swim-up). The
learned climbs are in docs/animals.md, "Strength of the ray".

Run: python experiments/ray_variants.py [OUT]  (about a minute; OUT defaults to a temp dir)
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
import tomli_w

sys.path.insert(0, str(Path(__file__).resolve().parent))

from ray_climb import add_fin_pair  # noqa: E402
from ray_strength import make_zoo, shape_strain  # noqa: E402

from zoetic.bodies import load_animal  # noqa: E402
from zoetic.physics import get_medium, law, multirate, simulate  # noqa: E402
from zoetic.physics.model import compile_model  # noqa: E402
from zoetic.physics.simulate import stable_dt  # noqa: E402

STRONG = {"k_m": 1000.0, "k_thick": 600.0}  # N/m: muscles and the wing's thickness springs
SHORTENING = 0.21  # the muscles' greatest shortening (the zoo ray's 0.2; 0.22 breaks the 10 % rule)
NOSE_DRAG = 0.12  # drag coefficient of the nose fan's faces (the dolphin's head's)
FIN_AREA = {"body": 0.03, "wing": 0.05}  # m² per fin
# where each side's fin sits: on the rear body station, or between the two rear stations'
# mid-wing nodes (where the wing twists as it flaps)
FIN_NODES = {
    "body": lambda s: [f"s3_T{s}", f"s3_B{s}"],
    "wing": lambda s: [f"s2_midT{s}", f"s2_midB{s}", f"s3_midT{s}", f"s3_midB{s}"],
}


def variant(strong: bool = False, nose: bool = False, fins: str | None = None) -> dict:
    """Return the animal document of the zoo ray with the chosen changes."""
    with contextlib.redirect_stdout(io.StringIO()):
        doc = make_zoo.ray(**(STRONG if strong else {}))
    for s in doc["springs"]:
        if strong and s["kind"] == "muscle":
            s["max_shortening"] = SHORTENING
    for f in doc["faces"]:
        if nose and "nose" in f["nodes"]:
            f["drag"] = NOSE_DRAG
    if fins:
        add_fin_pair(doc, FIN_NODES[fins], FIN_AREA[fins])
    return doc


VARIANTS = {
    "zoo": {},
    "strong": {"strong": True},
    "streamlined": {"strong": True, "nose": True},
    "fins_on_body": {"strong": True, "nose": True, "fins": "body"},
    "fins_on_wing": {"strong": True, "nose": True, "fins": "wing"},
}


def glide_drag(body, speed: float = 0.5) -> float:
    """Return the water's drag (N) on the ray at rest shape gliding nose first at ``speed``."""
    model = compile_model(body, get_medium("water"), body.dt, np.float64)
    x = body.rest_pos.T[:, :, None]
    v = np.zeros_like(x)
    v[0] = speed
    return float(-law.water(np, model, x, v)[0].sum())


def flap(body, seconds: float = 8.0) -> tuple[float, float]:
    """Return the 2 Hz flap's distance (m) in its first 3 s from rest and its sustained speed
    (body lengths/s over 4-8 s), fins held level."""
    steps = int(round(seconds / body.dt))
    t = np.arange(steps) * body.dt
    lag = {"elevator": 0.0, "depressor": 0.5}
    cols = [
        0.5 * (1 + np.sin(2 * np.pi * (2.0 * t - lag[n.split("_")[0]])))
        if n.split("_")[0] in lag
        else np.full(steps, 0.5)
        for n in body.actuator_names
    ]
    every = int(round(0.5 / body.dt))
    tr = simulate(body, np.stack(cols, axis=1)[None], record_every=every)
    com = tr.com(body)[0]
    k3, k4 = (int(np.searchsorted(tr.times, s - 1e-9)) for s in (3.0, 4.0))
    length = float(np.ptp(body.rest_pos[:, 0]))
    v = np.linalg.norm((com[-1] - com[k4])[[0, 2]]) / (tr.times[-1] - tr.times[k4]) / length
    return float(np.linalg.norm(com[k3] - com[0])), float(v)


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
    out.mkdir(parents=True, exist_ok=True)
    for name, changes in VARIANTS.items():
        path = out / f"{name}.toml"
        path.write_text(tomli_w.dumps(variant(**changes)))
        body = load_animal(path)
        dash, speed = flap(body)
        row = {
            "omega_max": round(multirate.omega_max(body), 1),
            "stable_dt_ms": round(1000 * stable_dt(body), 2),
            "shape_strain": shape_strain(body),
            "flap_bl_s": round(speed, 3),
            "dash_3s_m": round(dash, 3),
            "glide_drag_N": round(glide_drag(body), 3),
        }
        print(json.dumps({name: row}), flush=True)
    print(f"variants written to {out}")


if __name__ == "__main__":
    main()
