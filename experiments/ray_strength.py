"""How fast does the ray's hand-made flap swim, and does it keep its shape? A measurement.

Builds variants of the zoo ray with ``scripts/make_zoo.py``'s ``ray(**changes)`` and reports,
for each, the best sustained speed of the flap (elevators and depressors half a cycle apart,
body lengths per second over 4-8 s) over a sweep of frequencies, the 10 % rule's strain (any
one actuator fully on for 3 s), the lattice's highest frequency and the stable step. These are
the rows of docs/animals.md, "Strength of the ray".

Run: python experiments/ray_strength.py  (about a minute)
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))

import make_zoo  # noqa: E402

from zoetic.bodies import load_animal  # noqa: E402
from zoetic.physics import multirate, simulate  # noqa: E402
from zoetic.physics.simulate import stable_dt  # noqa: E402

FIRST = {"k_m": 220.0, "k_thick": None, "rear_groups": ("root", "thick", "wing"),
         "node_damping": 0.02}  # fmt: skip
VARIANTS = {
    "first ray": FIRST,
    "nodal damping 0.005": {**FIRST, "node_damping": 0.005},
    "... and muscles 800": {**FIRST, "node_damping": 0.005, "k_m": 800.0},
    "muscles 800, rear softening on the wing sheet only": {"k_thick": None},
    "the ray now": {},
    "muscles 1000, thickness 600": {"k_m": 1000.0, "k_thick": 600.0},
    "first ray 4x stiffer, nodal damping 0.005, 2.5 ms": {
        **FIRST,
        "node_damping": 0.005,
        "k_s": 1000.0,
        "k_m": 880.0,
        "dt": 0.0025,
    },
    "40 % of the mass in the wings": {"wing_mass": 0.4},
}
FREQS = (1.5, 2.0, 2.5, 3.0, 4.0)


def build(changes: dict):
    """Return the compiled Body of the zoo ray with ``changes``."""
    with contextlib.redirect_stdout(io.StringIO()):
        doc = make_zoo.ray(**changes)
    path = Path(tempfile.mkdtemp()) / "ray.toml"
    path.write_text(tomli_w.dumps(doc))
    return load_animal(path)


def flap_speed(body, freqs=FREQS, seconds: float = 8.0) -> dict[float, float]:
    """Return {frequency: body lengths per second over the second half} of the flap."""
    steps = int(round(seconds / body.dt))
    t = np.arange(steps) * body.dt
    lag = {"elevator": 0.0, "depressor": 0.5}
    tables = np.stack([
        np.stack([0.5 * (1 + np.sin(2 * np.pi * (f * t - lag[n.split("_")[0]])))
                  for n in body.actuator_names], axis=1)
        for f in freqs])  # fmt: skip
    tr = simulate(body, tables, record_every=max(1, steps // 40), check_step=False)
    com = tr.com(body)
    half = com.shape[1] // 2
    length = float(np.ptp(body.rest_pos[:, 0]))
    d = np.linalg.norm((com[:, -1] - com[:, half])[:, [0, 2]], axis=1)
    v = d / (tr.times[-1] - tr.times[half]) / length
    return {f: round(float(s), 3) for f, s in zip(freqs, v, strict=True)}


def shape_strain(body) -> float:
    """Return the largest passive strain with any one actuator fully on for 3 s."""
    steps = int(3.0 / body.dt)
    a = body.n_actuators
    acts = np.zeros((a, steps, a))
    for k in range(a):
        acts[k, :, k] = 1.0
    tr = simulate(body, acts, record_every=10, check_step=False)
    p = tr.positions
    length = np.linalg.norm(p[..., body.spring_b, :] - p[..., body.spring_a, :], axis=-1)
    passive = body.spring_actuator < 0
    return round(float(np.abs(length[..., passive] / body.relaxed[passive] - 1).max()), 3)


def main() -> None:
    for label, changes in VARIANTS.items():
        body = build(changes)
        speeds = flap_speed(body)
        best = max(speeds, key=speeds.get)
        row = {
            "best_hz": best,
            "bl_s": speeds[best],
            "shape_strain": shape_strain(body),
            "omega_max": round(multirate.omega_max(body), 1),
            "stable_dt_ms": round(1000 * stable_dt(body), 2),
            "dt_ms": 1000 * body.dt,
        }
        print(json.dumps({label: row}), flush=True)


if __name__ == "__main__":
    main()
