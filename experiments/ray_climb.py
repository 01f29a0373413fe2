"""How far can the ray rise or sink in 3 s? A measurement (swim-up and swim-down promise 0.5 m).

Plays hand-made flaps on the zoo ray from the swim-up task's two starts (rest and cruising):
the built-in 2 Hz flap with the wings held up or down (an offset between elevators and
depressors, which tilts the flap's thrust and so pitches the disc) and with a fast or slow
downstroke (a stroke asymmetry, which pushes more water one way). For each it prints the rise
of the centre of mass after 3 s and 6 s and the pitch reached: the disc pitches at about
5 degrees/s at most, so the ray's rise in 3 s stays under a tenth of a metre.

Run: python experiments/ray_climb.py  (about a minute)
"""

from __future__ import annotations

import numpy as np

from zoetic.bodies import load_animal
from zoetic.control.measure import motion_scalars
from zoetic.physics import State, get_medium, simulate
from zoetic.tasks import load_task, start_states

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


if __name__ == "__main__":
    main()
