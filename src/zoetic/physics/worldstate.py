"""What a World is made of and gives back, as values: animal placements, the world's state
(copy, save, restore) and the contacts of a step."""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import SimulationError


@dataclass(frozen=True)
class Animal:
    """An animal placed in a world: its body, where (offset of the rest pose; default the
    body's start offset), which way (yaw about the vertical, rad, left positive), how fast."""

    body: Body
    offset: tuple[float, float, float] | None = None
    yaw: float = 0.0
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def name(self) -> str:
        return self.body.name


def placed_pose(body: Body, offset=None, yaw: float = 0.0) -> np.ndarray:
    """Return the rest pose (N, 3) turned by ``yaw`` about the vertical through its centre of
    mass, then shifted by ``offset`` (default the body's start offset)."""
    off = body.start_offset if offset is None else np.asarray(offset, float)
    rest = body.rest_pos
    com = (body.mass @ rest) / body.total_mass
    c, s = np.cos(yaw), np.sin(yaw)
    rel = rest - com
    turned = np.stack([c * rel[:, 0] - s * rel[:, 2], rel[:, 1], s * rel[:, 0] + c * rel[:, 2]], 1)
    return turned + com + off


@dataclass(frozen=True)
class WorldState:
    """Everything that changes in a world, as arrays with a leading batch axis B.

    positions/velocities: per animal (B, N, 3) m, m/s; failed_step: per animal (B,) step at
    which it blew up (-1 if not); balls (B, K, 3); food (B, F, 3) and eaten (B, F).
    """

    step: int
    dt: float
    positions: tuple[np.ndarray, ...]
    velocities: tuple[np.ndarray, ...]
    failed_step: tuple[np.ndarray, ...]
    ball_positions: np.ndarray
    ball_velocities: np.ndarray
    food_positions: np.ndarray
    food_eaten: np.ndarray

    @property
    def time(self) -> float:
        """Return the simulated time in s."""
        return self.step * self.dt

    @property
    def batch(self) -> int:
        return int(self.ball_positions.shape[0])

    def take(self, index) -> WorldState:
        """Return the lanes at ``index`` (an int keeps a batch axis of one)."""
        idx = np.atleast_1d(np.asarray(index))
        return WorldState(
            self.step,
            self.dt,
            tuple(p[idx] for p in self.positions),
            tuple(v[idx] for v in self.velocities),
            tuple(f[idx] for f in self.failed_step),
            self.ball_positions[idx],
            self.ball_velocities[idx],
            self.food_positions[idx],
            self.food_eaten[idx],
        )

    def to_bytes(self) -> bytes:
        """Return the state as the bytes of an .npz file."""
        arrays = {
            "step": np.array(self.step),
            "dt": np.array(self.dt),
            "ball_positions": self.ball_positions,
            "ball_velocities": self.ball_velocities,
            "food_positions": self.food_positions,
            "food_eaten": self.food_eaten,
        }
        animals = zip(self.positions, self.velocities, self.failed_step, strict=True)
        for a, (p, v, f) in enumerate(animals):
            arrays |= {f"positions_{a}": p, f"velocities_{a}": v, f"failed_step_{a}": f}
        buf = io.BytesIO()
        np.savez_compressed(buf, **arrays)
        return buf.getvalue()

    def save(self, path: str | Path) -> Path:
        """Write the state to an .npz file (atomically); returns the path."""
        from zoetic.io import atomic_write_bytes

        return atomic_write_bytes(path, self.to_bytes())

    @classmethod
    def load(cls, path: str | Path) -> WorldState:
        """Return the state saved in an .npz file by ``save``."""
        try:
            with np.load(path) as z:
                n = sum(1 for k in z.files if k.startswith("positions_"))
                return cls(
                    int(z["step"]),
                    float(z["dt"]),
                    tuple(z[f"positions_{a}"] for a in range(n)),
                    tuple(z[f"velocities_{a}"] for a in range(n)),
                    tuple(z[f"failed_step_{a}"] for a in range(n)),
                    z["ball_positions"],
                    z["ball_velocities"],
                    z["food_positions"],
                    z["food_eaten"],
                )
        except (OSError, KeyError, ValueError) as exc:
            raise SimulationError(f"{path}: not a saved world state ({exc})") from None


@dataclass(frozen=True)
class Contacts:
    """What touched what during one ``World.step``: impulses in N s, batch axis first.

    impulse: per animal (B, N, O, 3), the impulse each node got from each object
    (objects indexed as in ``World.objects``; food and fixed shapes included, food never
    pushes; an animal that touched nothing gets a read-only view of zeros). An object
    received minus the sum over nodes. between: (B, A, A) the normal impulse animal i got
    from animal j's skin (None: no animal touched another). near: the animals whose nodes
    were tested against the objects (every other animal's impulses are zero; None: not
    known, any may be non-zero).
    """

    impulse: tuple[np.ndarray, ...]
    objects: tuple[str, ...] = field(default=())
    between: np.ndarray | None = None
    near: tuple[int, ...] | None = None

    @property
    def touching(self) -> np.ndarray:
        """Return (B, animals, O) bools: did any node of the animal touch the object."""
        return np.stack([np.abs(i).sum(axis=(1, 3)) > 0 for i in self.impulse], axis=1)

    @property
    def count(self) -> np.ndarray:
        """Return (B,) the number of (node, object) pairs that touched."""
        return sum(
            ((np.abs(i).sum(axis=3) > 0).sum(axis=(1, 2)) for i in self.impulse),
            np.zeros(self.impulse[0].shape[0], dtype=np.int64) if self.impulse else 0,
        )

    def on_object(self, index: int) -> np.ndarray:
        """Return (B, 3) the impulse the animals gave object ``index``."""
        return -sum(i[:, :, index].sum(axis=1) for i in self.impulse)
