"""A world: animals of any kinds plus passive objects in one medium, stepped in lockstep.

``World([shark, Ball(...), Box(...)], medium="sea", batch=B)`` holds B copies (candidates)
of the scene. ``world.step(seconds, activations)`` advances them all with the batched animal
kernel (the same compiled code as ``physics.simulate``, so a lone animal stepped in slices
follows the open-loop trajectory) and moves the objects; a node against a fixed shape feels a
penalty force, a ball is resolved by impulses with restitution below one (``physics.contacts``),
and animals push each other with dissipative penalties (a node against the other's skin,
``physics.bodycontact``); each step() returns their record. ``world.state`` is a
frozen value that can be copied, saved and restored, so a planner can look ahead from "now".

The parts: how the animals and contacts are stepped (``stepping``), which animals may touch
what and so how a slice is stepped (``broadphase``), the food (``food``), the values a world
takes and gives (``worldstate``). What the world decides for a stretch of steps (which animals
may touch what, which food was eaten) it decides on its own grid of slices (every
``MAX_SLICE`` steps from t = 0), never per call: stepping 0.1 s at once or as 0.05 + 0.05 s
gives the same world bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.physics.bodycontact import surface_reach
from zoetic.physics.broadphase import BroadPhase
from zoetic.physics.food import Pantry
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.model import compile_model
from zoetic.physics.objects import Ball, Box, Cylinder, Food, Solids
from zoetic.physics.stepping import PARALLEL_FROM, ContactSlices, Drive
from zoetic.physics.worldstate import Animal, Contacts, WorldState, placed_pose

__all__ = ["PARALLEL_FROM", "Animal", "Contacts", "World", "WorldState", "placed_pose"]

F32 = np.float32
MAX_SLICE = 20  # steps between reach checks while objects are about


class World:
    """Animals and passive objects in one medium, B copies stepped together.

    members: Bodies (placed at their start offset), ``Animal`` placements, and ``Ball``,
    ``Box``, ``Cylinder`` and ``Food`` objects, in any order. medium: a Medium or a name
    (default the first animal's). dt: default the smallest of the animals' own. current:
    water velocity (m/s) that carries food and drags balls. animal_contact: animals push
    each other apart when they touch (``physics.bodycontact``; default True). node_radius:
    the radius of a node (and an animal's skin) in contacts; contact_steps, damping_ratio,
    friction: a node-object contact's duration in steps, damping ratio and Coulomb friction.
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
        self._sort(members)
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
        self._solids = Solids(self.objects, self.batch)
        self.balls, self.statics = self._solids.balls, self._solids.statics
        self.foods = [o for o in self.objects if isinstance(o, Food)]
        self._pantry = Pantry(self.foods, self.batch, self.current, self.dt)
        self._object_names = tuple(o.name for o in self.objects)
        self._lay_out_animals()
        # animal-animal contact: only where every animal has a skin
        self._touchy = bool(animal_contact) and len(self.animals) > 1
        self._touchy &= all(len(b.faces) for b in self.bodies)
        reach = [surface_reach(b) for b in self.bodies]
        self._broad = BroadPhase(
            self._pos,
            self._vel,
            self._off,
            self._views,
            reach,
            self.node_radius,
            self.dt,
            self._solids,
            self._touchy,
        )
        models = [compile_model(b, self.medium, self.dt) for b in self.bodies]
        state = (self._pos, self._vel, self._fs_all, self._failed_all)
        self._drive = Drive(self.bodies, models, self._views, state, self._off[:-1])
        self._chunk = self._drive.chunk
        self._contacts = ContactSlices(
            self._drive,
            self._broad,
            self._solids,
            self.bodies,
            self.medium,
            self.current,
            self.dt,
            self.node_radius,
            contact_steps,
            damping_ratio,
            friction,
        )
        self._n = 0
        self.restore(self.initial_state())

    def _sort(self, members) -> None:
        """Set ``animals`` (placements) and ``objects`` from the members, or refuse them."""
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

    def _lay_out_animals(self) -> None:
        """Allocate the animals' state: one (N_total, 3, B) float32 array of positions and one
        of velocities, each animal a contiguous block of rows (``offsets``), and each animal's
        failure marks (the kernel's ``fs``, >= 0 a dead lane; ``failed``, the step)."""
        sizes = [b.n_nodes for b in self.bodies]
        self._off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self._pos = np.zeros((int(self._off[-1]), 3, self.batch), dtype=F32)
        self._vel = np.zeros_like(self._pos)
        rows = zip(self._off[:-1], self._off[1:], strict=True)
        self._views = [(self._pos[o0:o1], self._vel[o0:o1]) for o0, o1 in rows]
        # one row an animal (views of one array each, so that a lane group reads them all)
        self._fs_all = -np.ones((len(self.bodies), self.batch), dtype=np.int64)
        self._failed_all = -np.ones_like(self._fs_all)
        self._fs, self._failed = list(self._fs_all), list(self._failed_all)
        heads = [o + b.head for o, b in zip(self._off[:-1], self.bodies, strict=True)]
        self._head_rows = np.array(heads, int)
        self._lone = len(self.animals) == 1
        self._no_contacts = Contacts(
            tuple(np.zeros((self.batch, b.n_nodes, 0, 3)) for b in self.bodies), ()
        )

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
            0,
            self.dt,
            tuple(pos),
            tuple(vel),
            tuple(-np.ones(B, dtype=np.int64) for _ in self.animals),
            rows([b.position for b in self.balls], nb),
            rows([b.velocity for b in self.balls], nb),
            rows([f.position for f in self.foods], nf),
            np.zeros((B, nf), dtype=bool),
        )

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
            self._n,
            self.dt,
            pos,
            vel,
            tuple(f.copy() for f in self._failed),
            self.ball_positions,
            self.ball_velocities,
            self.food_positions,
            self.food_eaten,
        )

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
        self._solids.pos[:, :, sel] = np.asarray(state.ball_positions).transpose(1, 2, 0)
        self._solids.vel[:, :, sel] = np.asarray(state.ball_velocities).transpose(1, 2, 0)
        self._broad.forget()  # the broad phase decides afresh from here
        if lanes is None:
            if state.batch != self.batch:
                raise SimulationError(
                    f"the state holds {state.batch} lanes; this world {self.batch}"
                )
            self._n = int(state.step)
            self._pantry.restore(state.food_positions, state.food_eaten, self._n, self._heads())
        else:  # these lanes' food held at the mark, so that it lies where the state puts it now
            self._pantry.restore_lanes(
                sel, state.food_positions, state.food_eaten, self._n, self._heads()
            )

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
        return self._solids.pos.transpose(2, 0, 1).copy()

    @property
    def ball_velocities(self) -> np.ndarray:
        """Return the balls' velocities (B, K, 3) in m/s."""
        return self._solids.vel.transpose(2, 0, 1).copy()

    @property
    def food_positions(self) -> np.ndarray:
        """Return the food particles (B, F, 3) in m."""
        return self._pantry.positions(self._n)

    @property
    def food_eaten(self) -> np.ndarray:
        """Return (B, F) bools: which food particles have been eaten."""
        return self._pantry.eaten.copy()

    # ---- stepping ---------------------------------------------------------------------
    def steps_for(self, seconds: float) -> int:
        """Return how many time steps ``step(seconds)`` takes from now (the clock stays on
        the dt grid: 30 steps of 1/30 s with dt 5 ms take 200 steps in all)."""
        return int(round((self._n * self.dt + seconds) / self.dt)) - self._n

    def step(self, seconds: float, activations=None) -> Contacts:
        """Advance the world by ``seconds`` (rounded to whole time steps) and return the
        contacts it made.

        activations: for each animal (a list, a dict by animal name, or one array for a lone
        animal) an array (A,) or (B, A) held over the slice, or (B, T, A) one row a step with
        T = ``steps_for(seconds)``; None holds every actuator at 0.

        How the steps are split into calls changes nothing: the broad phase decides once for
        each slice of the world's grid (``MAX_SLICE`` steps; the pairs of animals again every
        ``stepping.SUB_SLICE``) and keeps its decision for the rest of the slice, and food is
        tested and drifted at the grid's steps (a particle eaten during a slice shows as eaten
        from the slice's last step on). The returned contacts are this call's.
        """
        steps = int(round((self._n * self.dt + seconds) / self.dt)) - self._n  # steps_for
        if steps < 0:
            raise SimulationError(f"cannot step back in time ({seconds} s)")
        if self._lone and type(activations) is np.ndarray:
            tables = [self._drive.table(0, activations, steps)]
            if not self.objects:  # one animal alone: the shortest path (closed-loop slices)
                self._drive.run(0, tables[0], 0, steps, self._n)
                self._n += steps
                return self._no_contacts
        else:
            tables = self._drive.tables(activations, steps)
        if not self.objects and not self._touchy:  # nothing to touch, nothing to eat
            self._drive.run_all(tables, 0, steps, self._n)
            self._n += steps
            return self._no_contacts
        return self._step_slices(tables, steps)

    def _step_slices(self, tables, steps: int) -> Contacts:
        """``step`` with objects about or animals that may touch: slice by slice of the
        world's grid, each stepped as the broad phase decides, the food tested at its ends."""
        # the impulses of the animals tested against the objects, made at each one's first test
        impulse: dict[int, np.ndarray] = {}
        self._contacts.tested = set()
        n_an = len(self.animals)
        between = np.zeros((self.batch, n_an, n_an)) if self._touchy else None
        decide = self._solids.any or self._touchy
        n = self._n
        t = 0
        while t < steps:
            # the world's slices end on its own grid (every MAX_SLICE steps from t = 0), not
            # where the caller's steps end: a caller may split a slice, never change it
            end = (n + t) // MAX_SLICE * MAX_SLICE + MAX_SLICE
            t1 = min(steps, end - n)
            mode, pairs, near_now = self._broad.decide(end, n + t) if decide else ("free", [], None)
            if mode == "lockstep":  # balls couple everything, or some node is near a shape
                self._contacts.lockstep(tables, t, t1, n, impulse, pairs, between)
            elif mode == "apart":
                self._contacts.apart(tables, t, t1, n, impulse, near_now, pairs, between)
            else:
                self._drive.run_all(tables, t, t1, n + t)
                if len(self.balls):
                    self._solids.force[:] = 0.0
                    self._contacts.balls(t1 - t)
            t = t1
            if self.foods and n + t == end:  # the food's mark, where the animals now are
                self._pantry.update(end, self._heads())
        self._n += steps
        return Contacts(
            self._impulses(impulse),
            self._object_names,
            between if between is not None and between.any() else None,
            tuple(sorted(self._contacts.tested)),
        )

    def _impulses(self, found: dict[int, np.ndarray]) -> tuple[np.ndarray, ...]:
        """Return each animal's impulses (B, N, O, 3) from those ``found`` (N, S, 3, B) over
        the objects a node can touch (``Solids.columns``): an animal that touched nothing gets
        a read-only view of one zero (one a shape, made once), so that the memory follows the
        touches, not the animals times the objects (food included)."""
        out = list(self._zero_impulses)
        cols = self._solids.columns
        for a, got in found.items():
            if got.any():
                full = np.zeros(out[a].shape)
                full[:, :, cols] = got.transpose(3, 0, 1, 2)
                out[a] = full
        return tuple(out)

    @cached_property
    def _zero_impulses(self) -> tuple[np.ndarray, ...]:
        """Each animal's impulses when it touched nothing: read-only zero views (B, N, O, 3),
        one a shape."""
        zeros: dict[tuple[int, ...], np.ndarray] = {}
        for body in self.bodies:
            shape = (self.batch, body.n_nodes, len(self.objects), 3)
            zeros.setdefault(shape, np.broadcast_to(0.0, shape))
        return tuple(zeros[(self.batch, b.n_nodes, len(self.objects), 3)] for b in self.bodies)

    def _heads(self) -> np.ndarray:
        """Return the animals' head nodes (animals, B, 3) in m."""
        return self._pos[self._head_rows].transpose(0, 2, 1).astype(np.float64)
