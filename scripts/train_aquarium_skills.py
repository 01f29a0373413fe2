"""Train the learned motor skills the aquarium ships (src/zoetic/behavior/aquarium/skills/).

For each body (default: shark, the lattice both the minnow and the shark species swim with)
runs ``zoetic repertoire train BODY --seed SEED`` in a scratch directory (about 1.5 minutes
on 2 cores; the same seed gives the same repertoire) and copies its index and controller files,
not the training runs, into ``skills/BODY/``, where ``[motor] skills = "learned"`` in a species
file finds them. Run: python scripts/train_aquarium_skills.py [--bodies shark] [--seed 0]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from zoetic.behavior.aquarium.species import SKILLS_DIR
from zoetic.io import atomic_write_bytes, read_json


def train(body: str, seed: int, budget: int | None) -> Path:
    """Train ``body``'s repertoire and install it in ``SKILLS_DIR / body``; return that."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / body
        cmd = [sys.executable, "-m", "zoetic", "repertoire", "train", body, "--out", str(out),
               "--seed", str(seed)]  # fmt: skip
        if budget is not None:
            cmd += ["--budget", str(budget)]
        subprocess.run(cmd, check=True)
        index = read_json(out / "repertoire.json", what="repertoire index")
        files = ["repertoire.json", *(e["file"] for e in index["entries"])]
        dest = SKILLS_DIR / body
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
    args = ap.parse_args()
    for body in args.bodies:
        dest = train(body, args.seed, args.budget)
        size = sum(p.stat().st_size for p in dest.iterdir())
        print(f"{body}: {dest} ({size / 1024:.1f} KiB)")


if __name__ == "__main__":
    main()
