"""Throughput of the JAX backend on whatever device JAX sees: python bench/jax_sim.py."""

from __future__ import annotations

import argparse
import json


def main() -> None:
    """Print the JAX benchmark (simulated seconds per second, compile time apart) as JSON."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--animal", default="shark")
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--numba", action="store_true", help="also run the Numba kernel's bench")
    args = ap.parse_args()
    from zoetic.physics.jax_bench import benchmark

    out = {"jax": benchmark(args.animal, args.seconds, args.batch, args.repeats)}
    if args.numba:
        from zoetic.physics.bench import bench_simulate

        out["numba"] = bench_simulate(args.animal, args.seconds, args.batch, args.repeats)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
