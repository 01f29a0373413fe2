"""MuJoCo simulation of a planar creature driven by a closed-loop policy (a SAN or any other).

Public interface::

    class Policy(Protocol):
        def reset(self) -> None
        def step(self, sensors: np.ndarray, dt: float) -> np.ndarray
            # sensors (S,) bool -> commands (A,) float in [-2, 2]; an optional attribute
            # ``state`` (1-D float array) is recorded at each record step when present
    Rollout   frozen dataclass: metric, fell, distance, seconds, times (R,), poses (R, L, 3),
              sensors (R, S), commands (R, A), targets (R, A), states (R, N) | None,
              follow (R, 2) | None, terrain (K, 2) | None, unstable
    World(creature, terrain="flat" | "rough" | "hill", seed=0, follow=None, mirror=False)
        .run(policy, seconds=None, record_every=0) -> Rollout
        .set_tuning(creature)                  same structure, new Fig. 8 parameters
        .read_sensors(follow_point=None), .poses(), .com(), .ground(x)   for the current state
        (``follow`` defaults to creature.metric == "follow"; without a follow point eyes see
        nothing and a "follow" creature is scored by its distance; ``mirror`` reflects the
        follow spline left for right)
    evaluate(creature, policy, seconds=None, terrain="flat", seed=0) -> float

How a rollout runs. Every ``control_dt`` the world reads the binary sensors, calls
``policy.step(sensors, control_dt)`` and maps each command u (clipped to [-2, 2]) linearly onto
its actuator's range: target = lo + (u + 2) / 4 * (hi - lo). MuJoCo position servos then apply
T = ks (target - q) - kd dq/dt at every physics step ``dt`` (implicit-fast integration), with
no hard joint limits unless the creature declares them. Sensors are read from the poses MuJoCo
computed at the start of the last physics step (at most ``dt`` old).

Media. Vertical creatures stand on the ground: MuJoCo contacts with Coulomb friction
``friction``. Horizontal (top-view) creatures have no gravity; their medium acts on each link
through ``data.xfrc_applied``, updated every physics step:
- water (the fish): per face, F = -k * integral(v . N) dA over the faces moving into the water
  (the paper's F = k integral(v . N) dA). For a link of length l, thickness 2r and depth w this
  sums to a drag -k w l v_n along the link normal, -k w 2r v_t along its axis and a torque
  -k w (l^3 + (2r)^3) / 12 omega; no gravity, so the fish is neutrally buoyant.
- ground seen from above (the crawler): each link is a point load m g sliding on the floor
  with anisotropic friction relative to the root link's heading: coefficient mu_f when moving
  forward, mu_b when moving backward, mu_l sideways, smoothed as mu m g tanh(v / 0.02 m/s).

Metrics (over the centre of mass, COM). "distance": |x(T) - x(0)|, 0 after a fall. "hop":
integral (dx/dt + k y^2) dt, y the COM height above the ground, k = ``hop_k``. "follow":
integral v . F dt with v the COM velocity and F the unit vector from the COM towards the
follow point; the follow point moves at ``follow_speed`` along a seeded Catmull-Rom spline
through waypoints starting ``follow_lead`` ahead of the creature (Fig. 10). ``distance`` is
always the signed COM displacement along x. A creature falls when a ``fall_links`` link touches
the ground or its root link turns more than ``fall_tilt`` from its start angle; once fallen it
stays fallen. A rollout whose physics goes non-finite or MuJoCo flags as unstable stops and
reports ``unstable=True``, ``fell=True`` and metric 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import mujoco
import numpy as np

from zoetic.errors import SimulationError
from zoetic.san.creature import Creature, CreatureError
from zoetic.san.follow import FollowPath
from zoetic.san.kernels import ANGLE, EYE, LENGTH, TOUCH, command, fallen, medium_forces, sense
from zoetic.san.mjcf import GRAVITY, build_mjcf, hill_profile, rough_profile

__all__ = ["Policy", "Rollout", "World", "evaluate"]

_TOUCH_CLEAR = 0.002  # m, clearance below which a fall link counts as touching


@runtime_checkable
class Policy(Protocol):
    """A closed-loop controller: binary sensors in, commands in [-2, 2] out."""

    def reset(self) -> None:
        """Return the policy to its start state."""

    def step(self, sensors: np.ndarray, dt: float) -> np.ndarray:
        """Return the (A,) commands for sensors (S,) bool after ``dt`` seconds."""


@dataclass(frozen=True)
class Rollout:
    """What a run produced: the metric and, when recorded, R samples of the motion.

    ``poses`` (R, L, 3) are [x, z, angle] of each link frame (x forward, z up or, top view,
    to the left); ``targets`` the desired joint angles (rad) or lengths (m); ``terrain`` the
    rough ground profile (K, 2) or None for flat ground or a top-view creature.
    """

    metric: float
    fell: bool
    distance: float
    seconds: float
    times: np.ndarray
    poses: np.ndarray
    sensors: np.ndarray
    commands: np.ndarray
    targets: np.ndarray
    states: np.ndarray | None = None
    follow: np.ndarray | None = None
    terrain: np.ndarray | None = None
    unstable: bool = False


def _probes(link, at: float | None) -> list[tuple[float, float, float]]:
    """Local points (x, z, radius) whose clearance above the ground is what touches."""
    a, b, r = link.start, link.start + link.length, link.radius
    if link.shape == "sphere":
        return [(link.centre, 0.0, r)]
    if at is not None:
        x = min(max(at, a), b)
        if link.shape == "box":
            return [(x, -r, 0.0), (x, r, 0.0)]
        return [(x, 0.0, r)]
    if link.shape == "capsule":
        return [(a, 0.0, r), (b, 0.0, r)]
    return [(a, -r, 0.0), (a, r, 0.0), (b, -r, 0.0), (b, r, 0.0)]


class World:
    """A creature compiled into MuJoCo once, on flat or rough ground or in a valley between two
    hills (``hill``: uphill at 10% either way from |x| = 0.5 m); ``run`` resets it.
    ``mirror`` reflects the follow point's spline about the creature's start line."""

    def __init__(
        self,
        creature: Creature,
        terrain: str = "flat",
        seed: int = 0,
        follow: bool | None = None,
        mirror: bool = False,
    ):
        if terrain not in ("flat", "rough", "hill"):
            raise CreatureError(f"unknown terrain {terrain!r} (expected 'flat', 'rough' or 'hill')")
        c = creature
        self.creature, self.terrain_kind, self.seed = c, terrain, int(seed)
        self.mirror = bool(mirror)
        self.vertical = c.plane == "vertical"
        self.follow_on = (c.metric == "follow") if follow is None else bool(follow)
        self.terrain = None
        if terrain == "rough" and self.vertical:
            self.terrain = rough_profile(c.rough_height, self.seed)
        elif terrain == "hill" and self.vertical:
            self.terrain = hill_profile()
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(c, self.terrain))
        m = self.model
        if self.terrain is not None:
            z = self.terrain[:, 1] / max(float(self.terrain[:, 1].max()), 1e-6)
            m.hfield_data[:] = np.tile(z, 3)
            self._gx = np.ascontiguousarray(self.terrain[:, 0])
            self._gz = np.ascontiguousarray(self.terrain[:, 1])
        else:
            self._gx = self._gz = np.zeros(0)
        self.data = mujoco.MjData(m)
        d = self.data  # these views into MjData's buffers stay valid for its lifetime
        self._qpos, self._xpos, self._xmat = d.qpos, d.xpos, d.xmat
        self.substeps = int(round(c.control_dt / c.dt))
        self.body = np.array([m.body(ln.name).id for ln in c.links], dtype=np.int64)
        self.root_body = int(self.body[0])
        self._index(c)
        self.set_tuning(c)
        self.qpos0 = self._start_pose()

    # ------------------------------------------------------------------ set-up

    def _index(self, c: Creature) -> None:
        m = self.model
        jq = {j.name: int(m.jnt_qposadr[m.joint(j.name).id]) for j in c.joints if j.kind != "fixed"}
        joint_by = {j.name: j for j in c.joints}
        act_by = {a.name: a for a in c.actuators}
        links = {ln.name: i for i, ln in enumerate(c.links)}
        itab, ftab = [], []  # rows (kind, qpos adr or body, sensor), (px, pz, radius, offset)
        for i, s in enumerate(c.sensors):
            if s.kind in ("angle", "length"):
                jn = act_by[s.target].joint if s.target in act_by else s.target
                if s.kind == "angle":
                    itab.append((ANGLE, jq[jn], i))
                    ftab.append((0.0, 0.0, 0.0, 0.0))
                else:
                    itab.append((LENGTH, jq[jn], i))
                    ftab.append((0.0, 0.0, 0.0, joint_by[jn].offset))
            elif s.kind == "touch":
                li = links[s.target]
                for px, pz, r in _probes(c.links[li], s.at):
                    itab.append((TOUCH, self.body[li], i))
                    ftab.append((px, pz, r, 0.0))
            else:
                ln = c.links[links[s.target]]
                at = ln.start + ln.length if s.at is None else s.at
                itab.append((EYE, self.body[links[s.target]], i))
                ftab.append((at, 0.0, 0.0, 0.0))
        self._itab = np.array(itab, dtype=np.int64).reshape(-1, 3)
        self._ftab = np.array(ftab, dtype=float).reshape(-1, 4)
        self._raw = np.empty(c.n_sensors)
        fb, fp = [], []
        for name in c.fall_links:
            li = links[name]
            for p in _probes(c.links[li], None):
                fb.append(self.body[li])
                fp.append(p)
        self._fbody = np.array(fb, dtype=np.int64)
        self._fpts = np.array(fp, dtype=float).reshape(-1, 3)
        self._tilt = float(c.fall_tilt) if c.fall_tilt is not None else -1.0
        self.checks_fall = self.vertical and (self._fbody.size > 0 or self._tilt > 0)
        # servo ctrl = target - offset (a slide joint's length is offset + q)
        self._off = np.array(
            [joint_by[a.joint].offset if a.kind == "linear" else 0.0 for a in c.actuators]
        )
        # media
        self.medium_force = (not self.vertical) and (
            c.medium == "water" or any(v > 0 for v in c.crawl_friction)
        )
        self._water = c.medium == "water"
        self._load = np.array([ln.mass * GRAVITY for ln in c.links])
        self._mu = np.array(c.crawl_friction, dtype=float)
        w = np.array([ln.out_of_plane for ln in c.links])
        ll = np.array([ln.length if ln.shape != "sphere" else 2 * ln.radius for ln in c.links])
        th = np.array([2 * ln.radius for ln in c.links])
        k = c.water_k
        self._wn, self._wt, self._wrot = k * w * ll, k * w * th, k * w * (ll**3 + th**3) / 12.0

    def set_tuning(self, creature: Creature) -> None:
        """Use ``creature``'s Fig. 8 parameters (same creature otherwise: links, joints, names)."""
        old = self.creature
        same = (
            (creature.name, creature.links, creature.joints)
            == (
                old.name,
                old.links,
                old.joints,
            )
            and [(s.name, s.kind, s.target) for s in creature.sensors]
            == [(s.name, s.kind, s.target) for s in old.sensors]
            and [(a.name, a.kind, a.joint) for a in creature.actuators]
            == [(a.name, a.kind, a.joint) for a in old.actuators]
        )
        if not same:
            raise CreatureError(
                f"set_tuning: creature {creature.name!r} has other sensors or actuators than "
                f"{old.name!r}; build a new World"
            )
        self.creature = creature
        t = creature.tuning()
        m = self.model
        m.actuator_gainprm[:, 0] = t["ks"]
        m.actuator_biasprm[:, 1] = -t["ks"]
        m.actuator_biasprm[:, 2] = -t["kd"]
        self._alo, self._aspan = t["actuator_lo"], t["actuator_hi"] - t["actuator_lo"]
        self._slo, self._shi = t["sensor_lo"], t["sensor_hi"]

    def _start_pose(self) -> np.ndarray:
        """Initial qpos: joints at rest, the creature lowered to just touch the ground."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[2] = self.creature.root_angle
        mujoco.mj_kinematics(m, d)
        qpos = d.qpos.copy()
        if self.vertical:
            b, p = [], []
            for i, ln in enumerate(self.creature.links):
                for q in _probes(ln, None):
                    b.append(self.body[i])
                    p.append(q)
            xp, xm, p = d.xpos[b], d.xmat[b], np.array(p)
            x = xp[:, 0] + xm[:, 0] * p[:, 0] + xm[:, 2] * p[:, 1]
            z = xp[:, 2] + xm[:, 6] * p[:, 0] + xm[:, 8] * p[:, 1] - p[:, 2] - self.ground(x)
            qpos[1] -= float(z.min()) - 1e-4
        return qpos

    # ------------------------------------------------------------------ reading

    def ground(self, x: np.ndarray) -> np.ndarray:
        """Return the ground height (m) at positions ``x`` (0 on flat ground)."""
        if self.terrain is None:
            return np.zeros_like(np.asarray(x, dtype=float))
        return np.interp(x, self._gx, self._gz)

    def read_sensors(self, follow_point: np.ndarray | None = None) -> np.ndarray:
        """Return the (S,) binary sensor values for the current state (a fresh array)."""
        out = np.empty(self.creature.n_sensors, dtype=np.bool_)
        fp = np.zeros(0) if follow_point is None else np.asarray(follow_point, dtype=float)
        sense(
            self._qpos,
            self._xpos,
            self._xmat,
            self._itab,
            self._ftab,
            self._gx,
            self._gz,
            fp,
            self._slo,
            self._shi,
            self._raw,
            out,
        )
        return out

    def poses(self) -> np.ndarray:
        """Return (L, 3) [x, z, angle] of each link frame."""
        xp, xm = self._xpos[self.body], self._xmat[self.body]
        return np.stack([xp[:, 0], xp[:, 2], np.arctan2(xm[:, 6], xm[:, 0])], axis=1)

    def com(self) -> np.ndarray:
        """Return the creature's centre of mass [x, z]."""
        c = self.data.subtree_com[self.root_body]
        return np.array([c[0], c[2]])

    # ------------------------------------------------------------------ running

    def run(self, policy: Policy, seconds: float | None = None, record_every: int = 0) -> Rollout:
        """Return the rollout of ``policy`` from the start pose for ``seconds`` (default: the
        creature's); records every ``record_every`` control ticks (0: the metric only)."""
        c, m, d = self.creature, self.model, self.data
        seconds = float(c.seconds if seconds is None else seconds)
        cdt, k = c.control_dt, self.substeps
        n_ticks = int(round(seconds / cdt))
        angle0, com0, path, kind = self._begin(policy, seconds)
        buf: dict[str, list] = {key: [] for key in "tpsugxf"}
        fell = unstable = False
        acc = 0.0
        qpos, xpos, xmat, ctrl = self._qpos, self._xpos, self._xmat, d.ctrl
        gx, gz = self._gx, self._gz
        itab, ftab, slo, shi, raw = self._itab, self._ftab, self._slo, self._shi, self._raw
        alo, aspan, off = self._alo, self._aspan, self._off
        fbody, fpts, root, tilt = self._fbody, self._fpts, self.root_body, self._tilt
        check_fall, margs = self.checks_fall, self._medium_args()
        target, u = np.zeros(c.n_actuators), np.zeros(c.n_actuators)
        com = com0
        fp = path.at(0.0) if path is not None else np.zeros(0)
        for tick in range(n_ticks + 1):
            s = np.empty(c.n_sensors, dtype=np.bool_)
            sense(qpos, xpos, xmat, itab, ftab, gx, gz, fp, slo, shi, raw, s)
            if tick < n_ticks:
                u = np.asarray(policy.step(s, cdt), dtype=float)
                if u.shape != target.shape:
                    raise SimulationError(
                        f"policy.step returned commands of shape {u.shape}; creature "
                        f"{c.name!r} has {c.n_actuators} actuators"
                    )
                command(u, alo, aspan, off, target, ctrl)
            if record_every > 0 and tick % record_every == 0:
                follow = fp if path is not None else None
                self._record(buf, tick * cdt, s, u, target, policy, follow)
            if tick == n_ticks:
                break
            if margs is not None:
                for _ in range(k):
                    medium_forces(*margs)
                    mujoco.mj_step(m, d)
            else:
                mujoco.mj_step(m, d, k)
            if check_fall and not fell:
                fell = fallen(xpos, xmat, fbody, fpts, gx, gz, _TOUCH_CLEAR, root, angle0, tilt)
            if kind != "distance":
                new = self.com()
                if kind == "hop":
                    y = new[1] - float(self.ground(new[:1])[0])
                    acc += c.hop_k * y * y * cdt
                else:
                    dx, dz = fp[0] - com[0], fp[1] - com[1]
                    nrm = math.hypot(dx, dz)
                    if nrm > 1e-9:
                        acc += ((new[0] - com[0]) * dx + (new[1] - com[1]) * dz) / nrm
                com = new
            if path is not None:
                fp = path.at((tick + 1) * cdt)
            if tick % 64 == 63 and not math.isfinite(qpos[1] + d.qvel[0]):
                unstable = True
                break
        metric, fell, distance, unstable = self._outcome(kind, com0, acc, fell, unstable)
        return self._rollout(metric, fell, distance, seconds, buf, unstable)

    def _begin(self, policy: Policy, seconds: float):
        """Put the creature at its start pose and reset the policy; return the start angle,
        the start centre of mass, the follow path (or None) and the metric's kind."""
        c, m, d = self.creature, self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[:] = self.qpos0
        mujoco.mj_forward(m, d)
        policy.reset()
        angle0 = float(self.poses()[0, 2])
        com0 = self.com()
        path = None
        if self.follow_on:
            lateral = not self.vertical
            path = FollowPath.for_creature(c, com0, self.seed, seconds, lateral, self.mirror)
        kind = c.metric if (c.metric != "follow" or path is not None) else "distance"
        return angle0, com0, path, kind

    def _medium_args(self) -> tuple | None:
        """Return the arguments of ``kernels.medium_forces`` (None without a medium force)."""
        if not self.medium_force:
            return None
        d = self.data
        root = self.root_body
        return (
            self.body,
            d.cvel,
            d.xipos,
            self._xmat,
            d.subtree_com[root],
            d.xfrc_applied,
            self._water,
            self._wn,
            self._wt,
            self._wrot,
            root,
            self._load,
            self._mu,
        )

    def _record(self, buf: dict, t: float, s, u, target, policy, follow) -> None:
        """Append one recorded control tick to the rollout's buffers."""
        buf["t"].append(t)
        buf["p"].append(self.poses())
        buf["s"].append(s)
        buf["u"].append(np.clip(u, -2.0, 2.0))
        buf["g"].append(target.copy())
        st = getattr(policy, "state", None)
        buf["x"].append(None if st is None else np.array(st, dtype=float).ravel())
        buf["f"].append(follow)

    def _outcome(self, kind: str, com0, acc: float, fell: bool, unstable: bool):
        """Return (metric, fell, signed distance, unstable) at the end of a run."""
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
        if unstable or bad or not np.isfinite(d.qpos).all():
            unstable, fell = True, True
        com1 = com0 if unstable else self.com()
        distance = float(com1[0] - com0[0])
        if unstable:
            metric = 0.0
        elif kind == "distance":
            metric = 0.0 if fell else abs(distance)
        elif kind == "hop":
            metric = distance + acc
        else:
            metric = acc
        return metric, fell, distance, unstable

    def _rollout(self, metric, fell, distance, seconds, buf, unstable) -> Rollout:
        c = self.creature
        n = len(buf["t"])
        states = None
        if n and all(x is not None for x in buf["x"]):
            states = np.array(buf["x"], dtype=float)
        follow = None
        if n and buf["f"][0] is not None:
            follow = np.array(buf["f"], dtype=float)
        return Rollout(
            metric=float(metric),
            fell=bool(fell),
            distance=distance,
            seconds=seconds,
            times=np.array(buf["t"], dtype=float),
            poses=np.array(buf["p"], dtype=float).reshape(n, c.n_links, 3),
            sensors=np.array(buf["s"], dtype=bool).reshape(n, c.n_sensors),
            commands=np.array(buf["u"], dtype=float).reshape(n, c.n_actuators),
            targets=np.array(buf["g"], dtype=float).reshape(n, c.n_actuators),
            states=states,
            follow=follow,
            terrain=None if self.terrain is None else self.terrain.copy(),
            unstable=unstable,
        )


def evaluate(
    creature: Creature,
    policy: Policy,
    seconds: float | None = None,
    terrain: str = "flat",
    seed: int = 0,
) -> float:
    """Return the creature's evaluation metric for ``policy`` (builds a World)."""
    return World(creature, terrain=terrain, seed=seed).run(policy, seconds).metric
