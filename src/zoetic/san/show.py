"""Replaying a SAN, and what is drawn beside the creature so one sees why it moves (the video
itself is drawn by ``zoetic.viz.san.show_video``).

The side panel is a scrolling raster of the last seconds: one row per sensor (on = dark blue),
one per hidden node and one per actuator node (the integrator's state as a light tone, the
node's output on as the full colour), and one per actuator command (the bounded sum in
[-2, 2]: red below zero, blue above). The newest column is the current instant.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from zoetic.san.network import Network, NetworkError, SanPolicy, check_fits

__all__ = [
    "BLANK",
    "labelled_raster",
    "network_raster",
    "record_every_for",
    "replay",
    "resolve_network",
]

_SENSOR = np.array([0.16, 0.35, 0.75])
_HIDDEN = np.array([0.90, 0.50, 0.10])
_ACTUATOR = np.array([0.15, 0.60, 0.25])
BLANK = np.array([0.97, 0.97, 0.97])


def resolve_network(path: str | os.PathLike, rank: int = 1) -> Path:
    """Return the network file a path means: the file itself, a tune run's san.json, or the
    ``rank``-th kept network of a search run (sans/NN.json)."""
    path = Path(path)
    if path.is_file():
        return path
    for candidate in (path / "san.json", path / "sans" / f"{rank:02d}.json"):
        if candidate.is_file():
            return candidate
    raise NetworkError(
        f"{path}: not a network file, nor a run directory with san.json or sans/{rank:02d}.json"
    )


def record_every_for(creature, fps: float) -> int:
    """Return how many control ticks lie between two recorded frames at ``fps``."""
    return max(1, round(1.0 / (float(fps) * float(creature.control_dt))))


def replay(
    network: Network,
    creature,
    seconds: float | None = None,
    terrain: str = "flat",
    seed: int = 0,
    fps: float = 30.0,
):
    """Return the recorded Rollout of the network driving its (tuned) creature."""
    from zoetic.san.world import World

    check_fits(network, creature)
    tuned = network.tuned_creature(creature)
    world = World(tuned, terrain=terrain, seed=seed)
    return world.run(
        SanPolicy(network, tuned), seconds=seconds, record_every=record_every_for(tuned, fps)
    )


def network_raster(network: Network, rollout) -> tuple[np.ndarray, list[str]]:
    """Return an RGB raster (rows, R, 3) of sensors, node states and commands, and row labels."""
    sensors = np.asarray(rollout.sensors, dtype=float)  # (R, S)
    n, h = network.n_nodes, network.n_hidden
    states = rollout.states
    if states is None:
        states = np.zeros((len(sensors), 2 * n))
    states = np.asarray(states, dtype=float)
    istate, out = states[:, :n], states[:, n : 2 * n]
    cmds = np.clip(np.asarray(rollout.commands, dtype=float) / 2.0, -1.0, 1.0)  # (R, A)

    def tone(color, level):  # level 0 -> blank, 1 -> colour
        return BLANK + level[..., None] * (color - BLANK)

    rows = [tone(_SENSOR, sensors.T)]
    node_level = np.where(out > 0.5, 1.0, 0.35 * istate).T
    rows.append(tone(_HIDDEN, node_level[:h]))
    rows.append(tone(_ACTUATOR, node_level[h:]))
    pos, neg = np.array([0.15, 0.35, 0.85]), np.array([0.85, 0.2, 0.15])
    c = cmds.T
    rows.append(np.where(c[..., None] >= 0, tone(pos, np.abs(c)), tone(neg, np.abs(c))))
    raster = np.concatenate(rows, axis=0)
    names = [getattr(s, "name", f"s{i + 1}") for i, s in enumerate(_items(rollout, "sensors"))]
    if len(names) != sensors.shape[1]:
        names = [f"s{i + 1}" for i in range(sensors.shape[1])]
    acts = [f"a{i + 1}" for i in range(network.n_actuators)]
    labels = names + [f"h{i + 1}" for i in range(h)] + [f"node {a}" for a in acts]
    labels += [f"cmd {a}" for a in acts]
    return raster, labels


def _items(rollout, what: str):
    creature = getattr(rollout, "creature", None)
    return getattr(creature, what, ()) if creature is not None else ()


def labelled_raster(network: Network, creature, rollout) -> tuple[np.ndarray, list[str]]:
    """Return ``network_raster`` with its rows named after the (tuned) creature's sensors and
    actuators: what the video's side panel shows."""
    raster, labels = network_raster(network, rollout)
    tuned = network.tuned_creature(creature)
    sensor_names = [s.name for s in tuned.sensors] if getattr(tuned, "sensors", None) else []
    act_names = [a.name for a in tuned.actuators] if getattr(tuned, "actuators", None) else []
    if len(sensor_names) == network.n_sensors:
        labels[: network.n_sensors] = sensor_names
    if len(act_names) == network.n_actuators:
        k = network.n_sensors + network.n_hidden
        labels[k : k + network.n_actuators] = [f"node {a}" for a in act_names]
        labels[k + network.n_actuators :] = [f"cmd {a}" for a in act_names]
    return raster, labels
