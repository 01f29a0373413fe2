"""Train the learned motor skills the aquarium ships (src/zoetic/behavior/aquarium/skills/).

For each body (default: shark, the lattice both the minnow and the shark species swim with)
runs ``zoetic repertoire train BODY --seed SEED`` in a scratch directory (about 1.5 minutes
on 2 cores; the same seed gives the same repertoire), then learns the aquarium's extra entries
(``EXTRA``: the steering gait ``steer-left`` of the task of that name, abstracted like the
basic entries, and its mirror ``steer-right``; about a minute more) and copies the index and
controller files, not the training runs, into ``skills/BODY/``, where ``[motor] skills =
"learned"`` in a species file finds them. ``--extra-only`` learns only the extra entries and
adds them to the repertoire already there.
Run: python scripts/train_aquarium_skills.py [--bodies shark] [--seed 0] [--extra-only]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from zoetic.behavior.aquarium.species import SKILLS_DIR
from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.training import abstraction_report, mirrored_name
from zoetic.bodies import load_animal
from zoetic.control import Controller
from zoetic.control.abstract import AbstractController
from zoetic.io import atomic_write_bytes, read_json
from zoetic.learning.abstraction import abstract, mirror_abstract
from zoetic.learning.optimizers import make_optimizer
from zoetic.tasks import load_task

# (entry name, task, entry it starts from): what the aquarium's learned motor needs beyond
# the basic training. The steering gait is learned from the learned go-straight gait (a
# search from random gaits, budget 3500, found a gait thrashing on the spot: 117 degrees in
# 6 s at 0.01 m/s after abstraction, 2.5 degrees/s once swimming)
EXTRA = (("steer-left", "steer-left", "go-straight"),)
EXTRA_SEED = 100  # added to --seed for the extra entries (the basic ones use seed + k)
EXTRA_BUDGET = 3000  # evaluations
STEP_SIGMA = 0.1  # CMA-ES's first step, as a fraction of each parameter's range


def learn_from(
    body_name: str, task_name: str, start: AbstractController, seed: int, budget: int
) -> Controller:
    """Return the periodic controller CMA-ES learns for ``task_name`` starting from the gait
    ``start`` (its signals fitted by the task's periodic basis; steps ``STEP_SIGMA``)."""
    from zoetic.learning.run import CMAES_POPSIZE, LearnConfig, build

    setup = build(LearnConfig(animal=body_name, task=task_name, seed=seed, budget=budget))
    obj = setup.objective
    times = np.arange(obj.steps) * obj.dt
    basis = setup.template.design_matrix(times)  # (T, M)
    coef = np.linalg.lstsq(basis, start.raw(times), rcond=None)[0].T  # (A, M)
    lo, hi = obj.bounds()
    x0 = np.clip(obj.free_params(coef.ravel()), lo, hi)
    opt = make_optimizer("cmaes", x0, lo, hi, seed, budget, popsize=CMAES_POPSIZE, sigma=STEP_SIGMA)
    while opt.evaluations < budget and not opt.done():
        x = opt.ask()
        if len(x) == 0:
            break
        opt.tell(x, obj(x))
    return obj.controller(opt.best_x[None])


def learn_extra(body_name: str, out: Path, seed: int, budget: int | None) -> None:
    """Learn the ``EXTRA`` entries (and their mirrors) into the repertoire in ``out``."""
    body = load_animal(body_name)
    rep = Repertoire.load(out, body)
    for k, (name, task_name, base) in enumerate(EXTRA):
        task = load_task(task_name)
        original = learn_from(
            body_name,
            task_name,
            rep.controllers[base],
            seed + EXTRA_SEED + k,
            budget or EXTRA_BUDGET,
        )
        ab = abstract(original)
        rep.add(
            name,
            ab.controller,
            task.horizon,
            source=f"learned from {base}",
            **abstraction_report(body, original, ab, task),
        )
        right = mirrored_name(name)
        if right:
            rep.add(
                right,
                mirror_abstract(ab.controller, body.actuator_mirror),
                task.horizon,
                source=f"mirror of {name}",
            )
    rep.save(out)


def train(body: str, seed: int, budget: int | None, extra_only: bool = False) -> Path:
    """Train ``body``'s repertoire and install it in ``SKILLS_DIR / body``; return that."""
    dest = SKILLS_DIR / body
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / body
        if extra_only:
            out.mkdir(parents=True)
            for f in dest.glob("*.json"):
                (out / f.name).write_bytes(f.read_bytes())
        else:
            cmd = [
                sys.executable,
                "-m",
                "zoetic",
                "repertoire",
                "train",
                body,
                "--out",
                str(out),
                "--seed",
                str(seed),
            ]
            if budget is not None:
                cmd += ["--budget", str(budget)]
            subprocess.run(cmd, check=True)
        learn_extra(body, out, seed, budget)
        index = read_json(out / "repertoire.json", what="repertoire index")
        files = ["repertoire.json", *(e["file"] for e in index["entries"])]
        dest.mkdir(parents=True, exist_ok=True)
        for stale in dest.glob("*.json"):
            if stale.name not in files:
                stale.unlink()
        for name in files:
            atomic_write_bytes(dest / name, (out / name).read_bytes())
    return dest


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bodies", nargs="+", default=["shark"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--budget", type=int, default=None, help="evaluations per learned entry")
    ap.add_argument(
        "--extra-only",
        action="store_true",
        help="learn only the extra entries into the shipped repertoire",
    )
    args = ap.parse_args()
    for body in args.bodies:
        dest = train(body, args.seed, args.budget, args.extra_only)
        size = sum(p.stat().st_size for p in dest.iterdir())
        print(f"{body}: {dest} ({size / 1024:.1f} KiB)")


if __name__ == "__main__":
    main()
