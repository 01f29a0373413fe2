"""Is our integrator as stable as the papers' at the step we use? A measurement.

The papers integrate with semi-implicit Euler, implicit in the internal forces. zoetic's
kernel is symplectic Euler with the nodal damping implicit and the friction and water forces
capped (see physics/kernel.py). For each animal this runs both schemes (the implicit one in
physics/reference.py) for 5 s of the animal's wave plus random perturbations at a ladder of
steps, and reports the largest step at which each stays finite with every spring within 50-150%
of its relaxed length, and how far each is at the animal's own dt from a fine-step solution.

Run: python experiments/integrator_stability.py  (a minute or two)
"""

from __future__ import annotations

import json

import numpy as np

from zoetic.bodies import list_animals, load_animal
from zoetic.control import wave_controller
from zoetic.physics import get_medium, rest_state, simulate
from zoetic.physics.reference import step_semi_implicit
from zoetic.physics.simulate import stable_dt
from zoetic.reproduce import figures_dir

OUT = figures_dir() / "integrator_stability.json"
STEPS = (0.0025, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.04)
SECONDS = 5.0


def sane(body, x) -> bool:
    """Return True if positions are finite and every spring is within 50-150% of relaxed."""
    if not np.all(np.isfinite(x)):
        return False
    length = np.linalg.norm(x[..., body.spring_b, :] - x[..., body.spring_a, :], axis=-1)
    r = length / body.relaxed
    return bool(r.min() > 0.5 and r.max() < 1.5)


def run_kernel(body, dt):
    steps = int(round(SECONDS / dt))
    act = wave_controller(body).table(steps, dt)  # beyond the stable step on purpose: no check
    tr = simulate(body, act, dt=dt, record_every=steps, check_step=False)
    return tr.final.positions[0], (not tr.failed[0]) and sane(body, tr.final.positions)


def run_implicit(body, dt):
    steps = int(round(SECONDS / dt))
    act = wave_controller(body).table(steps, dt)
    med = get_medium(body.medium)
    st = rest_state(body, 1)
    x, v = st.positions, st.velocities
    for t in range(steps):
        x, v = step_semi_implicit(body, x, v, act[None, t], med, dt)
        if not np.all(np.isfinite(x)) or np.abs(v).max() > 200:
            return x[0], False
    return x[0], sane(body, x)


def main() -> None:
    report = {}
    for name in list_animals():
        body = load_animal(name)
        fine, _ = run_kernel(body, 0.0005)
        row = {"own_dt": body.dt, "predicted_limit": round(stable_dt(body), 5)}
        for label, fn in (("kernel", run_kernel), ("semi_implicit", run_implicit)):
            stable = [dt for dt in STEPS if fn(body, dt)[1]]
            row[f"{label}_stable_steps"] = stable
            x, ok = fn(body, body.dt)
            row[f"{label}_error_at_own_dt_m"] = round(float(np.abs(x - fine).max()), 4)
        report[name] = row
        print(name, row, flush=True)
    OUT.write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
