"""Fig. 8 of Grzeszczuk & Terzopoulos 95: how E_u shapes the learned controller.

The Fig. 6 shark task (goal reaching, time domain, M = 15, antiphase pairs) learned with
mu1 = 1 and (a) nu2 = 0, nu1 in {0, 0.1, 0.2}; (b) nu1 = 0, nu2 in {0, 0.002, 0.006}.
For each learned controller: its mean amplitude (half the peak-to-peak of u per actuator)
its dominant frequency (the strongest non-constant FFT mode of the nodal values), and the work
its muscles spend over the horizon (``control.measure.muscle_work``, every step recorded): the
paper's "less energy expenditure" as nu1 grows.
Writes docs/figures/fig8.png and docs/figures/fig8.json.

Run: python experiments/fig8_smoothness.py [--budget 3500] [--optimizer anneal]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from zoetic.control.measure import muscle_work
from zoetic.learning.run import LearnConfig, build
from zoetic.physics.simulate import simulate
from zoetic.reproduce import figures_dir
from zoetic.tasks import parse_task

OUT = figures_dir()


def learn(nu1: float, nu2: float, budget: int, optimizer: str, seed: int):
    """Return the learned controller's (times, u) and its summary numbers."""
    cfg = LearnConfig(animal="shark", task="reach-goal", nodes=15, coupling="antiphase",
                      optimizer=optimizer, budget=budget, seed=seed, popsize=16,
                      controller="time")  # fmt: skip
    from zoetic.tasks import load_task

    task = parse_task({**load_task("reach-goal").to_dict(), "mu1": 1.0, "nu1": nu1, "nu2": nu2})
    setup = build(cfg, task)
    opt, obj = setup.optimizer, setup.objective
    while opt.evaluations < budget and not opt.done():
        X = opt.ask()
        opt.tell(X, obj(X))
    if hasattr(opt, "close"):
        opt.close()
    ctrl = obj.controller(opt.best_x)
    u_nodes = ctrl.values  # (A, M)
    amp = float(np.mean((u_nodes.max(axis=1) - u_nodes.min(axis=1)) / 2))
    spec = np.abs(np.fft.rfft(u_nodes - u_nodes.mean(axis=1, keepdims=True), axis=1)).sum(axis=0)
    k = int(np.argmax(spec[1:]) + 1)
    freq = k / task.horizon
    t = np.linspace(0, task.horizon, 300)
    ev = obj.evaluate(opt.best_x[None])
    table = obj.tables(opt.best_x[None])
    traj = simulate(obj.body, table, obj.medium, obj.dt, obj.start, record_every=1)
    work = muscle_work(obj.body, traj.positions[:, 1:], table)[0]
    return (
        t,
        ctrl.sample(t),
        {
            "amplitude": round(amp, 3),
            "dominant_frequency_hz": round(freq, 3),
            "E_v": round(float(ev.E_v[0]), 4),
            "E_u": round(float(ev.E_u[0]), 4),
            "muscle_work_J": round(float(work), 1),
        },
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--budget", type=int, default=3500)
    ap.add_argument("--optimizer", default="anneal")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    OUT.mkdir(parents=True, exist_ok=True)
    settings = [("a", 0.0, 0.0), ("a", 0.1, 0.0), ("a", 0.2, 0.0),
                ("b", 0.0, 0.0), ("b", 0.0, 0.002), ("b", 0.0, 0.006)]  # fmt: skip
    fig, axes = plt.subplots(3, 2, figsize=(9, 6), sharex=True, sharey=True)
    report = {}
    for n, (panel, nu1, nu2) in enumerate(settings):
        t, u, summary = learn(nu1, nu2, args.budget, args.optimizer, args.seed)
        key = f"nu1={nu1} nu2={nu2}"
        report[key] = summary
        print(key, summary, flush=True)
        ax = axes[n % 3, 0 if panel == "a" else 1]
        ax.plot(t, u[:, 0], "k:", t, u[:, 1], "k-", lw=1)
        ax.set_title(f"({panel}) {key}: A {summary['amplitude']}, "
                     f"f {summary['dominant_frequency_hz']} Hz, "
                     f"work {summary['muscle_work_J']:.0f} J", fontsize=8)  # fmt: skip
    fig.tight_layout()
    fig.savefig(OUT / "fig8.png", dpi=100)
    (OUT / "fig8.json").write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
