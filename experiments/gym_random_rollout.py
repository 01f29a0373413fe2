"""A random policy in a zoetic Gymnasium environment: one episode, a few frames saved.

    .venv/bin/python experiments/gym_random_rollout.py [ENV_ID] [--frames DIR]

Trains nothing: it shows the reset/step loop, the observation and reward, and rendering.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium
import numpy as np

import zoetic.gym  # noqa: F401  (registers zoetic/SharkSwim-v0 and friends)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("env_id", nargs="?", default="zoetic/SharkSwim-v0")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--frames", type=Path, default=None, help="write every 20th frame here")
    args = parser.parse_args()

    env = gymnasium.make(args.env_id, render_mode="rgb_array")
    env.action_space.seed(args.seed)
    obs, _ = env.reset(seed=args.seed)
    total, steps, done = 0.0, 0, False
    while not done:
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        total += reward
        steps += 1
        done = terminated or truncated
        if args.frames is not None and steps % 20 == 0:
            import imageio.v3 as iio

            args.frames.mkdir(parents=True, exist_ok=True)
            iio.imwrite(args.frames / f"frame_{steps:04d}.png", env.render())
    print(f"{args.env_id}: {steps} steps, return {total:.3f}, last observation")
    print(np.array2string(obs, precision=3, suppress_small=True))


if __name__ == "__main__":
    main()
