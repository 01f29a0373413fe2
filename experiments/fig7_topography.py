"""Fig. 7 of Grzeszczuk & Terzopoulos 95: the topography of E over two parameters.

For each representation (time, frequency), E of the Fig. 6 shark task is evaluated on a grid
of two randomly chosen parameters, the others held at a random controller's values. The
roughness figure is the number of strict local minima on the grid (8-neighbourhood) and the
mean absolute second difference relative to the range of E. Writes docs/figures/fig7.png and
docs/figures/fig7.json.

Run: python experiments/fig7_topography.py [--grid 31] [--seed 0]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from zoetic.learning.run import LearnConfig, build
from zoetic.reproduce import figures_dir

OUT = figures_dir()


def local_minima(z: np.ndarray) -> int:
    """Return the number of interior grid points lower than all 8 neighbours."""
    c = z[1:-1, 1:-1]
    lower = np.ones_like(c, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                lower &= c < z[1 + di : z.shape[0] - 1 + di, 1 + dj : z.shape[1] - 1 + dj]
    return int(lower.sum())


def surface(controller: str, grid: int, seed: int):
    """Return (a, b, E grid, chosen parameter indices) for one representation."""
    setup = build(LearnConfig(animal="shark", task="reach-goal", nodes=15, seed=seed,
                              coupling="antiphase", controller=controller))  # fmt: skip
    obj = setup.objective
    lo, hi = obj.bounds()
    rng = np.random.default_rng(seed + 7)
    i, j = rng.choice(obj.dimension, size=2, replace=False)
    x = setup.optimizer.x0.copy()
    a = np.linspace(lo[i], hi[i], grid)
    b = np.linspace(lo[j], hi[j], grid)
    X = np.tile(x, (grid * grid, 1))
    A, B = np.meshgrid(a, b, indexing="ij")
    X[:, i], X[:, j] = A.ravel(), B.ravel()
    return a, b, obj(X).reshape(grid, grid), (int(i), int(j))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--grid", type=int, default=31)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=(10, 4.2))
    report = {}
    for k, controller in enumerate(("time", "frequency")):
        a, b, z, (i, j) = surface(controller, args.grid, args.seed)
        rough = float(
            np.mean(np.abs(np.diff(z, 2, axis=0))) + np.mean(np.abs(np.diff(z, 2, axis=1)))
        )
        report[controller] = {
            "parameters": [i, j],
            "local_minima": local_minima(z),
            "E_range": [round(float(z.min()), 4), round(float(z.max()), 4)],
            "roughness": round(rough / float(np.ptp(z) + 1e-12), 4),
        }
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        A, B = np.meshgrid(a, b, indexing="ij")
        ax.plot_surface(A, B, z, cmap="viridis", linewidth=0)
        ax.set_title(f"{controller} domain: {report[controller]['local_minima']} local minima")
        ax.set_xlabel(f"x = u[{i}]")
        ax.set_ylabel(f"y = u[{j}]")
        ax.set_zlabel("E")
        print(controller, report[controller], flush=True)
    fig.tight_layout()
    fig.savefig(OUT / "fig7.png", dpi=100)
    (OUT / "fig7.json").write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
