"""How a World's animals are stepped: the kernel over each animal's lanes in place (``Drive``),
and the slices in which contacts are resolved step by step (``ContactSlices``).

Each animal's lanes are stepped by the same compiled kernel as ``physics.simulate`` (a
``kernel.Stepper`` over the world's own state arrays), so a lone animal stepped in slices
follows the open-loop trajectory; the animals that share a model (a tank's fishes of one body)
step as the lanes of one call (``lanes.LaneGroup``), each lane as it would alone. Where the
broad phase (``broadphase``) finds a node within reach of an object or of another animal, the
contacts are resolved every time step: a node against a fixed shape feels a penalty force and a
ball is resolved by impulses (``physics.contacts``), and animals push each other with
dissipative penalties (``physics.bodycontact``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.bodies import Body
from zoetic.errors import SimulationError
from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.balls import balls_step
from zoetic.physics.bodycontact import CONTACT_STEPS, pairs_contacts
from zoetic.physics.broadphase import BroadPhase, near
from zoetic.physics.contacts import node_contacts
from zoetic.physics.kernel import advance_one, advance_serial, chunk_scratch, make_stepper
from zoetic.physics.lanes import LaneGroup, fingerprint
from zoetic.physics.media import Medium
from zoetic.physics.model import Model
from zoetic.physics.objects import Solids
from zoetic.physics.simulate import VMAX, chunk_size

fresh_numba_cache()

F32 = np.float32
# lane-steps per kernel call from which the thread pool is worth its launch (and its barrier,
# which is slow on a busy host): 64 gym lanes x 10 steps run faster on one thread
PARALLEL_FROM = 8192
SUB_SLICE = 5  # steps between the checks of animals that may touch one another


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


_KERNELS: dict = {}


def _kernel(parallel: bool):
    """Return the stateful kernel's entry point, threaded or serial (compiled, or loaded from
    numba's cache, once per process and only when first needed)."""
    if parallel not in _KERNELS:
        from zoetic.physics.kernel import advance_entry

        _KERNELS[parallel] = advance_entry(parallel)
    return _KERNELS[parallel]


class Drive:
    """The kernel side of a world: one Stepper per animal (its float32 model over its views
    (pos, vel) of the world's state, its failure marks ``fs`` and ``failed``), the animals
    that share a model stepped together as lanes (``lanes.LaneGroup``), the activation tables
    they read, and the kernel entry, threaded when the work is worth the pool.

    state: the world's (pos, vel (N_all, 3, B), fs, failed (animals, B)) arrays; first: each
    animal's first row."""

    def __init__(self, bodies: list[Body], models: list[Model], views, state, first) -> None:
        self.bodies = bodies
        pos, vel, fs, failed = state
        self.batch = batch = pos.shape[2]
        self.serial = _kernel(False)
        self.parallel = _kernel(True) if batch > 8 else self.serial
        self.chunk = chunk_size(batch)
        self.steppers = [
            make_stepper(m, p, v, f, fl, self.chunk, VMAX)
            for m, (p, v), f, fl in zip(models, views, fs, failed, strict=True)
        ]
        self.kernels = (self.serial, _kernel(True), PARALLEL_FROM)
        keys: dict[tuple, list[int]] = {}
        for a, m in enumerate(models):
            keys.setdefault(fingerprint(m), []).append(a)
        self.groups = [
            LaneGroup(idx, models[idx[0]], (*state, batch), first, bodies[idx[0]].n_actuators)
            for idx in keys.values()
        ]
        self.group_of = [0] * len(bodies)  # each animal's group
        for g, grp in enumerate(self.groups):
            for a in grp.members:
                self.group_of[a] = g
        self._tables: dict[tuple[int, int], tuple[np.ndarray, tuple]] = {}
        self._wide: dict[tuple[int, int], np.ndarray] = {}  # (group, steps) -> its table

    def kernel(self, steps: int):
        """Return the kernel entry for a call of ``steps`` steps of every lane."""
        return self.parallel if self.batch * steps >= PARALLEL_FROM else self.serial

    def run(self, a: int, table: np.ndarray, t0: int, t1: int, base: int) -> None:
        """Step animal a (alone in its group) through rows t0 .. t1 of its table (the world's
        step ``base`` at t0)."""
        kernel = self.parallel if self.batch * (t1 - t0) >= PARALLEL_FROM else self.serial
        kernel(self.steppers[a], table, t0, t1, base)

    def run_all(self, tables, t0: int, t1: int, base: int) -> None:
        """Step every animal through rows t0 .. t1 of its table."""
        self.run_some(range(len(self.bodies)), tables, t0, t1, base)

    def run_some(self, animals, tables, t0: int, t1: int, base: int) -> None:
        """Step the ``animals`` (in order) through rows t0 .. t1 of their tables: an animal
        alone in its group by its own stepper, the others of a group as lanes of one call."""
        picked: dict[int, list[int]] = {}
        for a in animals:
            picked.setdefault(self.group_of[a], []).append(a)
        for g, members in picked.items():
            grp = self.groups[g]
            if len(grp.members) == 1:
                self.run(members[0], tables[members[0]], t0, t1, base)
            else:
                grp.run(
                    self.kernels,
                    members,
                    self._wide[(g, tables[members[0]].shape[0])],
                    t0,
                    t1,
                    base,
                )

    def tables(self, activations, steps: int) -> list[np.ndarray]:
        """Return each animal's table for ``steps`` steps (``World.step``'s activations)."""
        return [self.table(a, u, steps) for a, u in enumerate(self._per_animal(activations))]

    def table(self, a: int, acts, steps: int) -> np.ndarray:
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
            out = self._view(a, steps)
            self._tables[(a, steps)] = (out, (self.batch, steps, na))
        else:
            out = cached[0]
        if acts is None or na == 0:
            out[...] = 0.0
            return out
        u3 = self._rows(body, np.asarray(acts), steps)
        if not fill_table(u3, out):
            raise SimulationError(f"activations for the {body.name} contain non-finite values")
        return out

    def _view(self, a: int, steps: int) -> np.ndarray:
        """Return animal a's (T, A, B) columns of its group's table for ``steps`` steps (the
        whole table, C-contiguous, for an animal alone in its group)."""
        g = self.group_of[a]
        grp = self.groups[g]
        wide = self._wide.get((g, steps))
        if wide is None:
            shape = (steps, grp.n_act, len(grp.members) * self.batch)
            wide = self._wide[(g, steps)] = np.zeros(shape, F32)
        c = grp.column[a] * self.batch
        return wide if len(grp.members) == 1 else wide[:, :, c : c + self.batch]

    def _rows(self, body: Body, u: np.ndarray, steps: int) -> np.ndarray:
        """Return activations (A,), (B, A) or (B, T, A) as (B|1, T|1, A), or refuse them."""
        na = body.n_actuators
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
        return u if u.ndim == 3 else u[:, None, :] if u.ndim == 2 else u[None, None, :]

    def _per_animal(self, activations) -> list:
        n = len(self.bodies)
        if n == 1 and isinstance(activations, np.ndarray):
            return [activations]
        if activations is None:
            return [None] * n
        if isinstance(activations, dict):
            names = [b.name for b in self.bodies]
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


class ContactSlices:
    """The steps of a world in which contacts are resolved, one step at a time: the pairs of
    animals that may touch push each other, the nodes of the animals near an object touch it,
    the kernel takes the step, and the balls move.

    contact_steps, damping_ratio, friction: a node-object contact's duration in steps, its
    damping ratio (which also sets the balls' restitution) and Coulomb friction (``World``).
    """

    # a lone animal's lockstep runs as one compiled call (``lone_contact_steps``); False: step
    # by step from Python, as every other world (the same arithmetic in the same order)
    compiled_lone = True
    # within a lone animal's lockstep slice, the reach is checked again every ``lone_every``
    # steps of the world's grid (the broad phase's ``near`` over that sub-slice's horizon): a
    # sub-slice in which no node can reach an object is one kernel call and the balls' steps,
    # without contact tests (which would find nothing); 0: every step with its contacts
    lone_every = SUB_SLICE

    def __init__(
        self,
        drive: Drive,
        broad: BroadPhase,
        solids: Solids,
        bodies: list[Body],
        medium: Medium,
        current: np.ndarray,
        dt: float,
        node_radius: float,
        contact_steps: int,
        damping_ratio: float,
        friction: float,
    ) -> None:
        self.drive, self.broad, self.solids = drive, broad, solids
        self.views = broad.views
        self.mass = [b.mass.astype(np.float64) for b in bodies]
        self.faces = [np.ascontiguousarray(b.faces, dtype=np.int64) for b in bodies]
        # every animal's masses and triangles stacked, for the pairs' contacts in one call
        self.mass_all = np.concatenate(self.mass)
        self.faces_all = np.concatenate([f.reshape(-1, 3) for f in self.faces])
        self.face_off = np.cumsum([0] + [len(f) for f in self.faces]).astype(np.int64)
        self.med64 = medium.as_array()
        self.current = current
        self.dt = dt
        self.node_radius = node_radius
        self.w = np.pi / (contact_steps * dt)
        self.w_body = np.pi / (CONTACT_STEPS * dt)
        self.zeta = float(damping_ratio)
        self.mu = float(friction)
        self.tested: set[int] = set()  # the animals whose node contacts a step computed
        # steps of lone lockstep slices taken without contact tests (``lone_contact_steps``)
        self.untested_steps = 0

    def lockstep(self, tables, t: int, t1: int, n: int, impulse, pairs, between) -> None:
        """Step steps t .. t1 of a call that started at the world's step n, every animal one
        step at a time with its contacts (impulses into ``impulse``, by animal as
        ``node_contacts`` makes them, those between animals into ``between``)."""
        if (
            self.compiled_lone
            and len(self.views) == 1
            and not pairs
            and self.drive.batch < PARALLEL_FROM
        ):
            self._lone_lockstep(tables[0], t, t1, n, impulse)
            return
        pair_rows = np.array(pairs, np.int64).reshape(-1, 2)
        for s in range(t, t1):
            self.solids.force[:] = 0.0
            self.pairs(pair_rows, between)
            for a in range(len(self.views)):
                self.node_contacts(a, impulse)
            self.drive.run_all(tables, s, s + 1, n + s)
            if len(self.solids.balls):
                self.balls(1)

    def _lone_lockstep(self, table, t: int, t1: int, n: int, impulse) -> None:
        """``lockstep`` for a lone animal on one thread: the same steps in the same order, its
        contacts, one kernel step and the balls' step, looped in one compiled call
        (``lone_contact_steps``) instead of three calls a step from Python."""
        self.tested.add(0)
        p = self.views[0][0]
        s = self.solids
        got = impulse.get(0)
        if got is None:
            got = impulse[0] = np.zeros((p.shape[0], len(s.columns), 3, p.shape[2]))
        self.untested_steps += lone_contact_steps(
            self.drive.steppers[0],
            table,
            t,
            t1,
            n,
            self.mass[0],
            self.node_radius,
            (s.pos, s.vel, s.par, s.force, s.kind, s.center, s.size, s.ball_col, s.static_col),
            (self.med64, self.current, self.dt, self.w, self.zeta, self.mu),
            len(s.balls) > 0,
            got,
            self.lone_every,
        )

    def apart(
        self, tables, t: int, t1: int, n: int, impulse, near_now: np.ndarray, pairs=(), between=None
    ) -> None:
        """Step steps t .. t1 of animals that no balls couple: the animals near no fixed shape
        (``near_now``) and in no pair in one kernel call, those near one one step at a time
        with their contacts; the animals of ``pairs`` (that may touch one another) in
        lockstep, one step at a time (``_pairs_apart``). Animals that share a model step as
        lanes of one call (``Drive.run_some``)."""
        busy = {a for p in pairs for a in p}
        alone = [a for a in range(len(self.views)) if a not in busy]
        self.drive.run_some([a for a in alone if not near_now[a]], tables, t, t1, n + t)
        near = [a for a in alone if near_now[a]]
        if busy:
            self._pairs_apart(
                tables, t, t1, n, impulse, near_now, pairs, (sorted(busy), near), between
            )
            return
        for s in range(t, t1):
            for a in near:
                self.node_contacts(a, impulse)
            self.drive.run_some(near, tables, s, s + 1, n + s)

    def _pairs_apart(self, tables, t, t1, n, impulse, near_now, pairs, who, between) -> None:
        """``apart`` for ``who``: the animals of ``pairs`` and those in no pair but near a
        fixed shape. The pairs are checked again every SUB_SLICE steps (on the world's grid,
        as the slices); an animal of a pair not close now takes the sub-slice in one kernel
        call (the pairs' contact impulses recorded in ``between``)."""
        busy, near = who
        near_shape = [a for a in busy if self.solids.any and near_now[a]]
        s = t
        while s < t1:
            end = (n + s) // SUB_SLICE * SUB_SLICE + SUB_SLICE
            s1 = min(t1, end - n)
            now = self.broad.close_now(pairs, end, n + s)
            tight = sorted({int(a) for p in now for a in p} | set(near_shape))
            self.drive.run_some([a for a in busy if a not in tight], tables, s, s1, n + s)
            touch = near_shape + near
            step = sorted(tight + near)
            for u in range(s, s1):
                self.pairs(now, between)
                for a in touch:
                    self.node_contacts(a, impulse)
                self.drive.run_some(step, tables, u, u + 1, n + u)
            s = s1

    def pairs(self, pairs: np.ndarray, between: np.ndarray) -> None:
        """One step's contact impulses between the animals of each pair (P, 2), in order
        (recorded in ``between``)."""
        if len(pairs):
            pos, vel = self.broad.pos, self.broad.vel
            pairs_contacts(
                pos,
                vel,
                self.broad.off,
                self.mass_all,
                self.faces_all,
                self.face_off,
                pairs,
                self.node_radius,
                self.dt,
                self.w_body,
                self.zeta,
                between,
            )

    def node_contacts(self, a: int, impulse: dict[int, np.ndarray]) -> None:
        """One step's contacts of animal a's nodes with the objects (``contacts.node_contacts``;
        impulses recorded in ``impulse[a]``, (N, S, 3, B) over the ``solids.columns``, made at
        the animal's first test, the balls' reactions in ``solids.force``)."""
        self.tested.add(a)
        p, v = self.views[a]
        s = self.solids
        got = impulse.get(a)
        if got is None:
            got = impulse[a] = np.zeros((p.shape[0], len(s.columns), 3, p.shape[2]))
        node_contacts(
            p,
            v,
            self.mass[a],
            self.node_radius,
            s.pos,
            s.vel,
            s.par,
            s.kind,
            s.center,
            s.size,
            s.ball_col,
            s.static_col,
            self.dt,
            self.w,
            self.zeta,
            self.mu,
            s.force,
            got,
        )

    def balls(self, steps: int) -> None:
        """Move the balls ``steps`` steps under the force the animals put on them."""
        s = self.solids
        balls_step(
            s.pos,
            s.vel,
            s.par,
            s.force,
            self.med64,
            self.current,
            s.kind,
            s.center,
            s.size,
            self.dt,
            steps,
            self.w,
            self.zeta,
            self.mu,
        )


@njit(cache=True)
def lone_contact_steps(st, table, t, t1, n, mass, radius, solids, medium, balls, impulse, every):
    """Step a lone animal's Stepper ``st`` through rows t .. t1 of its ``table`` (the world's
    step n at row 0), one step at a time: the balls' contact forces cleared, the nodes'
    contacts with the objects (``node_contacts``, impulses into ``impulse``), one kernel step
    on this thread (``advance_one``, its scratch made once), then the balls' step if there
    are ``balls``. ``solids``: the Solids' pos, vel, par, force, kind, center, size,
    ball_col, static_col; ``medium``: the medium's array, the current, dt, w, zeta, mu (as
    ``ContactSlices``).

    Every ``every`` steps of the world's grid (0: never), a sub-slice that this call holds
    whole and in which no node can reach a ball or a fixed shape (the broad phase's ``near``
    over its horizon) is stepped as a free slice is: one kernel call (``advance_serial``) and
    the balls' steps under no force. The contact tests it skips would have found nothing, so
    the steps are the same as one at a time, but for the kernel's blow-up checks (every 8
    steps of a call, as in a free slice, not every step). Return how many steps were taken
    so, without contact tests."""
    bpos, bvel, bpar, bforce, kind, center, size, ball_col, static_col = solids
    med, current, dt, w, zeta, mu = medium
    scratch = chunk_scratch(st)
    untested = 0
    s = t
    while s < t1:
        if (
            every > 0
            and (n + s) % every == 0
            and s + every <= t1
            and not near(st.pos, st.vel, radius, bpos, bvel, bpar, kind, center, size, every * dt)
        ):
            advance_serial(st, table, s, s + every, n + s)
            if balls:
                bforce[:] = 0.0
                balls_step(
                    bpos, bvel, bpar, bforce, med, current, kind, center, size, dt, every, w,
                    zeta, mu,
                )  # fmt: skip
            s += every
            untested += every
            continue
        bforce[:] = 0.0
        node_contacts(
            st.pos, st.vel, mass, radius, bpos, bvel, bpar, kind, center, size, ball_col,
            static_col, dt, w, zeta, mu, bforce, impulse,
        )  # fmt: skip
        advance_one(st, table, s, n + s, scratch)
        if balls:
            balls_step(
                bpos, bvel, bpar, bforce, med, current, kind, center, size, dt, 1, w, zeta, mu
            )
        s += 1
    return untested
