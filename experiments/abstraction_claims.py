"""Check the muscle paper's claims about abstracted controllers (section 3, Fig. 9).

Learns (CMA-ES) a straight and a sharp-turn controller for the shark and the snake, then:
- abstracts each keeping the K = 1, 2, 3 strongest modes per actuator (and "auto") and says
  what fraction of the original's forward distance (or heading change) each keeps: the paper
  says one mode suffices for the shark, two for the snake;
- measures the phase between left and right actuators of the learned straight shark (the
  paper: roughly antiphase) from their dominant modes, and the correlation of the signals;
- summarises the learned shark turn per muscle pair, side by side (the paper, Fig. 9b: the
  right side's anterior and posterior muscles are "essentially unused", the left side's move
  approximately in phase);
- follows the learned snake turn's body bend (signed angle between the front and back halves)
  over time: the paper says a turn first coils toward the turn, then returns to serpentine.
``--animals shark-1995`` runs the fish's cases on the 1995 paper's shark (its references'
constants, docs/animals.md "The papers' animals"); a fish (water) gets the shark's cases, a
crawler (ground) the snake's. Writes docs/figures/abstraction_*.png and abstraction.json (the
default animals) or abstraction_NAMES.json, and prints a Markdown table. About 5 minutes on 2
cores:
    python experiments/abstraction_claims.py [--budget 6000] [--out /tmp/claims]
        [--animals shark,snake]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from zoetic.bodies import load_animal
from zoetic.learning.abstraction import abstract, compare, spectrum
from zoetic.learning.run import LearnConfig, Run
from zoetic.physics import get_medium, rest_state, simulate
from zoetic.reproduce import figures_dir
from zoetic.tasks import load_task
from zoetic.viz.media import abstract_files

FIGS = figures_dir()
CASES = {  # the animal's medium: (task, nodes) of its cases
    "water": (("swim-straight", 40), ("sharp-turn-left", 30)),
    "ground": (("crawl-straight", 15), ("sharp-turn-left", 15)),
}
DEFAULT_ANIMALS = "shark,snake"


def cases(animals: list[str]) -> list[tuple[str, str, int]]:
    """Return (animal, task, nodes) of the animals' cases, a fish's and a crawler's by medium."""
    out = []
    for animal in animals:
        medium = load_animal(animal).medium
        if medium not in CASES:
            raise SystemExit(f"--animals: {animal} lives in {medium!r}; only water and ground")
        out += [(animal, task, nodes) for task, nodes in CASES[medium]]
    return out


def learn(animal: str, task: str, nodes: int, budget: int, out: Path, seed: int):
    """Return the best controller of a CMA-ES run (resumed if it is already there)."""
    run_dir = out / f"{animal}-{task}"
    if (run_dir / "config.toml").exists():
        run = Run.resume(run_dir)
    else:
        cfg = LearnConfig(animal=animal, task=task, optimizer="cmaes", budget=budget, seed=seed,
                          nodes=nodes, popsize=24, controller="time")  # fmt: skip
        run = Run.create(run_dir, cfg)
    run.learn()
    return run_dir, run.best_controller()


def antiphase(body, ctrl) -> list[dict]:
    """Return, per left/right pair, the phase gap of their dominant modes and the correlation."""
    spec = spectrum(ctrl)
    t = np.linspace(0, ctrl.duration, 800)
    u = ctrl.raw(t)
    rows = []
    for i, name in enumerate(body.actuator_names):
        j = int(body.actuator_mirror[i])
        if body.actuator_side[i] != "left" or j == i:
            continue
        k = int(np.argmax(spec.amp[i]))
        gap = (spec.phase[j, k] - spec.phase[i, k] + np.pi) % (2 * np.pi) - np.pi
        corr = float(np.corrcoef(u[:, i], u[:, j])[0, 1])
        rows.append({"pair": f"{name}/{body.actuator_names[j]}", "hz": float(spec.freq[i, k]),
                     "phase_gap_deg": round(float(np.degrees(abs(gap))), 1),
                     "correlation": round(corr, 3)})  # fmt: skip
    return rows


def turn_sides(body, ctrl) -> dict:
    """Return the learned turn's activity per muscle (the standard deviation of its signal over
    the turn, 0-1 activation) paired left/right by segment, the right side's activity as a
    fraction of the left's, and the left side's spread of dominant-mode phases (deg): the
    paper's "right side unused, left side in phase" is a small fraction and a small spread."""
    spec = spectrum(ctrl)
    u = ctrl.sample(np.linspace(0, ctrl.duration, 800))
    rows, left_phase = [], []
    for i, name in enumerate(body.actuator_names):
        j = int(body.actuator_mirror[i])
        if body.actuator_side[i] != "left" or j == i or "fin" in name:
            continue  # muscles only: the paper's shark has no fins
        k = int(np.argmax(spec.amp[i]))
        left_phase.append(float(spec.phase[i, k]))
        rows.append({"pair": f"{name}/{body.actuator_names[j]}",
                     "left_activity": round(float(u[:, i].std()), 3),
                     "right_activity": round(float(u[:, j].std()), 3),
                     "left_mean": round(float(u[:, i].mean()), 3),
                     "right_mean": round(float(u[:, j].mean()), 3)})  # fmt: skip
    ph = np.asarray(left_phase)
    gaps = (ph[:, None] - ph[None, :] + np.pi) % (2 * np.pi) - np.pi
    left = sum(r["left_activity"] for r in rows)
    right = sum(r["right_activity"] for r in rows)
    return {"pairs": rows, "right_over_left_activity": round(right / max(left, 1e-9), 3),
            "left_phase_spread_deg": round(float(np.degrees(np.abs(gaps).max())), 1)}  # fmt: skip


def snake_bend(body, ctrl, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """Return times (R,) and the signed bend (R,) rad of the snake: + is coiled to the left."""
    dt = body.dt
    steps = int(round(seconds / dt))
    every = int(round(0.02 / dt))
    traj = simulate(body, ctrl.table(steps, dt)[None], get_medium(body.medium), dt,
                    rest_state(body, 1), every)  # fmt: skip
    pos = traj.positions[0][:, :, [0, 2]]  # (R, N, 2)
    rings = np.stack([pos[:, 1 + 4 * r : 5 + 4 * r].mean(axis=1) for r in range(11)], axis=1)
    front = rings[:, 0] - rings[:, 5]
    back = rings[:, 5] - rings[:, 10]
    a = np.arctan2(front[:, 1], front[:, 0]) - np.arctan2(back[:, 1], back[:, 0])
    return traj.times, (a + np.pi) % (2 * np.pi) - np.pi


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--budget", type=int, default=6000)
    ap.add_argument("--out", type=Path, default=Path("/tmp/zoetic-claims"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--animals", default=DEFAULT_ANIMALS, help="comma-separated zoo animals")
    args = ap.parse_args()
    animals = [a.strip() for a in args.animals.split(",") if a.strip()]
    results = {}
    print("| animal | task | original | K=1 | K=2 | K=3 | auto (modes) |")
    print("|---|---|---|---|---|---|---|")
    for k, (animal, task_name, nodes) in enumerate(cases(animals)):
        body = load_animal(animal)
        task = load_task(task_name)
        run_dir, ctrl = learn(animal, task_name, nodes, args.budget, args.out, args.seed + k)
        cells, keep = [], {}
        for modes in (1, 2, 3, "auto"):
            ab = abstract(ctrl, modes)
            cmp = compare(body, ctrl, ab.controller, task)
            keep[str(modes)] = {"kept": round(cmp.kept, 3),
                                "modes": ab.modes_per_actuator().tolist()}  # fmt: skip
            cells.append(f"{cmp.kept:.0%}")
        m = cmp.measure
        orig = cmp.original[m]
        unit = f"{orig:.3f} m" if m == "forward" else f"{np.degrees(orig):.0f} deg"
        auto_modes = np.mean(keep["auto"]["modes"])
        print(f"| {animal} | {task_name} | {unit} | {cells[0]} | {cells[1]} | {cells[2]} | "
              f"{cells[3]} ({auto_modes:.1f}) |")  # fmt: skip
        results[f"{animal}/{task_name}"] = {"measure": m, "original": orig, **keep}
        abstract_files(run_dir, FIGS / f"abstraction_{animal}_{task_name}", modes=2)
        fish, crawler = body.medium == "water", body.medium == "ground"
        if fish and task_name == "swim-straight":
            results[f"{animal}_antiphase"] = antiphase(body, ctrl)
        if fish and "turn" in task_name:
            results[f"{animal}_turn_sides"] = turn_sides(body, ctrl)
        if crawler and "turn" in task_name:
            t, bend = snake_bend(body, ctrl, task.horizon)
            thirds = np.array_split(np.degrees(bend), 3)
            results[f"{animal}_turn_bend_deg"] = {
                "mean_by_third": [round(float(b.mean()), 1) for b in thirds],
                "max": round(float(np.degrees(bend.max())), 1),
                "t_of_max": round(float(t[np.argmax(bend)]), 2),
            }
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            fig, ax = plt.subplots(figsize=(6, 3))
            ax.plot(t, np.degrees(bend))
            ax.axhline(0, color="k", lw=0.5)
            ax.set_xlabel("time (s)")
            ax.set_ylabel("body bend (deg, + = left)")
            ax.set_title("learned snake turn: body bend over time")
            fig.tight_layout()
            fig.savefig(FIGS / f"abstraction_{animal}_turn_bend.png", dpi=110)
    print(json.dumps({k: v for k, v in results.items() if "/" not in k}, indent=1))
    text = json.dumps(results, indent=1, default=float)
    tag = "" if args.animals == DEFAULT_ANIMALS else "_" + "_".join(animals)
    (args.out / f"claims{tag}.json").write_text(text)
    (FIGS / f"abstraction{tag}.json").write_text(text + "\n")


if __name__ == "__main__":
    main()
