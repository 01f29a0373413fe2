"""Sensor-actuator networks as data (van de Panne & Fiume 93, Fig. 5-7) and their policy.

A network has S sensor inputs, H hidden nodes and A actuator nodes (N = H + A nodes). Every
hidden and actuator node reads every sensor and every node output (hidden and actuator nodes
are fully interconnected) through integer weights in [-2, 2]:

    weights[i] : (S + N,)  over [sensors..., hidden nodes..., actuator nodes...]

Each node runs Fig. 7 each control tick: the weighted sum moves its internal state up at rate
k1 (> 0) while positive and down at rate k2 (< 0) otherwise; the state is clamped to [0, 1]
and the binary output switches on when the state reaches 1 and off when it reaches 0
(hysteresis). So a node with a constant positive sum switches on after T_on = 1/k1 and, once
the sum stops being positive, off after T_off = -1/k2. Actuator nodes also clip their sum to
[-2, 2]; that value is the command the world maps linearly onto the actuator's [lo, hi].
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from zoetic import io as rd
from zoetic.errors import ZoeticError
from zoetic.io import LIMITS, abbrev, check_keys, read_json, write_json
from zoetic.san.creature_file import creature_from_dict, creature_to_dict, load_creature

__all__ = [
    "FORMAT",
    "PAPER_HIDDEN",
    "TUNING_KEYS",
    "Network",
    "NetworkError",
    "SanPolicy",
    "check_fits",
    "default_delays",
    "load_network",
    "load_with_creature",
    "network_from_dict",
    "random_network",
    "save_network",
]

FORMAT = "zoetic-san"
TUNING_KEYS = ("actuator_lo", "actuator_hi", "ks", "kd", "sensor_lo", "sensor_hi")
WEIGHT_MAX = 2
SUM_BOUND = 2.0
# Hidden nodes per creature in Table 1 of the paper ("about as many as sensors").
PAPER_HIDDEN = {
    "crawler": 10,
    "fish": 5,
    "boulder": 8,
    "bouncer": 8,
    "luxo": 6,
    "cart": 5,
    "walker": 6,
    "twolink": 5,
    "threelink": 7,
    "fourlink": 8,
    "star": 7,
}
_EPS = 1e-9


class NetworkError(ZoeticError):
    """A sensor-actuator network (or its file) is malformed or does not fit its creature."""


def _where(source: str | os.PathLike | None) -> str:
    return f"{source}: " if source else ""


@dataclass(frozen=True, eq=False)
class Network:
    """A SAN: integer weights (N, S+N), per-node rates k1 > 0 and k2 < 0, and its creature.

    ``tuning`` holds the creature's six Fig. 8 arrays (actuator lo/hi, ks, kd, sensor lo/hi)
    when the network was tuned (or saved with them), so it replays exactly; ``None`` means
    the creature's own values.
    """

    creature: str
    weights: np.ndarray  # (N, S+N) int8
    k1: np.ndarray  # (N,) 1/s, > 0
    k2: np.ndarray  # (N,) 1/s, < 0
    n_hidden: int
    tuning: dict[str, np.ndarray] | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _validate(self, None)

    @property
    def n_nodes(self) -> int:
        """Number of hidden plus actuator nodes."""
        return int(self.weights.shape[0])

    @property
    def n_sensors(self) -> int:
        """Number of sensor inputs."""
        return int(self.weights.shape[1] - self.weights.shape[0])

    @property
    def n_actuators(self) -> int:
        """Number of actuator nodes (the last rows of ``weights``)."""
        return self.n_nodes - self.n_hidden

    @property
    def t_on(self) -> np.ndarray:
        """Per-node delay to switch on, 1/k1 (s)."""
        return 1.0 / self.k1

    @property
    def t_off(self) -> np.ndarray:
        """Per-node delay to switch off, -1/k2 (s)."""
        return -1.0 / self.k2

    def with_params(self, **changes: Any) -> Network:
        """Return a copy with some fields replaced (validated again)."""
        return replace(self, **changes)

    def tuned_creature(self, creature):
        """Return the creature with this network's tuning applied (itself when untuned)."""
        check_fits(self, creature)
        if self.tuning is None:
            return creature
        return creature.with_tuning(**{k: self.tuning[k] for k in TUNING_KEYS})

    def to_dict(self) -> dict[str, Any]:
        """Return the network as plain JSON-ready data."""
        out: dict[str, Any] = {
            "format": FORMAT,
            "version": 1,
            "creature": self.creature,
            "n_sensors": self.n_sensors,
            "n_hidden": self.n_hidden,
            "n_actuators": self.n_actuators,
            "weights": self.weights.astype(int).tolist(),
            "k1": [float(v) for v in self.k1],
            "k2": [float(v) for v in self.k2],
        }
        if self.tuning is not None:
            out["tuning"] = {k: [float(v) for v in self.tuning[k]] for k in TUNING_KEYS}
        if self.info:
            out["info"] = self.info
        return out

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Network):
            return NotImplemented
        if self.tuning is None or other.tuning is None:
            same_tuning = self.tuning is other.tuning
        else:
            same_tuning = all(np.array_equal(self.tuning[k], other.tuning[k]) for k in TUNING_KEYS)
        return (
            self.creature == other.creature
            and self.n_hidden == other.n_hidden
            and np.array_equal(self.weights, other.weights)
            and np.array_equal(self.k1, other.k1)
            and np.array_equal(self.k2, other.k2)
            and same_tuning
        )

    __hash__ = None  # type: ignore[assignment]


def _validate(net: Network, source: str | os.PathLike | None) -> None:
    at = _where(source)
    w = np.asarray(net.weights)
    if w.ndim != 2 or w.shape[0] < 1 or w.shape[1] < w.shape[0]:
        raise NetworkError(
            f"{at}weights must be a matrix (nodes, sensors + nodes), got shape {w.shape}"
        )
    if not np.all(np.isfinite(w.astype(float))) or not np.all(np.equal(np.round(w), w)):
        bad = np.argwhere(~np.isfinite(w.astype(float)) | (np.round(w) != w))[0]
        raise NetworkError(
            f"{at}weight [{bad[0]}, {bad[1]}] = {w[tuple(bad)]!r} is not an integer "
            f"(SAN weights are integers in [-{WEIGHT_MAX}, {WEIGHT_MAX}])"
        )
    if np.any(np.abs(w) > WEIGHT_MAX):
        bad = np.argwhere(np.abs(w) > WEIGHT_MAX)[0]
        raise NetworkError(
            f"{at}weight [{bad[0]}, {bad[1]}] = {int(w[tuple(bad)])} is out of range "
            f"[-{WEIGHT_MAX}, {WEIGHT_MAX}]"
        )
    object.__setattr__(net, "weights", np.ascontiguousarray(w, dtype=np.int8))
    n = w.shape[0]
    if not (0 <= int(net.n_hidden) <= n - 1):
        raise NetworkError(f"{at}n_hidden = {net.n_hidden} must be in [0, {n - 1}] for {n} nodes")
    object.__setattr__(net, "n_hidden", int(net.n_hidden))
    for name, sign in (("k1", 1.0), ("k2", -1.0)):
        k = np.asarray(getattr(net, name), dtype=float)
        if k.shape != (n,):
            raise NetworkError(f"{at}{name} must have one value per node ({n}), got {k.shape}")
        if not np.all(np.isfinite(k)) or np.any(sign * k <= 0):
            what = "positive (T_on = 1/k1)" if sign > 0 else "negative (T_off = -1/k2)"
            raise NetworkError(f"{at}{name} must be finite and {what}, got {abbrev(k.tolist())}")
        object.__setattr__(net, name, k.copy())
    if net.tuning is not None:
        tuning = {}
        missing = [k for k in TUNING_KEYS if k not in net.tuning]
        if missing:
            raise NetworkError(f"{at}tuning lacks {', '.join(missing)}")
        sizes = {"actuator": net.n_actuators, "sensor": net.n_sensors}
        for key in TUNING_KEYS:
            arr = np.asarray(net.tuning[key], dtype=float)
            size = sizes["sensor" if key.startswith("sensor") else "actuator"]
            if arr.shape != (size,):
                raise NetworkError(f"{at}tuning {key} must have {size} values, got {arr.shape}")
            if not np.isfinite(arr).all():
                raise NetworkError(f"{at}tuning {key} holds non-finite values: {arr.tolist()}")
            tuning[key] = arr.copy()
        object.__setattr__(net, "tuning", tuning)


def check_fits(network: Network, creature, source: str | os.PathLike | None = None) -> None:
    """Raise NetworkError unless the network's sensors and actuators match the creature's."""
    at = _where(source)
    if network.creature != creature.name:
        raise NetworkError(
            f"{at}network is for creature {network.creature!r}, not {creature.name!r}"
        )
    if network.n_sensors != creature.n_sensors or network.n_actuators != creature.n_actuators:
        raise NetworkError(
            f"{at}network has {network.n_sensors} sensors and {network.n_actuators} actuators; "
            f"creature {creature.name!r} has {creature.n_sensors} sensors and "
            f"{creature.n_actuators} actuators"
        )


NETWORK_KEYS = (
    "format",
    "version",
    "creature",
    "n_sensors",
    "n_hidden",
    "n_actuators",
    "weights",
    "k1",
    "k2",
    "tuning",
    "info",
    "creature_def",
)


def network_from_dict(data: Any, source: str | os.PathLike | None = None) -> Network:
    """Return the network described by JSON data; errors name ``source`` and the entry.

    Strict: unknown keys are refused, counts must be whole numbers, every array is checked
    for shape and size before it becomes a NumPy array.
    """
    at = _where(source)
    src = str(source) if source else "network"
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise NetworkError(f"{at}not a sensor-actuator network file (format != {FORMAT!r})")
    check_keys(data, NETWORK_KEYS, src, NetworkError)
    for key in ("creature", "weights", "k1", "k2", "n_hidden"):
        if key not in data:
            raise NetworkError(f"{at}missing entry {key!r}")
    creature = rd.string(data["creature"], f"{src}: creature", NetworkError)
    n_hidden = rd.integer(data["n_hidden"], f"{src}: n_hidden", NetworkError, 0, LIMITS.links)
    rows = data["weights"]
    if not isinstance(rows, list) or not 1 <= len(rows) <= 2 * LIMITS.links:
        raise NetworkError(
            f"{at}weights must be a list of 1 to {2 * LIMITS.links} rows, got {rd.abbrev(rows)}"
        )
    weights = np.asarray(rd.matrix(rows, f"{src}: weights", NetworkError), dtype=float)
    n = weights.shape[0]
    k1 = np.asarray(rd.numbers(data["k1"], f"{src}: k1", NetworkError, size=n), dtype=float)
    k2 = np.asarray(rd.numbers(data["k2"], f"{src}: k2", NetworkError, size=n), dtype=float)
    tuning = data.get("tuning")
    if tuning is not None:
        if not isinstance(tuning, dict):
            raise NetworkError(f"{at}tuning must be a table of six arrays")
        check_keys(tuning, TUNING_KEYS, f"{src}: tuning", NetworkError)
        tuning = {k: rd.numbers(v, f"{src}: tuning {k}", NetworkError) for k, v in tuning.items()}
    info = data.get("info") or {}
    if not isinstance(info, dict):
        raise NetworkError(f"{at}info must be a table, got {rd.abbrev(info)}")
    shell = object.__new__(Network)
    fields = dict(
        creature=creature,
        weights=weights,
        k1=k1,
        k2=k2,
        n_hidden=n_hidden,
        tuning=tuning,
        info=dict(info),
    )
    for key, value in fields.items():
        object.__setattr__(shell, key, value)
    _validate(shell, source)  # errors name the file
    for key in ("n_sensors", "n_actuators"):
        if key in data:
            value = rd.integer(data[key], f"{src}: {key}", NetworkError, 0)
            if value != getattr(shell, key):
                raise NetworkError(
                    f"{at}{key} = {value} disagrees with the weights ({getattr(shell, key)})"
                )
    return shell


def save_network(network: Network, path: str | os.PathLike, creature=None) -> Path:
    """Write the network as JSON (atomically); returns the path.

    With ``creature`` (the untuned creature it drives) the file carries the creature's whole
    definition (``creature_def``, the creature file's tables), so it is read back without the
    zoo or the creature file: a SAN found for a creature file is tuned, shown and evolved
    like a zoo one."""
    data = network.to_dict()
    if creature is not None:
        check_fits(network, creature, path)
        data["creature_def"] = creature_to_dict(creature)
    return write_json(path, data)


def load_network(path: str | os.PathLike, creature=None) -> Network:
    """Return the network in a JSON file, checked against ``creature`` when given."""
    data = read_json(path, "network file", NetworkError)
    net = network_from_dict(data, path)
    if creature is not None:
        check_fits(net, creature, path)
    return net


def load_with_creature(path: str | os.PathLike, creature=None):
    """Return (network, creature) from a network file.

    The creature is ``creature`` when given (a Creature, a zoo name or a creature file), else
    the one the file carries (``creature_def``), else, for a file written before SAN files
    carried their creature, the zoo creature the file names."""
    data = read_json(path, "network file", NetworkError)
    net = network_from_dict(data, path)
    try:
        if creature is not None and not isinstance(creature, str | os.PathLike):
            c = creature
        elif creature is not None:
            c = load_creature(creature)
        elif "creature_def" in data:
            c = creature_from_dict(data["creature_def"], path)
        else:
            c = load_creature(net.creature)
    except ZoeticError as exc:
        raise NetworkError(f"{path}: its creature: {exc}") from None
    check_fits(net, c, path)
    return net, c


def default_delays(creature) -> float:
    """Return the default node delay T_on = T_off = 0.25 x the creature's expected cycle (s)."""
    return 0.25 * float(creature.expected_cycle)


def default_hidden(creature) -> int:
    """Return the number of hidden nodes: the creature's own, Table 1's, or its sensor count."""
    own = getattr(creature, "hidden", None) or getattr(creature, "n_hidden", None)
    if own:
        return int(own)
    return PAPER_HIDDEN.get(creature.name, creature.n_sensors)


def random_network(
    creature, rng: np.random.Generator, n_hidden: int | None = None, delay: float | None = None
) -> Network:
    """Return a SAN for ``creature`` with uniformly random integer weights in [-2, 2].

    Node delays are T_on = T_off = ``delay`` (default 0.25 x the expected cycle).
    """
    h = default_hidden(creature) if n_hidden is None else int(n_hidden)
    n = h + creature.n_actuators
    weights = rng.integers(-WEIGHT_MAX, WEIGHT_MAX + 1, size=(n, creature.n_sensors + n))
    t = default_delays(creature) if delay is None else float(delay)
    if not t > 0:
        raise NetworkError(f"node delay must be positive, got {t}")
    return Network(
        creature=creature.name,
        weights=weights.astype(np.int8),
        k1=np.full(n, 1.0 / t),
        k2=np.full(n, -1.0 / t),
        n_hidden=h,
    )


class SanPolicy:
    """The network run as a controller: binary sensors (S,) -> actuator commands (A,) in [-2, 2].

    It is a ``zoetic.control.policy.Policy`` like every other controller: ``act`` takes the
    observation ``{"san_sensors": (1, S)}`` and a control ``Period`` and returns the commands
    (1, A) held over it (``step`` is the same, unbatched, for the SAN world's hot loop).

    ``state`` is the per-node internal state (N,) in [0, 1] followed by the binary outputs
    (N,); all start at 0 (``reset``). Nodes update synchronously from the previous outputs.

    The step is event driven (measured ~5x faster than the same in NumPy ops for these sizes):
    the weighted sums change only when a sensor or a node output changes, and between such
    events only the integrators that are not yet clamped move.
    """

    def __init__(self, network: Network, creature=None) -> None:
        if creature is not None:
            check_fits(network, creature)
        self.network = network
        self._n, self._s, self._h = network.n_nodes, network.n_sensors, network.n_hidden
        self._w = network.weights.astype(np.float64)
        self._k1 = network.k1.tolist()
        self._k2 = network.k2.tolist()
        self._dt = -1.0
        self.reset()

    sensors: tuple[str, ...] = ("san_sensors",)

    def act(self, observation, period) -> np.ndarray:
        """Return the commands (1, A) for a control period, after advancing the nodes over it
        with the binary sensor values ``observation["san_sensors"]`` (1, S)."""
        seen = np.asarray(observation["san_sensors"], dtype=np.float64).reshape(-1)
        return self.step(seen, period.steps * period.dt)[None, :]

    def reset(self, seed: int | None = None) -> None:
        """Set every node's internal state and output to 0 (deterministic: ``seed`` unused)."""
        n = self._n
        self._x = np.zeros(self._s + n)  # [sensors, node outputs]
        self._ist = [0.0] * n
        self._out = [0] * n
        self._rate = [0.0] * n
        self._moving: list[int] = []
        self._key = None
        self._dirty = True
        self._command = np.zeros(n - self._h)

    @property
    def state(self) -> np.ndarray:
        """Return [internal states (N,), outputs (N,)]: hidden nodes first, then actuators."""
        return np.array(self._ist + [float(o) for o in self._out])

    @property
    def outputs(self) -> np.ndarray:
        """Return the binary node outputs (N,) as floats 0/1."""
        return np.array(self._out, dtype=float)

    def step(self, sensors: np.ndarray, dt: float) -> np.ndarray:
        """Advance every node by ``dt`` (s); return the actuator commands (A,) in [-2, 2]."""
        if dt != self._dt:
            self._dt = dt
            self._dirty = True
        key = sensors.tobytes() if isinstance(sensors, np.ndarray) else bytes(sensors)
        if self._dirty or key != self._key:
            self._key = key
            self._x[: self._s] = np.asarray(sensors, dtype=np.float64).reshape(self._s)
            self._recompute()
        # the command uses this tick's sums (sensors now, node outputs of the last tick)
        command = self._command
        if self._moving:
            ist, rate, out = self._ist, self._rate, self._out
            still = []
            for i in self._moving:
                v = ist[i] + rate[i]
                if v >= 1.0 - _EPS:
                    ist[i] = 1.0
                    if not out[i]:
                        out[i] = 1
                        self._x[self._s + i] = 1.0
                        self._dirty = True
                elif v <= _EPS:
                    ist[i] = 0.0
                    if out[i]:
                        out[i] = 0
                        self._x[self._s + i] = 0.0
                        self._dirty = True
                else:
                    ist[i] = v
                    still.append(i)
            self._moving = still
        return command

    def _recompute(self) -> None:
        sums = self._w @ self._x
        self._command = np.clip(sums[self._h :], -SUM_BOUND, SUM_BOUND)
        dt, k1, k2, ist = self._dt, self._k1, self._k2, self._ist
        rate = self._rate
        moving = []
        for i, total in enumerate(sums.tolist()):
            if total > 0.0:
                rate[i] = k1[i] * dt
                if ist[i] < 1.0:
                    moving.append(i)
            else:
                rate[i] = k2[i] * dt
                if ist[i] > 0.0:
                    moving.append(i)
        self._moving = moving
        self._dirty = False
