"""A world: animals of any kinds plus passive objects in one medium, stepped in lockstep.

``World([shark, Ball(...), Box(...)], medium="sea", batch=B)`` holds B copies (candidates)
of the scene. ``world.step(seconds, activations)`` advances them all with the batched animal
kernel (the same compiled code as ``physics.simulate``, so a lone animal stepped in slices
follows the open-loop trajectory) and moves the objects; a node against a fixed shape feels a
penalty force, a ball is resolved by impulses with restitution below one (``physics.contacts``),
and animals push each other with dissipative penalties (a node against the other's skin,
``physics.bodycontact``); each step() returns their record. ``world.state`` is a
frozen value that can be copied, saved and restored, so a planner can look ahead from "now".

Contacts are resolved every time step, but only while some node is within reach of an object
or of another animal; far from everything the animals run whole slices through the kernel at
full speed. What the world decides for a stretch of steps (which animals may touch what, which
food was eaten) it decides on its own grid of slices (every ``MAX_SLICE`` steps from t = 0), never
per call: stepping 0.1 s at once or as 0.05 + 0.05 s gives the same world bit for bit.
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics.bodycontact import (
    CONTACT_STEPS,
    close,
    close_pairs,
    pair_contacts,
    surface_reach,
)
from zoetic.physics.contacts import balls_step, near, node_contacts
from zoetic.physics.kernel import make_stepper
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.multirate import split
from zoetic.physics.objects import Ball, Box, Cylinder, Food, pack_balls, pack_statics
from zoetic.physics.simulate import VMAX, chunk_size, kernel_arrays

F32 = np.float32
# lane-steps per kernel call from which the thread pool is worth its launch (and its barrier,
# which is slow on a busy host): 64 gym lanes x 10 steps run faster on one thread
PARALLEL_FROM = 8192
MAX_SLICE = 20  # steps between reach checks while objects are about
SUB_SLICE = 5  # steps between the checks of animals that may touch one another


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
            self.step, self.dt, tuple(p[idx] for p in self.positions),
            tuple(v[idx] for v in self.velocities), tuple(f[idx] for f in self.failed_step),
            self.ball_positions[idx], self.ball_velocities[idx], self.food_positions[idx],
            self.food_eaten[idx],
        )  # fmt: skip

    def to_bytes(self) -> bytes:
        """Return the state as the bytes of an .npz file."""
        arrays = {
            "step": np.array(self.step), "dt": np.array(self.dt),
            "ball_positions": self.ball_positions, "ball_velocities": self.ball_velocities,
            "food_positions": self.food_positions, "food_eaten": self.food_eaten,
        }  # fmt: skip
        for a, (p, v, f) in enumerate(zip(self.positions, self.velocities, self.failed_step,
                                          strict=True)):  # fmt: skip
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
                    int(z["step"]), float(z["dt"]),
                    tuple(z[f"positions_{a}"] for a in range(n)),
                    tuple(z[f"velocities_{a}"] for a in range(n)),
                    tuple(z[f"failed_step_{a}"] for a in range(n)),
                    z["ball_positions"], z["ball_velocities"], z["food_positions"],
                    z["food_eaten"],
                )  # fmt: skip
        except (OSError, KeyError, ValueError) as exc:
            raise SimulationError(f"{path}: not a saved world state ({exc})") from None


@dataclass(frozen=True)
class Contacts:
    """What touched what during one ``World.step``: impulses in N s, batch axis first.

    impulse: per animal (B, N, O, 3), the impulse each node got from each object
    (objects indexed as in ``World.objects``; food and fixed shapes included, food never
    pushes). An object received minus the sum over nodes. between: (B, A, A) the normal
    impulse animal i got from animal j's skin (None: no animal touched another). near: the
    animals whose nodes were tested against the objects (every other animal's impulses are
    zero; None: not known, any may be non-zero).
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


def _kernel(parallel: bool):
    """Return the stateful kernel's entry point, threaded or serial (compiled, or loaded from
    numba's cache, once per process and only when first needed)."""
    if parallel not in _KERNELS:
        from zoetic.physics.kernel import advance_entry

        _KERNELS[parallel] = advance_entry(parallel)
    return _KERNELS[parallel]


_KERNELS: dict = {}


@njit(cache=True)
def fill_table(u, out) -> bool:
    """Copy activations u (B|1, T|1, A) into the kernel's table out (T, A, B), clipped to
    [0, 1]; return False if any is not finite."""
    steps, n_act, batch = out.shape
    one_b = u.shape[0] == 1
    one_t = u.shape[1] == 1
    for t in range(steps):
        for b in range(batch):
            for k in range(n_act):
                x = u[0 if one_b else b, 0 if one_t else t, k]
                if not math.isfinite(x):
                    return False
                out[t, k, b] = min(max(x, 0.0), 1.0)
    return True


@njit(cache=True)
def eaten_on_path(h0, h1, f0, f1, radius, eaten) -> None:
    """Mark eaten (B, F) the food particles (before f0, after f1: (B, F, 3)) that a head
    (before h0, after h1: (animals, B, 3)) came within ``radius`` (F,) of during the slice:
    the closest point of the head's path relative to the particle (a straight segment)."""
    for b in range(f0.shape[0]):
        for q in range(f0.shape[1]):
            if eaten[b, q]:
                continue
            for a in range(h0.shape[0]):
                a0 = h0[a, b, 0] - f0[b, q, 0]
                a1 = h0[a, b, 1] - f0[b, q, 1]
                a2 = h0[a, b, 2] - f0[b, q, 2]
                d0 = (h1[a, b, 0] - f1[b, q, 0]) - a0
                d1 = (h1[a, b, 1] - f1[b, q, 1]) - a1
                d2 = (h1[a, b, 2] - f1[b, q, 2]) - a2
                s = -(a0 * d0 + a1 * d1 + a2 * d2) / ((d0 * d0 + d1 * d1 + d2 * d2) + 1e-12)
                s = min(max(s, 0.0), 1.0)
                c0 = a0 + s * d0
                c1 = a1 + s * d1
                c2 = a2 + s * d2
                closest = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
                if math.isfinite(closest) and closest < radius[q]:
                    eaten[b, q] = True
                    break


@njit(cache=True)
def near_each(pos, vel, off, radius, bpos, bvel, bpar, skind, scenter, ssize, horizon, out):
    """Fill out (animals,) with ``contacts.near`` of each animal (rows off[a]:off[a + 1] of
    pos and vel): could any of its nodes touch a ball or fixed shape within ``horizon`` s."""
    for a in range(off.shape[0] - 1):
        out[a] = near(pos[off[a]:off[a + 1]], vel[off[a]:off[a + 1]], radius, bpos, bvel, bpar,
                      skind, scenter, ssize, horizon)  # fmt: skip


class World:
    """Animals and passive objects in one medium, B copies stepped together.

    members: Bodies (placed at their start offset), ``Animal`` placements, and ``Ball``,
    ``Box``, ``Cylinder`` and ``Food`` objects, in any order. medium: a Medium or a name
    (default the first animal's). dt: default the smallest of the animals' own. current:
    water velocity (m/s) that carries food and drags balls. animal_contact: animals push
    each other apart when they touch (``physics.bodycontact``; default True).
    """

    def __init__(
        self,
        members: Sequence[Body | Animal | Ball | Box | Cylinder | Food],
        medium: str | Medium | None = None,
        batch: int = 1,
        dt: float | None = None,
        current: Sequence[float] = (0.0, 0.0, 0.0),
        node_radius: float = 0.03,
        contact_steps: int = 4,
        damping_ratio: float = 0.3,
        friction: float = 0.5,
        animal_contact: bool = True,
    ) -> None:
        self.animals: list[Animal] = []
        self.objects: list[Ball | Box | Cylinder | Food] = []
        for m in members:
            if isinstance(m, Body):
                self.animals.append(Animal(m))
            elif isinstance(m, Animal):
                self.animals.append(m)
            elif isinstance(m, Ball | Box | Cylinder | Food):
                self.objects.append(m)
            else:
                raise SimulationError(f"a world holds animals and objects, not {type(m)!r}")
        if not self.animals:
            raise SimulationError("a world needs at least one animal")
        if batch < 1:
            raise SimulationError(f"batch must be at least 1, got {batch}")
        self.bodies = [a.body for a in self.animals]
        self.medium = get_medium(medium or self.bodies[0].medium)
        self.dt = float(dt or min(b.dt for b in self.bodies))
        if not self.dt > 0:
            raise SimulationError(f"dt must be positive, got {self.dt}")
        self.batch = int(batch)
        self.current = np.asarray(current, float).reshape(3)
        self.node_radius = float(node_radius)
        self._w = np.pi / (contact_steps * self.dt)
        self._w_body = np.pi / (CONTACT_STEPS * self.dt)
        self._zeta = float(damping_ratio)
        self._mu = float(friction)
        self._med32 = self.medium.as_array().astype(F32)
        self._med64 = self.medium.as_array()
        # objects by kind, each with its index in self.objects
        idx = {k: [i for i, o in enumerate(self.objects) if isinstance(o, k)]
               for k in (Ball, Box, Cylinder, Food)}  # fmt: skip
        self._ball_obj = np.array(idx[Ball], dtype=np.int64)
        self._static_obj = np.array(sorted(idx[Box] + idx[Cylinder]), dtype=np.int64)
        self._food_obj = np.array(idx[Food], dtype=np.int64)
        self.balls = [self.objects[i] for i in self._ball_obj]
        self.statics = [self.objects[i] for i in self._static_obj]
        self.foods = [self.objects[i] for i in self._food_obj]
        self._bpar = pack_balls(self.balls)
        self._skind, self._scenter, self._ssize = pack_statics(self.statics)
        self._solids = len(self.balls) + len(self.statics) > 0
        # animal state: one (N_total, 3, B) float32 array; each animal a contiguous slice
        sizes = [b.n_nodes for b in self.bodies]
        self._off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        n_tot = int(self._off[-1])
        self._pos = np.zeros((n_tot, 3, self.batch), dtype=F32)
        self._vel = np.zeros_like(self._pos)
        self._mass = [b.mass.astype(np.float64) for b in self.bodies]
        self._karr = [kernel_arrays(b) for b in self.bodies]
        # the multirate split of each body at this dt (stiff springs sub-stepped), as simulate
        self._splits = [tuple(split(b, self.dt)) for b in self.bodies]
        # the kernel's own failure marks, one array per animal: >= 0 marks a dead lane
        self._fs = [-np.ones(self.batch, dtype=np.int64) for _ in self.bodies]
        self._failed = [-np.ones(self.batch, dtype=np.int64) for _ in self.bodies]
        self._bpos = np.zeros((len(self.balls), 3, self.batch))
        self._bvel = np.zeros_like(self._bpos)
        self._bforce = np.zeros_like(self._bpos)
        self._food = np.zeros((self.batch, len(self.foods), 3))
        self._food_radius = np.array([f.radius for f in self.foods], float)
        self._eaten = np.zeros((self.batch, len(self.foods)), dtype=bool)
        self._n = 0
        # the world's own cadence (see ``step``): the food test's last mark (the step, the food
        # there, the heads there) and the broad phase's decisions for the slice under way
        self._mark = 0
        self._mark_heads: np.ndarray | None = None
        self._plan: tuple | None = None
        self._sub: tuple | None = None
        self._tables: dict[tuple[int, int], tuple[np.ndarray, tuple]] = {}
        self._tested: set[int] = set()  # the animals whose node contacts a step computed
        self._views = [(self._pos[o0:o1], self._vel[o0:o1])
                       for o0, o1 in zip(self._off[:-1], self._off[1:], strict=True)]  # fmt: skip
        self._lone = len(self.animals) == 1
        self._head_rows = np.array([o + b.head for o, b in zip(self._off[:-1], self.bodies,
                                                              strict=True)], int)
        # animal-animal contact: each body's skin triangles and the broad phase's reach
        self._touchy = bool(animal_contact) and len(self.animals) > 1
        self._faces = [np.ascontiguousarray(b.faces, dtype=np.int64) for b in self.bodies]
        self._touchy &= all(len(f) for f in self._faces)
        self._reach = [surface_reach(b) for b in self.bodies]
        self._reach_arr = np.array(self._reach, float)
        self._pair_buf = np.zeros((2, self.batch))
        self._no_contacts = Contacts(
            tuple(np.zeros((self.batch, b.n_nodes, 0, 3)) for b in self.bodies), ()
        )
        self._serial = _kernel(False)
        self._parallel = _kernel(True) if self.batch > 8 else self._serial
        self._chunk = chunk_size(self.batch)
        # one stepper per animal: its state views, body arrays and scratch, stepped in place
        self._steppers = [
            make_stepper(p, v, fs, failed, self.dt, self._chunk, VMAX, karr, self._med32, sp)
            for (p, v), fs, failed, karr, sp in zip(
                self._views, self._fs, self._failed, self._karr, self._splits, strict=True
            )
        ]
        self.restore(self.initial_state())

    # ---- state as a value -------------------------------------------------------------
    def initial_state(self) -> WorldState:
        """Return the state at t = 0: animals and objects where they were placed, B copies."""
        B = self.batch
        pos, vel = [], []
        for a in self.animals:
            p = placed_pose(a.body, a.offset, a.yaw)
            pos.append(np.broadcast_to(p, (B, *p.shape)).copy())
            vel.append(np.broadcast_to(np.asarray(a.velocity, float), (B, *p.shape)).copy())

        def rows(values, n):
            return np.broadcast_to(np.asarray(values, float).reshape(n, 3), (B, n, 3)).copy()

        nb, nf = len(self.balls), len(self.foods)
        return WorldState(
            0, self.dt, tuple(pos), tuple(vel),
            tuple(-np.ones(B, dtype=np.int64) for _ in self.animals),
            rows([b.position for b in self.balls], nb), rows([b.velocity for b in self.balls], nb),
            rows([f.position for f in self.foods], nf), np.zeros((B, nf), dtype=bool),
        )  # fmt: skip

    @property
    def time(self) -> float:
        """Return the simulated time in s."""
        return self._n * self.dt

    @property
    def step_count(self) -> int:
        """Return the number of time steps taken since t = 0."""
        return self._n

    @property
    def state(self) -> WorldState:
        """Return the current state as a value (copies: later steps do not change it)."""
        pos = tuple(self.positions(a) for a in range(len(self.animals)))
        vel = tuple(self.velocities(a) for a in range(len(self.animals)))
        return WorldState(
            self._n, self.dt, pos, vel, tuple(f.copy() for f in self._failed),
            self._bpos.transpose(2, 0, 1).copy(), self._bvel.transpose(2, 0, 1).copy(),
            self._food_now(), self._eaten.copy(),
        )  # fmt: skip

    def restore(self, state: WorldState, lanes=None) -> None:
        """Make ``state`` the current one; with ``lanes``, only those lanes take it (the
        state then holds one lane per index, or one for all) and the clock stays. The broad
        phase decides afresh from here for the rest of the grid's slice (it only picks which
        animals are checked for contacts, so the motion is the same), and the food test's path
        starts here (a state taken between the grid's steps goes on as one never interrupted
        but for that path and the food's drift rounding)."""
        if len(state.positions) != len(self.animals):
            raise SimulationError(
                f"the state holds {len(state.positions)} animals; this world {len(self.animals)}"
            )
        sel = slice(None) if lanes is None else np.atleast_1d(np.asarray(lanes))
        for a, body in enumerate(self.bodies):
            p = np.asarray(state.positions[a])
            if p.shape[1:] != (body.n_nodes, 3):
                raise SimulationError(
                    f"the state's animal {a} has {p.shape[1:]} positions; the {body.name} "
                    f"has ({body.n_nodes}, 3)"
                )
            o0, o1 = self._off[a], self._off[a + 1]
            self._pos[o0:o1, :, sel] = np.asarray(p).transpose(1, 2, 0)
            self._vel[o0:o1, :, sel] = np.asarray(state.velocities[a]).transpose(1, 2, 0)
            self._failed[a][sel] = state.failed_step[a]
            self._fs[a][sel] = np.where(np.asarray(state.failed_step[a]) >= 0, 0, -1)
        self._bpos[:, :, sel] = np.asarray(state.ball_positions).transpose(1, 2, 0)
        self._bvel[:, :, sel] = np.asarray(state.ball_velocities).transpose(1, 2, 0)
        self._eaten[sel] = state.food_eaten
        # the broad phase decides afresh from here; the food test's mark moves here
        self._plan = self._sub = None
        if lanes is None:
            if state.batch != self.batch:
                raise SimulationError(
                    f"the state holds {state.batch} lanes; this world {self.batch}"
                )
            self._n = self._mark = int(state.step)
            self._food[:] = state.food_positions
            self._mark_heads = self._heads()
        else:  # these lanes' food held at the mark, so that it lies where the state puts it now
            drift = self.current * (self._n - self._mark) * self.dt
            self._food[sel] = np.asarray(state.food_positions) - drift
            self._mark_heads[:, sel] = self._heads()[:, sel]

    def positions(self, animal: int = 0) -> np.ndarray:
        """Return the animal's node positions (B, N, 3) in m (a copy)."""
        o0, o1 = self._off[animal], self._off[animal + 1]
        return self._pos[o0:o1].transpose(2, 0, 1).astype(np.float64)

    def node_positions(self, lane: int = 0) -> np.ndarray:
        """Return every animal's node positions (N_total, 3) in m in one lane (a copy):
        animal a's are rows ``offsets[a]:offsets[a + 1]`` (``positions(a)[lane]`` for all the
        animals in one conversion)."""
        return self._pos[:, :, lane].astype(np.float64)

    def node_velocities(self, lane: int = 0) -> np.ndarray:
        """Return every animal's node velocities (N_total, 3) in m/s in one lane (a copy)."""
        return self._vel[:, :, lane].astype(np.float64)

    @property
    def offsets(self) -> np.ndarray:
        """Return (animals + 1,) the first row of each animal in ``node_positions``."""
        return self._off

    def velocities(self, animal: int = 0) -> np.ndarray:
        """Return the animal's node velocities (B, N, 3) in m/s (a copy)."""
        o0, o1 = self._off[animal], self._off[animal + 1]
        return self._vel[o0:o1].transpose(2, 0, 1).astype(np.float64)

    def failed(self, animal: int = 0) -> np.ndarray:
        """Return (B,) bools: True where that animal blew up."""
        return self._failed[animal] >= 0

    @property
    def ball_positions(self) -> np.ndarray:
        """Return the balls' centres (B, K, 3) in m."""
        return self._bpos.transpose(2, 0, 1).copy()

    @property
    def ball_velocities(self) -> np.ndarray:
        """Return the balls' velocities (B, K, 3) in m/s."""
        return self._bvel.transpose(2, 0, 1).copy()

    @property
    def food_positions(self) -> np.ndarray:
        """Return the food particles (B, F, 3) in m."""
        return self._food_now()

    def _food_now(self) -> np.ndarray:
        """Return the food particles now (a copy): as at the mark, drifted since."""
        if self._n == self._mark:
            return self._food.copy()
        return self._food + self.current * (self._n - self._mark) * self.dt

    @property
    def food_eaten(self) -> np.ndarray:
        """Return (B, F) bools: which food particles have been eaten."""
        return self._eaten.copy()

    # ---- stepping ---------------------------------------------------------------------
    def steps_for(self, seconds: float) -> int:
        """Return how many time steps ``step(seconds)`` takes from now (the clock stays on
        the dt grid: 30 steps of 1/30 s with dt 5 ms take 200 steps in all)."""
        return int(round((self._n * self.dt + seconds) / self.dt)) - self._n

    def _table(self, a: int, acts, steps: int) -> np.ndarray:
        """Return the (T, A, B) float32 table the kernel reads (a reused buffer)."""
        cached = self._tables.get((a, steps))
        if cached is not None and type(acts) is np.ndarray and acts.shape == cached[1]:
            # the common case, checked once: (B, T, A) rows for this slice length
            if not fill_table(acts, cached[0]):
                raise SimulationError(
                    f"activations for the {self.bodies[a].name} contain non-finite values"
                )
            return cached[0]
        body = self.bodies[a]
        na = body.n_actuators
        if cached is None:
            out = np.zeros((steps, max(1, na), self.batch), F32)
            self._tables[(a, steps)] = (out, (self.batch, steps, na))
        else:
            out = cached[0]
        if acts is None or na == 0:
            out[...] = 0.0
            return out
        u = np.asarray(acts)
        if u.ndim == 3 and u.shape[0] == self.batch and u.shape[2] == na and u.shape[1] != steps:
            raise SimulationError(
                f"the {body.name}'s activations hold {u.shape[1]} rows; this step takes "
                f"{steps} steps"
            )
        if u.shape not in ((na,), (self.batch, na), (self.batch, steps, na)):
            raise SimulationError(
                f"activations for the {body.name} must be shaped (A,), (B, A) or (B, T, A) with "
                f"B = {self.batch} lanes and A = {na} actuators, got {u.shape}"
            )
        u3 = u if u.ndim == 3 else u[:, None, :] if u.ndim == 2 else u[None, None, :]
        if not fill_table(u3, out):
            raise SimulationError(f"activations for the {body.name} contain non-finite values")
        return out

    def _per_animal(self, activations) -> list:
        n = len(self.animals)
        if n == 1 and isinstance(activations, np.ndarray):
            return [activations]
        if activations is None:
            return [None] * n
        if isinstance(activations, dict):
            names = [a.name for a in self.animals]
            unknown = set(activations) - set(names)
            if unknown:
                raise SimulationError(f"no animal named {sorted(unknown)} in this world")
            return [activations.get(nm) for nm in names]
        if isinstance(activations, list | tuple):
            if len(activations) != n:
                raise SimulationError(f"{len(activations)} activation arrays for {n} animals")
            return list(activations)
        if n != 1:
            raise SimulationError(f"this world holds {n} animals: give one array for each")
        return [activations]

    def _animals_run(self, tables, t0: int, t1: int) -> None:
        kernel = self._parallel if self.batch * (t1 - t0) >= PARALLEL_FROM else self._serial
        base = self._n + t0
        for stepper, table in zip(self._steppers, tables, strict=False):
            kernel(stepper, table, t0, t1, base)

    def step(self, seconds: float, activations=None) -> Contacts:
        """Advance the world by ``seconds`` (rounded to whole time steps) and return the
        contacts it made.

        activations: for each animal (a list, a dict by animal name, or one array for a lone
        animal) an array (A,) or (B, A) held over the slice, or (B, T, A) one row a step with
        T = ``steps_for(seconds)``; None holds every actuator at 0.

        How the steps are split into calls changes nothing: the broad phase decides once for
        each slice of the world's grid (``MAX_SLICE`` steps; the pairs of animals again every
        ``SUB_SLICE``) and keeps its decision for the rest of the slice, and food is tested
        and drifted at the grid's steps (a particle eaten during a slice shows as eaten from
        the slice's last step on). The returned contacts are this call's.
        """
        steps = int(round((self._n * self.dt + seconds) / self.dt)) - self._n  # steps_for
        if steps < 0:
            raise SimulationError(f"cannot step back in time ({seconds} s)")
        if self._lone and type(activations) is np.ndarray:
            tables = [self._table(0, activations, steps)]
            if not self.objects:  # one animal alone: the shortest path (closed-loop slices)
                kernel = self._parallel if self.batch * steps >= PARALLEL_FROM else self._serial
                kernel(self._steppers[0], tables[0], 0, steps, self._n)
                self._n += steps
                return self._no_contacts
        else:
            acts = self._per_animal(activations)
            tables = [self._table(a, u, steps) for a, u in enumerate(acts)]
        if not self.objects and not self._touchy:  # nothing to touch, nothing to eat
            self._animals_run(tables, 0, steps)
            self._n += steps
            return self._no_contacts
        n_obj = len(self.objects)
        # one zeroed buffer for all the animals' impulses, each a view of its rows
        whole = np.zeros((int(self._off[-1]), n_obj, 3, self.batch))
        impulse = [whole[o0:o1] for o0, o1 in zip(self._off[:-1], self._off[1:], strict=True)]
        self._tested = set()
        n_an = len(self.animals)
        between = np.zeros((self.batch, n_an, n_an)) if self._touchy else None
        decide = self._solids or self._touchy
        t = 0
        while t < steps:
            # the world's slices end on its own grid (every MAX_SLICE steps from t = 0), not
            # where the caller's steps end: a caller may split a slice, never change it
            end = (self._n + t) // MAX_SLICE * MAX_SLICE + MAX_SLICE
            t1 = min(steps, end - self._n)
            mode, pairs, near_now = self._decide(end, t) if decide else ("free", [], None)
            if mode == "lockstep":  # balls couple everything, or some node is near a shape
                for s in range(t, t1):
                    self._contact_step(tables, s, impulse, pairs, between)
            elif mode == "apart":
                self._slice_apart(tables, t, t1, impulse, near_now, pairs, between)
            else:
                self._animals_run(tables, t, t1)
                if len(self.balls):
                    self._bforce[:] = 0.0
                    self._balls(t1 - t)
            t = t1
            if self.foods and self._n + t == end:
                self._food_update(end)
        self._n += steps
        return Contacts(
            tuple(i.transpose(3, 0, 1, 2) for i in impulse),
            tuple(o.name for o in self.objects),
            between if between is not None and between.any() else None,
            tuple(sorted(self._tested)),
        )

    def _decide(self, end: int, t: int) -> tuple[str, list[tuple[int, int]], np.ndarray | None]:
        """Return the broad phase's decisions for the world's slice that ends at step ``end``
        (the caller's step t of this call): how it is stepped (``lockstep``: all animals one
        step at a time with their contacts; ``apart``: ``_slice_apart``; ``free``: whole in
        the kernel), the pairs of animals that may touch, and which animals are near a
        fixed shape. Decided once, at the first step of the slice stepped (its start, or
        where a restore left the clock), and kept however the calls split the slice."""
        if self._plan is not None and self._plan[0] == end:
            return self._plan[1]
        horizon = (end - self._n - t) * self.dt
        pairs = self._close_pairs(horizon) if self._touchy else []
        near_now = None
        if pairs and len(self.balls):
            mode = "lockstep"
        elif pairs or (self._solids and not len(self.balls) and len(self.animals) > 1):
            # no balls couple the animals: only those near a fixed shape step one step at a
            # time with contacts, the others the whole slice in one kernel call
            mode = "apart"
            near_now = np.zeros(len(self.animals), bool)
            near_each(self._pos, self._vel, self._off, self.node_radius, self._bpos,
                      self._bvel, self._bpar, self._skind, self._scenter, self._ssize, horizon,
                      near_now)  # fmt: skip
        elif self._solids and self._any_near(horizon):
            mode = "lockstep"
        else:
            mode = "free"
        self._plan = (end, (mode, pairs, near_now))
        return self._plan[1]

    def _close_pairs(self, horizon: float) -> list[tuple[int, int]]:
        """Return the pairs of animals that may touch within ``horizon`` s (broad phase)."""
        found = close_pairs(self._pos, self._vel, self._off, self._reach_arr, self.node_radius,
                            horizon)  # every pair in one kernel call, ``_close`` for each
        return [(int(a), int(c)) for a, c in found]

    def _close(self, a: int, c: int, horizon: float) -> bool:
        """Return True if animals a and c may touch within ``horizon`` s (``bodycontact.close``)."""
        reach = max(self._reach[a], self._reach[c]) + self.node_radius
        (pa, va), (pc, vc) = self._views[a], self._views[c]
        return bool(close(pa, va, pc, vc, reach, self.node_radius, horizon))

    def _pair(self, a: int, c: int, between: np.ndarray) -> None:
        """One step's contact impulses between animals a and c (recorded in ``between``)."""
        buf = self._pair_buf
        buf[:] = 0.0
        (pa, va), (pc, vc) = self._views[a], self._views[c]
        pair_contacts(pa, va, self._mass[a], self._faces[a], pc, vc, self._mass[c],
                      self._faces[c], self.node_radius, self.dt, self._w_body, self._zeta, buf)
        between[:, a, c] += buf[0]
        between[:, c, a] += buf[1]

    def _any_near(self, horizon: float) -> bool:
        for a in range(len(self.animals)):
            o0, o1 = self._off[a], self._off[a + 1]
            if near(self._pos[o0:o1], self._vel[o0:o1], self.node_radius, self._bpos, self._bvel,
                    self._bpar, self._skind, self._scenter, self._ssize, horizon):  # fmt: skip
                return True
        return False

    def _near(self, a: int, horizon: float) -> bool:
        o0, o1 = self._off[a], self._off[a + 1]
        return bool(near(self._pos[o0:o1], self._vel[o0:o1], self.node_radius, self._bpos,
                         self._bvel, self._bpar, self._skind, self._scenter, self._ssize,
                         horizon))  # fmt: skip

    def _slice_apart(self, tables, t: int, t1: int, impulse, near_now: np.ndarray, pairs=(),
                     between=None) -> None:  # fmt: skip
        """Step steps t..t1 of animals that no balls couple: each near a fixed shape
        (``near_now``) one step at a time with its contacts, each other one in one kernel
        call; the animals of ``pairs`` (that may touch one another) in lockstep, one step at a
        time."""
        kernel = self._parallel if self.batch * (t1 - t) >= PARALLEL_FROM else self._serial
        one = self._parallel if self.batch >= PARALLEL_FROM else self._serial
        base = self._n + t
        busy = sorted({a for p in pairs for a in p})
        for a, (stepper, table) in enumerate(zip(self._steppers, tables, strict=False)):
            if a in busy:
                continue
            if not near_now[a]:
                kernel(stepper, table, t, t1, base)
                continue
            for s in range(t, t1):
                self._node_contacts(a, impulse)
                one(stepper, table, s, s + 1, self._n + s)
        if not busy:
            return
        near_shape = [a for a in busy if self._solids and near_now[a]]
        # the pairs checked again every SUB_SLICE steps (on the world's grid, as the slices):
        # an animal of a pair not close now takes the sub-slice in one kernel call
        s = t
        while s < t1:
            end = (self._n + s) // SUB_SLICE * SUB_SLICE + SUB_SLICE
            s1 = min(t1, end - self._n)
            if self._sub is None or self._sub[0] != end:
                horizon = (end - self._n - s) * self.dt
                self._sub = (end, [p for p in pairs if self._close(*p, horizon)])
            now = self._sub[1]
            tight = sorted({a for p in now for a in p} | set(near_shape))
            for a in busy:
                if a not in tight:
                    kernel(self._steppers[a], tables[a], s, s1, self._n + s)
            for u in range(s, s1):
                for a, c in now:
                    self._pair(a, c, between)
                for a in near_shape:
                    self._node_contacts(a, impulse)
                for a in tight:
                    one(self._steppers[a], tables[a], u, u + 1, self._n + u)
            s = s1

    def _node_contacts(self, a: int, impulse) -> None:
        """One step's contacts of animal a's nodes with the objects (``contacts.node_contacts``;
        impulses recorded in ``impulse[a]``, the balls' reactions in ``_bforce``)."""
        self._tested.add(a)
        o0, o1 = self._off[a], self._off[a + 1]
        node_contacts(
            self._pos[o0:o1], self._vel[o0:o1], self._mass[a], self.node_radius, self._bpos,
            self._bvel, self._bpar, self._skind, self._scenter, self._ssize, self._ball_obj,
            self._static_obj, self.dt, self._w, self._zeta, self._mu, self._bforce, impulse[a],
        )  # fmt: skip

    def _balls(self, steps: int) -> None:
        balls_step(
            self._bpos, self._bvel, self._bpar, self._bforce, self._med64, self.current,
            self._skind, self._scenter, self._ssize, self.dt, steps, self._w, self._zeta, self._mu,
        )  # fmt: skip

    def _contact_step(self, tables, s: int, impulse, pairs=(), between=None) -> None:
        self._bforce[:] = 0.0
        for a, c in pairs:
            self._pair(a, c, between)
        for a in range(len(self.animals)):
            self._node_contacts(a, impulse)
        self._animals_run(tables, s, s + 1)
        if len(self.balls):
            self._balls(1)

    def _heads(self) -> np.ndarray:
        """Return the animals' head nodes (animals, B, 3) in m."""
        return self._pos[self._head_rows].transpose(0, 2, 1).astype(np.float64)

    def _food_update(self, at: int) -> None:
        """At step ``at`` of the world's grid (where the animals now are): drift
        the food with the current since the mark; a particle is eaten when a head's path
        since the mark (relative to the particle, a straight segment) came within its
        radius. The mark moves here."""
        f0 = self._food.copy()
        self._food += self.current * (at - self._mark) * self.dt
        heads = self._heads()
        eaten_on_path(self._mark_heads, heads, f0, self._food, self._food_radius, self._eaten)
        self._mark, self._mark_heads = at, heads
