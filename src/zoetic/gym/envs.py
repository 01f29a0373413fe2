"""Gymnasium environments over a zoetic World: one animal, B lanes of the batched kernel.

Every environment is a ``_Core`` of B lanes: the single ``ZoeticEnv`` is B = 1 and the native
``ZoeticVectorEnv`` is B = num_envs stepping all lanes in one kernel call, so both run the
same numbers. Each action is one control period of the one closed-loop driver
(``control.loop.step_period``).

Action: ``Box(0, 1, (A,), float32)``, the activation of each actuator (muscles contract toward
1, fins tilt), held for one control period (``control_period`` s, default 0.05).

Observation: ``Box(-inf, inf, (12 + A,), float32)``, read from the animal's sensors
(``control.sensors``; heading, pitch and roll of the body's forward and up axes):

====== =============================================================================
index  reading
====== =============================================================================
0-2    centre-of-mass velocity in the heading frame: forward, up, left (m/s)
3      pitch (rad, nose up positive)
4      roll (rad)
5      depth below the water surface (m; 0 without a surface)
6, 7   cos and sin of the bearing to the goal (goal tasks), of the heading error to the
       target heading (turn) or of the heading against the start heading (crawl)
8      distance to the goal (m, in 3-D; 0 for turn and crawl)
9      heading change since the start (rad, left positive)
10, 11 cos and sin of 2 pi f t: a clock at the animal's own wave frequency f
12-    the activations now held (the previous action)
====== =============================================================================

Rewards (per step) are the change of a task term (``tasks.terms``) over the step: ``swim`` the
decrease of ``goal_distance_xz`` (the top-view distance to the goal, m), +1 on reaching it
(within ``goal_radius``, which ends the episode); ``crawl`` the increase of ``position_along``
the start heading (m); ``turn`` the decrease of ``heading_error`` against a target heading
+-pi/2 from the start (rad), ending within 0.1 rad. A blown-up simulation ends the episode
with reward -1.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from zoetic.bodies import load_animal
from zoetic.control.loop import as_rows, step_period
from zoetic.control.policy import Period
from zoetic.control.sensors import observe, wrap_angle
from zoetic.physics.objects import Ball
from zoetic.physics.world import Animal, World
from zoetic.render import Cameras, look_rotation, render, world_mesh
from zoetic.tasks.signals import BodyFrame, Signals
from zoetic.tasks.terms import TERMS, TermParams

KINDS = ("swim", "crawl", "turn")
N_OBS = 12
SENSORS = ("velocity", "heading", "pitch", "roll", "depth")
GOAL_SENSORS = ("target_distance", "target_bearing")
# each task's reward: the term whose change over a step it is, and whether an increase pays
REWARDS = {
    "swim": ("goal_distance_xz", False),
    "crawl": ("position_along", True),
    "turn": ("heading_error", False),
}
WATER = (0.05, 0.25, 0.35)  # the colour of empty water in the pictures
ANIMAL = (0.55, 0.6, 0.68)


class _Core:
    """B lanes of one animal doing one task; lanes reset on their own."""

    def __init__(
        self,
        animal: str,
        kind: str,
        batch: int,
        control_period: float = 0.05,
        goal_distance: float = 3.0,
        goal_radius: float = 0.3,
    ) -> None:
        if kind not in KINDS:
            raise ValueError(f"task kind must be one of {KINDS}, got {kind!r}")
        self.body = load_animal(animal)
        self.kind = kind
        self.batch = batch
        self.period = float(control_period)
        self.goal_distance = float(goal_distance)
        self.goal_radius = float(goal_radius)
        self.world = World([Animal(self.body)], batch=batch)
        self.n_act = self.body.n_actuators
        self.frame = BodyFrame.of(self.body)
        self._start = self.world.initial_state()
        w = self.body.mass / self.body.total_mass
        self._com0 = w @ self._start.positions[0][0]
        self.goal = np.zeros((batch, 3))
        self.start_heading = np.zeros(batch)
        self.target_heading = np.zeros(batch)
        self.held = np.zeros((batch, self.n_act))
        self.steps = np.zeros(batch, dtype=np.int64)
        self.potential = np.zeros(batch)
        self.heading = np.zeros(batch)

    def observation_size(self) -> int:
        """Return the length of an observation (12 + A)."""
        return N_OBS + self.n_act

    def _place(self, lane: int, rng: np.random.Generator) -> None:
        """Put one lane back at the start turned to a random heading; draw its goal."""
        yaw = float(rng.uniform(-np.pi, np.pi))
        pose = self._start.take(0)
        com = self._com0
        c, s = np.cos(yaw), np.sin(yaw)
        rel = pose.positions[0][0] - com
        turned = np.stack(
            [c * rel[:, 0] - s * rel[:, 2], rel[:, 1], s * rel[:, 0] + c * rel[:, 2]], 1
        )
        self.world.restore(replace(pose, positions=(turned[None] + com,)), lanes=[lane])
        self.held[lane] = 0.0
        self.steps[lane] = 0
        if self.kind == "swim":
            bearing = yaw + float(rng.uniform(-np.pi / 4, np.pi / 4))
            self.goal[lane] = com + self.goal_distance * np.array(
                [np.cos(bearing), 0.0, np.sin(bearing)]
            )
        elif self.kind == "turn":
            self.goal[lane] = com
            self.target_heading[lane] = np.pi / 2 * (1.0 if rng.random() < 0.5 else -1.0)

    def reset_lanes(self, lanes: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Put each lane back at the start, with its own random heading and goal."""
        for lane, rng in zip(lanes, rngs, strict=True):
            self._place(lane, rng)
        head = self._sense()["heading"]
        self.start_heading[lanes] = head[lanes]
        self.heading[lanes] = head[lanes]
        if self.kind == "turn":
            self.target_heading[lanes] += head[lanes]
        self.potential[lanes] = self._potential()[lanes]

    def _sense(self) -> dict[str, np.ndarray]:
        """Return the sensors' readings the observation is made of (control.sensors)."""
        if self.kind == "swim":
            return observe(self.world, 0, SENSORS + GOAL_SENSORS, target=self.goal)
        return observe(self.world, 0, SENSORS)

    def _potential(self) -> np.ndarray:
        """Return the reward's term (REWARDS) of the world now, (B,)."""
        w = self.world
        s = Signals(
            np,
            self.frame,
            w.positions(0)[:, None],
            self.held[:, None],
            np.array([w.time]),
            w.medium.water_level,
            self.period,
        )
        target = self.start_heading if self.kind == "crawl" else self.target_heading
        return TERMS[REWARDS[self.kind][0]].fn(np, s, TermParams(target, self.goal))

    def observe(self, sensed: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """Return the observations (B, 12 + A) float32 (see the module's table)."""
        o = sensed or self._sense()
        head = self.heading
        c, sn = np.cos(head), np.sin(head)
        v = o["velocity"]
        fwd = c * v[:, 0] + sn * v[:, 2]
        left = -sn * v[:, 0] + c * v[:, 2]
        if self.kind == "swim":
            ang, dist = o["target_bearing"], o["target_distance"]
        elif self.kind == "turn":
            ang, dist = self.target_heading - head, np.zeros(self.batch)
        else:
            ang, dist = head - self.start_heading, np.zeros(self.batch)
        phase = 2 * np.pi * self.body.wave_frequency * self.steps * self.period
        obs = np.column_stack(
            [
                fwd,
                v[:, 1],
                left,
                o["pitch"],
                o["roll"],
                o["depth"],
                np.cos(ang),
                np.sin(ang),
                dist,
                wrap_angle(head - self.start_heading),
                np.cos(phase),
                np.sin(phase),
                self.held,
            ]
        )
        return obs.astype(np.float32)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Hold ``actions`` (B, A) for one period; return observations, rewards, terminated."""
        a = np.clip(np.asarray(actions, dtype=np.float64).reshape(self.batch, self.n_act), 0, 1)
        w = self.world
        period = Period(w.step_count, w.steps_for(self.period), w.dt)
        step_period(w, [as_rows(a, w, 0, period.steps)], period)
        self.held = a
        self.steps += 1
        sensed = self._sense()
        self.heading = self.heading + wrap_angle(sensed["heading"] - self.heading)  # unwrapped
        pot = self._potential()
        reward = pot - self.potential if REWARDS[self.kind][1] else self.potential - pot
        self.potential = pot
        terminated = np.zeros(self.batch, dtype=bool)
        if self.kind == "swim":
            reached = pot < self.goal_radius
            reward = reward + reached
            terminated |= reached
        elif self.kind == "turn":
            terminated |= pot < 0.1
        failed = w.failed(0) | ~np.isfinite(reward)
        reward = np.where(failed, -1.0, reward)
        terminated |= failed
        obs = self.observe(sensed)
        obs[failed] = 0.0
        return obs, reward.astype(np.float64), terminated

    def render(self, lane: int, size: tuple[int, int]) -> np.ndarray:
        """Return an (H, W, 3) uint8 picture of one lane (``zoetic.render``): the animal (and
        its goal, as a ball) seen from above and to the side."""
        pos = self.world.positions(0)[lane]
        com = self.body.mass @ pos / self.body.total_mass
        length = float(np.ptp(pos @ np.asarray(self.body.forward, float))) + 1e-9
        goal = [Ball(0.1 * length, position=tuple(self.goal[lane]))] if self.kind == "swim" else []
        mesh = world_mesh([self.body], [pos], [ANIMAL], goal)
        centre = 0.5 * (com + self.goal[lane]) if goal else com
        span = max(length, float(np.linalg.norm(self.goal[lane] - com)) if goal else 0.0)
        eye = centre + np.array([0.0, 0.6, 1.0]) * span
        view = Cameras(eye, look_rotation(centre - eye), np.radians(60.0), size)
        return render(mesh.vertices, mesh.triangles, mesh.colors, view, WATER)[0]


class ZoeticEnv(gymnasium.Env):
    """One animal learning a task in its medium (see the module docstring for the spaces).

    animal: a zoo animal or an animal file; kind: "swim" (toward a goal), "crawl" or "turn";
    control_period: seconds each action is held.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        animal: str = "shark",
        kind: str = "swim",
        control_period: float = 0.05,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (320, 240),
    ) -> None:
        self.core = _Core(animal, kind, 1, control_period)
        n = self.core.observation_size()
        self.observation_space = spaces.Box(-np.inf, np.inf, (n,), np.float32)
        self.action_space = spaces.Box(0.0, 1.0, (self.core.n_act,), np.float32)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.render_size = render_size
        self.metadata = {**self.metadata, "render_fps": int(round(1 / control_period))}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode at a random heading (and goal); return (observation, info)."""
        super().reset(seed=seed)
        self.core.reset_lanes(np.array([0]), [self.np_random])
        return self.core.observe()[0], {}

    def step(self, action) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold the action for one control period; return the Gymnasium step tuple."""
        obs, reward, terminated = self.core.step(np.asarray(action)[None])
        return obs[0], float(reward[0]), bool(terminated[0]), False, {}

    def render(self) -> np.ndarray | None:
        """Return an RGB picture (rgb_array mode), rendered by zoetic.render."""
        if self.render_mode != "rgb_array":
            return None
        return self.core.render(0, self.render_size)


class ZoeticVectorEnv(VectorEnv):
    """``num_envs`` copies of a ZoeticEnv stepped together in one batched World (next-step
    autoreset, like ``SyncVectorEnv``; episodes end after ``max_episode_steps``)."""

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        num_envs: int,
        animal: str = "shark",
        kind: str = "swim",
        control_period: float = 0.05,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (320, 240),
    ) -> None:
        self.num_envs = int(num_envs)
        self.core = _Core(animal, kind, self.num_envs, control_period)
        n = self.core.observation_size()
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (n,), np.float32)
        self.single_action_space = spaces.Box(0.0, 1.0, (self.core.n_act,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.max_episode_steps = max_episode_steps
        self.render_mode = render_mode
        self.render_size = render_size
        self._rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)

    def _rng(self, i: int, seed: int | None) -> np.random.Generator:
        if seed is not None or self._rngs[i] is None:
            self._rngs[i], _ = gymnasium.utils.seeding.np_random(seed)
        return self._rngs[i]

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every lane (seed: None, an int s giving s, s+1, ..., or one per lane)."""
        seeds = [None] * self.num_envs if seed is None else seed
        if isinstance(seeds, int):
            seeds = [seeds + i for i in range(self.num_envs)]
        if len(seeds) != self.num_envs:
            raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        lanes = np.arange(self.num_envs)
        self.core.reset_lanes(lanes, [self._rng(i, s) for i, s in enumerate(seeds)])
        self._autoreset[:] = False
        return self.core.observe(), {}

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        """Step every lane; lanes that ended last step are reset instead (reward 0)."""
        obs, reward, terminated = self.core.step(actions)
        truncated = (
            self.core.steps >= self.max_episode_steps
            if self.max_episode_steps is not None
            else np.zeros(self.num_envs, dtype=bool)
        )
        lanes = np.flatnonzero(self._autoreset)
        if len(lanes):
            self.core.reset_lanes(lanes, [self._rng(i, None) for i in lanes])
            obs[lanes] = self.core.observe()[lanes]
            reward[lanes] = 0.0
            terminated[lanes] = False
            truncated[lanes] = False
        self._autoreset = terminated | truncated
        return obs, reward, terminated, truncated, {}

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Return one RGB picture per lane (rgb_array mode)."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(self.core.render(i, self.render_size) for i in range(self.num_envs))
