"""The objective E = mu1 * E_u + mu2 * E_v of section 2.2, evaluated for a batch of candidates.

E_u is discretised on the controller's M nodes exactly as section 4.2 writes it:
    E_u = sum_i sum_j  nu1 / (2 h^2) (u_i^{j+1} - u_i^j)^2
                     + nu2 / (2 h^4) (u_i^{j+1} - 2 u_i^j + u_i^{j-1})^2
with h the time between nodal parameters (a frequency-domain controller is sampled at the same
M node times). E_v is a weighted sum of named terms (``zoetic.tasks.terms.TERMS``), which see
the motion recorded at the task's ``record_hz``.
A candidate whose simulation blew up scores +inf and is counted, never raised.

A task with several starts (``[[starts]]``) plays each candidate from every start, all in one
batched kernel call (candidate k from start s is lane k * S + s), scores each rollout with the
same terms relative to its own start, and takes the mean over the starts: E = mu1 * E_u +
mu2 * mean_s E_v(s). A candidate that blows up from any start scores +inf.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from zoetic.bodies import Body
from zoetic.control import Controller
from zoetic.errors import ZoeticError
from zoetic.physics import Medium, State, get_medium, simulate
from zoetic.tasks import Task, start_states
from zoetic.tasks.terms import BodyFrame, Signals, evaluate_terms, term_names


def control_energy_xp(xp, u_nodes, h: float, nu1: float, nu2: float):
    """Return E_u (K,) for nodal values u (K, A, M) spaced h seconds apart, with module xp."""
    e = xp.zeros(u_nodes.shape[0])
    if nu1:
        d1 = u_nodes[..., 1:] - u_nodes[..., :-1]
        e = e + nu1 / (2 * h**2) * xp.sum(d1**2, axis=(-2, -1))
    if nu2:
        d2 = u_nodes[..., 2:] - 2 * u_nodes[..., 1:-1] + u_nodes[..., :-2]
        e = e + nu2 / (2 * h**4) * xp.sum(d2**2, axis=(-2, -1))
    return e


def control_energy(u_nodes: np.ndarray, h: float, nu1: float, nu2: float) -> np.ndarray:
    """Return E_u (K,) for nodal values u (K, A, M) spaced h seconds apart."""
    return control_energy_xp(np, np.asarray(u_nodes, float), h, nu1, nu2)


def signals(
    task: Task,
    body: Body,
    positions,
    activations=None,
    dt: float = 0.05,
    medium: Medium | str | None = None,
    xp=np,
    frame: BodyFrame | None = None,
) -> Signals:
    """Return what a task's terms see of recordings (K, R, N, 3) taken ``dt`` seconds apart."""
    k, r = positions.shape[:2]
    if activations is None:
        activations = xp.zeros((k, r, body.n_actuators))
    level = get_medium(medium or body.medium).water_level
    return Signals(
        xp,
        frame or BodyFrame.of(body),
        positions,
        activations,
        np.arange(r) * dt,
        level,
        task.horizon,
    )


def heading_angles(body: Body, positions: np.ndarray) -> np.ndarray:
    """Return the unwrapped heading (rad, left turns positive) over time, (K, R)."""
    return Signals(np, BodyFrame.of(body), positions, None, np.zeros(0), 0.0, 1.0).heading


def motion_terms(
    task: Task,
    body: Body,
    positions: np.ndarray,
    horizon: float | None = None,
    activations=None,
    dt: float = 0.05,
    medium=None,
) -> dict:
    """Return each term's raw value (K,) for recorded positions (K, R, N, 3), by term name."""
    s = signals(task, body, positions, activations, dt, medium)
    if horizon is not None:
        s.horizon = float(horizon)
    return dict(zip(term_names(task.terms), evaluate_terms(np, s, task.terms), strict=True))


@dataclass(frozen=True)
class Evaluation:
    """Scores of a batch: E, its two parts, each motion term, and who blew up."""

    E: np.ndarray
    E_u: np.ndarray
    E_v: np.ndarray
    terms: dict  # each term's value (K,), the mean over the starts
    failed: np.ndarray
    per_start: np.ndarray | None = None  # E (K, S) from each start; None for a single start


def merge(parts: list[Evaluation]) -> Evaluation:
    """Return one Evaluation from the Evaluations of consecutive chunks of a batch."""
    cat = np.concatenate
    return Evaluation(
        cat([p.E for p in parts]),
        cat([p.E_u for p in parts]),
        cat([p.E_v for p in parts]),
        {k: cat([p.terms[k] for p in parts]) for k in parts[0].terms},
        cat([p.failed for p in parts]),
        None if parts[0].per_start is None else cat([p.per_start for p in parts]),
    )


class Objective:
    """Scores parameter vectors of one controller family on one task for one body."""

    def __init__(
        self,
        task: Task,
        body: Body,
        template: Controller,
        medium: Medium | str | None = None,
        dt: float | None = None,
        start: State | None = None,
        coupling: str = "none",
        fins: str = "held",
        harmonic_bound: float | None = None,
    ):
        self.task = task
        self.body = body
        self.template = template
        self.medium = get_medium(medium or body.medium)
        self.dt = float(dt or body.dt)
        self.steps = int(round(task.horizon / self.dt))
        self.record_every = max(1, int(round(1.0 / (task.record_hz * self.dt))))
        # the start states, one per row (S, N, 3): the task's starts, or the one given
        self.starts = start if start is not None else start_states(task, body, self.medium)
        self.frame = BodyFrame.of(body)
        times = np.arange(self.steps) * self.dt
        self._basis = template.design_matrix(times)  # (T, M): activations are linear in params
        self.node_times = np.linspace(0.0, task.horizon, task.nodes)
        self._node_basis = template.design_matrix(self.node_times)  # (M, M')
        self.h = task.horizon / (task.nodes - 1)
        m = self._basis.shape[1]
        self.full_shape = (body.n_actuators, m)
        self.coupling = coupling
        # bound on a frequency-domain controller's non-constant amplitudes (None: the
        # template's own, 0.5)
        self.harmonic_bound = harmonic_bound
        # pectoral fins are not learned with the gait (the fish model's separate pitch/roll
        # controllers drive them): held level, as the built-in wave holds them, unless "free"
        if fins not in ("held", "free"):
            raise ZoeticError(f"unknown fins mode {fins!r} (held or free)")
        is_fin = np.array([k == "fin" for k in body.actuator_kind], dtype=bool)
        self.held = np.flatnonzero(is_fin) if fins == "held" else np.zeros(0, dtype=int)
        self._one = np.linalg.lstsq(self._basis, np.ones(self.steps), rcond=None)[0]
        if coupling == "none":
            self.free = np.setdiff1d(np.arange(body.n_actuators), self.held)
        elif coupling == "wave":
            # a straight gait is mirror-symmetric: each right actuator does what its left
            # mirror does, later by the lag the animal's own wave puts between them (half a
            # stroke for the shark: one parameter set per pair instead of two)
            self.free, self._shift = self._wave_pairs(times)
        elif coupling == "antiphase":
            # the paper's Fig. 6 set-up: one signal per segment, the right side 1 - left
            if not body.is_mirror_symmetric:
                raise ZoeticError(f"the {body.name} has no mirror pairs to couple")
            self.free = np.array(
                [
                    k
                    for k, s in enumerate(body.actuator_side)
                    if s != "right" and k not in self.held
                ],
                dtype=int,
            )
        else:
            raise ZoeticError(f"unknown coupling {coupling!r} (none, wave or antiphase)")
        self.shape = (len(self.free), m)

    def _wave_pairs(self, times: np.ndarray) -> tuple[np.ndarray, dict]:
        """Return the free actuators and, per right actuator, (its left mirror, S (M, M)) with
        right coefficients = S @ left ones: the left signal delayed by the wave's lag."""
        body = self.body
        mirror = np.asarray(body.actuator_mirror)
        pairs = [
            (k, int(mirror[k]))
            for k, side in enumerate(body.actuator_side)
            if side == "right" and 0 <= mirror[k] != k and k not in self.held
        ]
        if not pairs:
            raise ZoeticError(f"the {body.name} has no mirror pairs to couple")
        phase = np.nan_to_num(np.asarray(body.wave_phase, float))
        shift = {}
        for k, j in pairs:
            lag = (phase[k] - phase[j]) / body.wave_frequency  # s
            delayed = self.template.design_matrix(times - lag)
            S = np.linalg.lstsq(self._basis, delayed, rcond=None)[0]
            if not np.allclose(self._basis @ S, delayed, atol=1e-6):
                raise ZoeticError(
                    f"coupling 'wave' needs a periodic (frequency-domain) controller: a "
                    f"{self.template.kind} controller delayed by {lag:g} s is another signal"
                )
            shift[k] = (j, S.T)
        free = np.array(
            [k for k in range(body.n_actuators) if k not in shift and k not in self.held], dtype=int
        )
        return free, shift

    @property
    def start(self) -> State:
        """The first start state (batch 1); setting it makes it the only start."""
        return State(self.starts.positions[:1], self.starts.velocities[:1])

    @start.setter
    def start(self, state: State) -> None:
        """Make ``state`` (batch S) the starts every candidate is played from."""
        self.starts = state

    @property
    def n_starts(self) -> int:
        """The number S of start states each candidate is played from."""
        return int(self.starts.positions.shape[0])

    @property
    def dimension(self) -> int:
        """The length of a candidate vector: free actuators times parameters per actuator."""
        return int(np.prod(self.shape))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the (lower, upper) bounds of the free parameters."""
        lo, hi = (b.reshape(self.full_shape)[self.free].ravel() for b in self.template.bounds())
        if self.harmonic_bound is not None and self.template.kind == "frequency":
            omega = np.tile(np.asarray(self.template.omega), self.shape[0])
            lo = np.where(omega == 0, lo, -self.harmonic_bound)
            hi = np.where(omega == 0, hi, self.harmonic_bound)
        return lo, hi

    def free_params(self, full: np.ndarray) -> np.ndarray:
        """Return the free parameters (dim,) of a full controller parameter vector."""
        return np.asarray(full, float).reshape(self.full_shape)[self.free].ravel()

    def params_of(self, controller: Controller) -> np.ndarray:
        """Return the free parameters (dim,) whose signals come nearest to ``controller``'s
        over the horizon (least squares on every step), within the bounds: a start for the
        search from a known gait (the animal's own wave plays exactly on a periodic basis of
        its frequency)."""
        u = controller.table(self.steps, self.dt)  # (T, A)
        coef = np.linalg.lstsq(self._basis, u, rcond=None)[0].T  # (A, M)
        lo, hi = self.bounds()
        return np.clip(self.free_params(coef), lo, hi)

    def full_coefficients(self, params: np.ndarray) -> np.ndarray:
        """Return the coefficients (K, A, M) of every actuator for free parameters (K, dim)."""
        free = np.asarray(params, dtype=np.float64).reshape(-1, *self.shape)
        if self.coupling == "none" and len(self.held) == 0:
            return free
        coef = np.empty((free.shape[0], *self.full_shape))
        coef[:, self.free] = free
        for k in self.held:  # level: the wave's held activation (the angle 0)
            coef[:, k] = self._one * np.nan_to_num(self.body.wave_held[k], nan=0.5)
        if self.coupling == "wave":
            index = {k: i for i, k in enumerate(self.free)}
            for k, (j, st) in self._shift.items():
                coef[:, k] = free[:, index[j]] @ st
        if self.coupling == "antiphase":
            mirror = self.body.actuator_mirror
            for k in self.free:
                if mirror[k] != k:
                    coef[:, mirror[k]] = self._one - free[:, list(self.free).index(k)]
        return coef

    def controller(self, params: np.ndarray) -> Controller:
        """Return the full controller for one free parameter vector."""
        return self.template.with_params(self.full_coefficients(params)[0].ravel())

    def tables(self, params: np.ndarray) -> np.ndarray:
        """Return activation tables (K, T, A) for parameter vectors (K, dim)."""
        return np.clip(self.actuator_signals(params).transpose(0, 2, 1), 0.0, 1.0)

    def actuator_signals(self, params: np.ndarray) -> np.ndarray:
        """Return each actuator's signal (K, A, T) for parameter vectors (K, dim), not yet
        clipped to [0, 1] as ``tables`` are (the simulator clips what it reads)."""
        coef = self.full_coefficients(params)
        k, a, m = coef.shape
        # one matrix product (K A, M) x (M, T): the same values as the sum over m, at a
        # fraction of einsum's cost
        return (coef.reshape(k * a, m) @ self._basis.T).reshape(k, a, -1)

    def recorded(self, signals: np.ndarray, n_records: int) -> np.ndarray:
        """Return the activations (K, R, A) applied at each recorded instant (``record_rows``)
        of actuator ``signals`` (K, A, T): ``tables``' rows there."""
        rows = self.record_rows(n_records)
        return np.clip(signals[:, :, rows].transpose(0, 2, 1), 0.0, 1.0)

    def control_cost(self, params: np.ndarray) -> np.ndarray:
        """Return E_u (K,) of parameter vectors, on the M node times."""
        coef = self.full_coefficients(params)
        u = np.einsum("jm,kam->kaj", self._node_basis, coef)
        return control_energy(u, self.h, self.task.nu1, self.task.nu2)

    def simulate(self, params: np.ndarray):
        """Return the Trajectory of each parameter vector over the task's horizon, from each
        start: K * S rollouts, candidate k from start s at k * S + s."""
        return self._run(self._lanes(self.tables(params)))

    def _lanes(self, tables: np.ndarray) -> np.ndarray:
        """Return the tables (K * S, T, A) of every candidate's rollout from every start."""
        s = self.n_starts
        return tables if s == 1 else np.repeat(tables, s, axis=0)

    def _run(self, lanes: np.ndarray):
        state = self.start_lanes(lanes.shape[0] // self.n_starts)
        return simulate(self.body, lanes, self.medium, self.dt, state, self.record_every)

    def record_rows(self, n_records: int) -> np.ndarray:
        """Return the activation-table rows applied at each recorded instant, (R,)."""
        return np.minimum(np.arange(n_records) * self.record_every, self.steps - 1)

    def rollout_key(self) -> tuple:
        """What the simulator must share, beside the body, to play this objective's rollouts in
        one batched call with another's (the kernel's lanes are independent: a lane moves the
        same in any batch): the medium, time step, steps and recording interval."""
        return (self.medium.name, self.dt, self.steps, self.record_every)

    def start_lanes(self, k: int) -> State:
        """Return the start state of each of K candidates' rollouts (K * S lanes)."""
        reps = (k, 1, 1)
        return State(np.tile(self.starts.positions, reps), np.tile(self.starts.velocities, reps))

    def evaluate(self, params: np.ndarray) -> Evaluation:
        """Return the Evaluation of a batch of parameter vectors (K, dim)."""
        params = np.atleast_2d(params)
        tables = self.tables(params)
        traj = self._run(self._lanes(tables))  # one kernel call for every candidate and start
        acts = tables[:, self.record_rows(traj.positions.shape[1])]
        return self.score(params, acts, traj.positions, traj.failed)

    def score(self, params, acts, positions, failed) -> Evaluation:
        """Return the Evaluation of a batch (K, dim) from its rollouts: the candidates'
        activations at the recorded instants ``acts`` (K, R, A) (``recorded``), the recorded
        ``positions`` (K * S, R, N, 3) and ``failed`` (K * S,) of candidate k from start s at
        k * S + s."""
        acts = self._lanes(acts)
        s = signals(
            self.task,
            self.body,
            positions,
            acts,
            self.record_every * self.dt,
            self.medium,
            frame=self.frame,
        )
        values = evaluate_terms(np, s, self.task.terms)
        e_v = sum(t.weight * v for t, v in zip(self.task.terms, values, strict=True))
        e_u = self.control_cost(params)
        n = self.n_starts
        e = self.task.mu1 * (e_u if n == 1 else np.repeat(e_u, n)) + self.task.mu2 * e_v
        failed = failed | ~np.isfinite(e)
        e = np.where(failed, np.inf, e)
        if n == 1:
            terms = dict(zip(term_names(self.task.terms), values, strict=True))
            return Evaluation(e, e_u, np.where(failed, np.inf, e_v), terms, failed)
        k = params.shape[0]
        per, failed = e.reshape(k, n), failed.reshape(k, n).any(axis=1)
        terms = {
            name: v.reshape(k, n).mean(axis=1)
            for name, v in zip(term_names(self.task.terms), values, strict=True)
        }
        e_v = np.where(failed, np.inf, e_v.reshape(k, n).mean(axis=1))
        return Evaluation(np.where(failed, np.inf, per.mean(axis=1)), e_u, e_v, terms, failed, per)

    def __call__(self, params: np.ndarray) -> np.ndarray:
        """Return E (K,) for a batch of parameter vectors."""
        return self.evaluate(params).E
