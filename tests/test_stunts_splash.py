"""Stunts, second part: flight in the air is ballistic; the splash measure (area x normal speed
of the faces crossing the surface) tells a bellyflop from a clean dive; contact records name
the body part that struck the ball; the stunt video frames the whole stunt; the bench judges
tricks against the issue's targets."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from zoetic.behavior.repertoire import Repertoire
from zoetic.behavior.stunt_measures import cylinder_distance
from zoetic.behavior.stunt_problem import StuntProblem, StuntRecord
from zoetic.behavior.stunts import measures, splash_ratio, targets_met
from zoetic.behavior.training import rest_abstraction
from zoetic.behavior.tricks import list_tricks, load_trick, parse_trick
from zoetic.cli import main
from zoetic.physics import State, Trajectory, simulate
from zoetic.physics.objects import Cylinder
from zoetic.tasks.terms import PARTS, TERMS, BodyFrame, Signals, TermParams, body_parts
from zoetic.viz.render3d import look_at, project_points
from zoetic.viz.spray import Splash, spray_particles, surface_crossings
from zoetic.viz.stunts import stunt_camera, stunt_frames, subdivision


@pytest.fixture(scope="module")
def repertoire(dolphin):
    rep = Repertoire(dolphin.name, tuple(dolphin.actuator_names))
    rep.add("do-nothing", rest_abstraction(dolphin), 1.0)
    return rep


def _turned(body, pitch: float) -> np.ndarray:
    """The rest pose about its centre of mass, turned nose-up by ``pitch`` about +z."""
    w = body.mass / body.total_mass
    rel = body.rest_pos - w @ body.rest_pos
    c, s = math.cos(pitch), math.sin(pitch)
    return rel @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]).T


def _signals(frame, pos, dt, level=0.0, balls=None, touch=None) -> Signals:
    k, r = pos.shape[:2]
    return Signals(
        np, frame, pos, np.zeros((k, r, 1)), np.arange(r) * dt, level, r * dt, None, balls, touch
    )


def test_flight_in_the_air_is_a_parabola_and_keeps_its_angular_momentum(dolphin):
    """High above the water, tumbling, with its muscles working: the centre of mass falls at
    g and the angular momentum about it stays (internal forces only, no drag)."""
    body = dolphin.with_(node_damping=np.zeros(dolphin.n_nodes))
    rel = _turned(body, 0.3)
    omega = np.array([0.5, 0.0, 6.0])  # a somersault spin, a little roll
    vel = np.cross(omega, rel) + [2.0, 3.0, 0.0]
    st = State((rel + [0.0, 4.0, 0.0])[None], vel[None])
    steps = int(round(0.6 / body.dt))
    t = np.arange(steps) * body.dt
    act = np.clip(
        0.5 + 0.5 * np.sin(2 * np.pi * 3 * t[:, None] + np.arange(body.n_actuators)), 0, 1
    )
    tr = simulate(body, act, medium="sea", state=st, record_every=5)
    pos = tr.positions[0]
    assert pos[:, :, 1].min() > 1.0  # all of it in the air all along
    com = tr.com(body)[0]
    g = -2 * np.polyfit(tr.times, com[:, 1], 2)[0]
    assert g == pytest.approx(9.81, rel=1e-3)
    assert np.polyfit(tr.times, com[:, 0], 1)[0] == pytest.approx(2.0, rel=1e-3)
    vel_all = np.gradient(pos, tr.times, axis=0)  # (R, N, 3)
    ang = np.einsum("n,rnk->rk", body.mass, np.cross(pos - com[:, None], vel_all))
    ref = np.linalg.norm(ang[1])
    assert ref > 1.0  # it really spins
    assert np.abs(ang[1:-1] - ang[1]).max() < 0.02 * ref


def _plate(edge_on: bool, heights, face_up: bool = False) -> tuple[BodyFrame, np.ndarray]:
    """A 1 m x 1 m plate (one panel, its face down) moving through the surface, flat or
    edge-on."""
    corners = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]])
    if face_up:
        corners = corners[::-1]
    if edge_on:
        corners = corners[:, [0, 2, 1]]  # the plate in the vertical x-y plane
    frame = BodyFrame(
        np.full(4, 0.25),
        0,
        np.zeros(0, int),
        np.zeros(0, int),
        np.array([[0, 1, 2, 3]]),
        np.full((1, 4), 0.25),
    )
    pos = corners[None, None] + np.asarray(heights)[None, :, None, None] * [0.0, 1.0, 0.0]
    return frame, pos


def test_a_plate_dropped_flat_splashes_more_than_the_same_plate_edge_on():
    heights = 1.0 - 3.0 * np.arange(21) * 0.02  # 3 m/s down, from 1 m to -0.2 m
    flat, edge = _plate(False, heights), _plate(True, heights)
    splash = TERMS["splash"].fn
    got_flat = float(splash(np, _signals(*flat, 0.02), TermParams())[0])
    got_edge = float(splash(np, _signals(*edge, 0.02), TermParams())[0])
    assert got_flat == pytest.approx(1.0 * 3.0, rel=1e-6)  # area x normal speed
    assert got_edge == pytest.approx(0.0, abs=1e-9)
    # only a face that leads into the water slaps it: the same plate face up, none
    assert float(splash(np, _signals(*_plate(False, heights, True), 0.02), TermParams())[0]) == 0
    # coming out (face up) is a crossing too, but no splash on re-entry
    up = _signals(*_plate(False, heights[::-1], True), 0.02)
    assert float(up.crossing_flux.sum()) == pytest.approx(-3.0, rel=1e-6)
    assert float(splash(np, up, TermParams())[0]) == 0


def _drop(body, pitch: float, speed: float = 5.0, gap: float = 0.1):
    """The dolphin turned by ``pitch``, its lowest node ``gap`` m above the surface, falling
    at ``speed``."""
    rel = _turned(body, pitch)
    rel = rel + [0.0, gap - rel[:, 1].min(), 0.0]
    st = State(rel[None], np.tile([0.0, -speed, 0.0], (body.n_nodes, 1))[None])
    steps = int(round(0.5 / body.dt))
    tr = simulate(body, np.zeros((steps, body.n_actuators)), medium="sea", state=st, record_every=5)
    return tr


def _area_facing_down(body, pitch: float) -> float:
    """The area of the turned rest pose's panels that face down (its silhouette seen from
    below), from the geometry alone."""
    p = _turned(body, pitch)[body.panels]
    twice = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    return float(np.maximum(-0.5 * twice[:, 1], 0.0).sum())


@pytest.mark.slow
def test_a_bellyflop_splashes_more_than_a_nose_first_dive_in_numpy_and_jax(dolphin):
    jnp = pytest.importorskip("jax.numpy")
    frame = BodyFrame.of(dolphin)
    flop, dive = _drop(dolphin, 0.0), _drop(dolphin, -math.pi / 2)
    pos = np.concatenate([flop.positions, dive.positions])
    dt = flop.times[1] - flop.times[0]
    got = TERMS["splash"].fn(np, _signals(frame, pos, dt), TermParams())
    # a rigid body going in at speed v has sum(A max(n.v, 0)) = its area seen along v times
    # v: belly down, the lattice's plan area, all of it entering at about the speed it meets
    # the surface with; nose first, faces entering one after another as the water slows it
    v = np.sqrt(5.0**2 + 2 * 9.81 * 0.1)
    assert got[0] == pytest.approx(_area_facing_down(dolphin, 0.0) * v, rel=0.15)
    assert got[0] > 1.4 * got[1] > 0.0
    s = Signals(
        jnp,
        frame,
        jnp.asarray(pos, jnp.float32),
        jnp.zeros((2, pos.shape[1], 1)),
        np.arange(pos.shape[1]) * dt,
        0.0,
        1.0,
    )
    assert np.allclose(np.asarray(TERMS["splash"].fn(jnp, s, TermParams())), got, rtol=1e-4)
    spray = surface_crossings(dolphin, flop.positions[0], flop.times, 0.0)
    assert spray.flux.sum() == pytest.approx(got[0], rel=1e-9)
    assert np.allclose(spray.points[:, 1], 0.0)


def test_body_parts_name_nose_head_belly_back_and_tail(dolphin):
    parts = body_parts(dolphin)
    named = dict(zip(dolphin.node_names, (PARTS[p] for p in parts), strict=True))
    assert named["nose"] == "nose" and named["r1_0"] == "head"
    assert named["tail_top"] == named["tail_bottom"] == "tail"
    assert {named["r3_1"], named["r3_0"]} == {"belly", "back"}
    assert set(named.values()) == set(PARTS)


def _strike(dolphin, repertoire, tail_first: bool):
    """The dolphin under a ball on a post, shot up at it nose first or (turned over, moving
    backward) tail first; returns the problem, its record and the terms."""
    pitch = -math.pi / 2 if tail_first else math.pi / 2
    doc = {
        "name": "strike",
        "horizon": 0.6,
        "record_hz": 50.0,
        "requires": ["surface"],
        "start": {
            "position": [0.0, 0.0, 0.0],
            "depth": 1.1,
            "pitch": pitch,
            "speed": 8.0 if tail_first else 4.5,
        },
        "objects": [
            {"kind": "ball", "radius": 0.2, "mass": 0.3, "position": [0.0, 0.3, 0.0]},
            {
                "kind": "cylinder",
                "center": [0.0, -0.2, 0.0],
                "radius": 0.03,
                "length": 0.6,
                "axis": "y",
                "name": "post",
            },
        ],
        "terms": [{"kind": "ball_moved_by_nose"}, {"kind": "ball_moved_by_tail"}],
    }
    problem = StuntProblem(dolphin, repertoire, parse_trick(doc, "strike"))
    if tail_first:  # the start state swims nose down: send it the other way, tail up
        problem.start = dataclasses.replace(problem.start, velocities=-problem.start.velocities)
    rec = problem.record(np.zeros((1, 1), int), np.ones((1, 1)))
    return problem, rec, problem.scores(rec)


def test_the_contact_record_names_the_nose_or_the_tail_that_struck_the_ball(dolphin, repertoire):
    problem, rec, nose = _strike(dolphin, repertoire, tail_first=False)
    m = measures(problem, rec)
    assert m["ball_contact"] == "yes" and m["ball_parts"][0] == "nose"
    assert nose["ball_moved_by_nose"][0] > 0.2 and nose["ball_moved_by_tail"][0] == 0.0
    jnp = pytest.importorskip("jax.numpy")  # one definition for NumPy and JAX
    s = problem.signals(rec)
    sj = Signals(
        jnp,
        s.frame,
        jnp.asarray(s.positions),
        jnp.asarray(s.activations),
        s.times,
        s.level,
        s.horizon,
        jnp.asarray(s.contacts),
        jnp.asarray(s.balls),
        jnp.asarray(s.ball_touch),
    )
    got = float(TERMS["ball_moved_by_nose"].fn(jnp, sj, TermParams())[0])
    assert got == pytest.approx(nose["ball_moved_by_nose"][0], rel=1e-5)
    assert targets_met("ball-nose", m, problem.trick) == {
        "struck_by_nose": True,
        "off_support": True,
    }
    problem, rec, tail = _strike(dolphin, repertoire, tail_first=True)
    m = measures(problem, rec)
    assert m["ball_parts"][0] == "tail" and "nose" not in m["ball_parts"]
    assert tail["ball_moved_by_tail"][0] > 0.2 and tail["ball_moved_by_nose"][0] == 0.0
    assert not targets_met("ball-nose", m, problem.trick)["struck_by_nose"]


def test_bellyflop_and_clean_dive_are_tricks_that_push_the_splash_opposite_ways(dolphin):
    assert {"bellyflop", "clean-dive"} <= set(list_tricks())
    weight = {
        n: next(t.weight for t in load_trick(n).task.terms if t.kind == "splash")
        for n in ("bellyflop", "clean-dive")
    }
    assert weight["bellyflop"] < 0 < weight["clean-dive"]  # maximise, minimise
    out = {"most_nodes_out_of_water": 1.0}
    assert splash_ratio(out | {"splash_m3_s": 3.0}, out | {"splash_m3_s": 1.0}) == 3.0
    # only broke the surface from below (no leap): no re-entry to compare
    under = {"most_nodes_out_of_water": 0.4, "splash_m3_s": 0.0}
    assert splash_ratio(out | {"splash_m3_s": 0.04}, under) is None


def test_hurdle_clearance_is_the_distance_to_the_bar():
    bar = Cylinder(center=(2.0, 0.3, 0.0), radius=0.02, length=1.0, axis="z")
    pts = np.array([[2.0, 0.8, 0.0], [2.0, 0.3, 0.0], [2.0, 0.3, 0.9], [1.0, 0.3, 0.0]])
    np.testing.assert_allclose(cylinder_distance(bar, pts), [0.48, -0.02, 0.4, 0.98])


def test_the_camera_frames_body_ball_and_bar_all_along():
    rng = np.random.default_rng(0)
    r = 60
    t = np.arange(r) * 0.05
    body = np.stack([t * 2.0, 3.0 * t - 0.5 * 9.81 * t**2 - 1.0, 0 * t], 1)[:, None]
    pts = np.concatenate(
        [
            body + rng.normal(0, 0.4, (r, 20, 3)),
            np.broadcast_to([[2.0, 0.3, -0.6], [2.0, 0.3, 0.6]], (r, 2, 3)),
        ],
        axis=1,
    )
    size, fov = (320, 180), 45.0
    direction = np.array([-0.3, 0.25, -0.92])
    direction /= np.linalg.norm(direction)
    focal = 0.5 * size[1] / np.tan(np.radians(fov) / 2)

    def all_in_view(pts, eyes, targets) -> bool:
        for k in range(len(pts)):
            scr, z = project_points(pts[k], eyes[k], look_at(eyes[k], targets[k]), focal, size)
            if not ((z > 0).all() and (scr >= 0).all() and (scr <= size).all()):
                return False
        return True

    eyes, targets = stunt_camera(pts, t, size, fov, direction)
    assert all_in_view(pts, eyes, targets)
    # smooth: the camera's motion changes little from frame to frame (no jerks)
    assert np.abs(np.diff(targets, 2, axis=0)).max() < 0.05
    # frames picked at repeated instants (a strip) are framed too
    pick = [0, 5, 5, 40]
    eyes, targets = stunt_camera(pts[pick], t[pick], size, fov, direction)
    assert all_in_view(pts[pick], eyes, targets)


def test_the_display_surface_is_a_closed_smooth_mesh_over_the_lattice(dolphin):
    s, faces = subdivision(dolphin.faces, dolphin.n_nodes, levels=2)
    assert faces.shape[0] == 16 * len(dolphin.faces)
    np.testing.assert_allclose(s.sum(axis=1), 1.0)  # affine: moves with the body
    assert (s >= -1e-12).all()  # inside the lattice's hull
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), 1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all()  # still closed


def test_spray_grows_with_the_splash_and_falls_back_into_the_water():
    small = spray_particles(Splash(np.array([0.0]), np.zeros((1, 3)), np.array([0.1])), 0.0)
    big = spray_particles(Splash(np.array([0.0]), np.zeros((1, 3)), np.array([0.6])), 0.0)
    assert 0 < len(small(0.05)) < len(big(0.05))
    assert (big(0.2)[:, 1] > 0).all() and len(big(3.0)) == 0


def test_stunt_frames_show_the_ball_and_the_spray(dolphin, repertoire):
    problem, rec, _ = _strike(dolphin, repertoire, tail_first=False)
    frames = list(
        stunt_frames(
            dolphin,
            rec.traj.positions[0][::6],
            rec.traj.times[::6],
            dolphin.medium,
            problem.trick.objects,
            rec.balls[0][::6],
            size=(160, 90),
        )
    )
    assert len(frames) == len(rec.traj.times[::6]) and frames[0].shape == (90, 160, 3)
    red = [(f[..., 0] > 150) & (f[..., 1] < 110) & (f[..., 2] < 110) for f in frames]
    assert all(m.sum() > 5 for m in red)  # the ball in view in every frame
    white = [int(((f > 225).all(axis=2)).sum()) for f in frames]
    assert max(white) > white[0]  # spray once the body broke the surface


def test_bench_stunts_judges_tricks_against_the_targets(tmp_path, capsys, repertoire):
    repertoire.save(tmp_path / "memory")
    code = main(
        [
            "bench",
            "stunts",
            "--memory",
            str(tmp_path / "memory"),
            "--tricks",
            "ball-nose,bellyflop,clean-dive",
            "--budget",
            "3",
            "--json",
        ]
    )
    assert code == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["ball-nose"]["success"] is False  # a resting dolphin strikes nothing
    assert out["ball-nose"]["ball_contact"] == "no"
    assert set(out["ball-nose"]["flags"]) == {"struck_by_nose", "off_support"}
    assert out["splash_ratio"] is None and out["splash_ratio_met"] is False
    # the budget counts simulations: the robust bellyflop plays each plan from 3 starts
    assert out["bellyflop"]["evaluations"] == 1 and out["clean-dive"]["evaluations"] == 3
    assert out["all_wall_s"] >= out["bellyflop"]["wall_s"]


def _record(body, pos, n_objects) -> StuntRecord:
    r = pos.shape[1]
    traj = Trajectory(
        np.arange(r) * 0.05,
        pos,
        State(pos[:, -1], np.zeros_like(pos[:, -1])),
        np.array([-1]),
        0.005,
    )
    return StuntRecord(
        traj,
        np.zeros((1, r, body.n_actuators)),
        np.zeros((1, r), int),
        np.zeros((1, r, 0, 3)),
        np.array([False]),
        np.zeros((1, r, body.n_nodes, n_objects)),
    )


def test_a_hand_made_jump_over_the_hurdle_clears_it_and_a_low_one_does_not(dolphin, repertoire):
    problem = StuntProblem(dolphin, repertoire, load_trick("hurdle"))
    rel = _turned(dolphin, 0.0)
    bar = problem.trick.objects[0]
    bar_x, bar_top = bar.center[0], bar.center[1] + bar.radius
    x = np.linspace(bar_x - 2.5, bar_x + 2.5, 41)
    for top, over in ((bar_top + 0.7, True), (bar_top + 0.04, False)):
        y = top - 1.6 * (x - bar_x) ** 2 / 4.0  # an arc, its top at the bar
        pos = (rel[None] + np.stack([x, y, 0 * x], 1)[:, None])[None]
        m = measures(problem, _record(dolphin, pos, len(problem.trick.objects)))
        assert m["bar_crossed"] is over and m["hurdle_touched"] is False
        assert (m["hurdle_clearance_m"] > 0.2) is over
        flags = targets_met("hurdle", m, problem.trick)
        assert flags["over_bar"] is over and flags["no_contact"] and flags["leaves_water"]


def test_the_drawn_pool_floor_stays_below_a_dive_from_a_deep_start():
    from zoetic.viz.stunts import Pool, deep_enough

    assert deep_enough(Pool(), 2.0).depth == 4.0  # a shallow stunt keeps the default floor
    deeper = deep_enough(Pool(), 4.6)
    assert deeper.depth == pytest.approx(5.6)  # 1 m of room under the deepest point
    assert deeper.margin == Pool().margin and deeper.rim == Pool().rim


def _arc(body, rise: float, seconds: float = 4.0, hz: float = 40.0, cut: float | None = None):
    """A rigid dolphin on a ballistic arc whose centre of mass rises from 1 m down to ``rise``
    m above the surface and falls back, its nose along its velocity all the way (a clean
    nose-first exit and entry); the motion stops at ``cut`` s if given (a body left hanging).
    Returns positions (1, R, N, 3) at ``hz``."""
    g, vx = 9.81, 3.0
    vy0 = math.sqrt(2 * g * (rise + 1.0))
    t = np.arange(int(round(seconds * hz)) + 1) / hz
    tt = t if cut is None else np.minimum(t, cut)
    y = -1.0 + vy0 * tt - 0.5 * g * tt**2
    y = np.maximum(y, -3.0)  # under water it stops falling (drag; terms only read the crossing)
    pitch = np.arctan2(vy0 - g * tt, vx)
    pos = np.stack(
        [_turned(body, p) + [vx * s, h, 0.0] for p, s, h in zip(pitch, tt, y, strict=True)]
    )
    return pos[None]


def _trick_cost(body, name: str, pos: np.ndarray, hz: float = 40.0) -> tuple[float, dict]:
    trick = load_trick(name)
    s = _signals(BodyFrame.of(body), pos, 1.0 / hz)
    from zoetic.tasks.terms import evaluate_terms

    vals = evaluate_terms(np, s, trick.task.terms)
    return (
        float(sum(t.weight * v[0] for t, v in zip(trick.task.terms, vals, strict=True))),
        {t.kind: float(v[0]) for t, v in zip(trick.task.terms, vals, strict=True)},
    )


def test_the_clean_dive_prefers_a_low_clean_slip_to_a_high_fast_entry(dolphin):
    """The splash grows with the entry speed, so for the judges a leap that just clears the
    water and slips back in nose first beats the same clean entry from a high leap (with the
    old 1/m reward for height the high leap scored better and the search leapt 1.8 m)."""
    low, high = _arc(dolphin, 0.5), _arc(dolphin, 2.0)
    e_low, t_low = _trick_cost(dolphin, "clean-dive", low)
    e_high, t_high = _trick_cost(dolphin, "clean-dive", high)
    assert t_low["clear_fraction"] == t_high["clear_fraction"] == 1.0  # both leave the water
    assert 0 < t_low["splash"] < t_high["splash"]
    assert e_low < e_high


def test_the_bellyflop_must_land_its_splash(dolphin):
    """A bellyflop still in the air at the end has made no splash yet: the trick charges the
    height left (its flag ``back_in_water`` fails), so the same leap landed scores better."""
    landed = _arc(dolphin, 2.0, seconds=3.0)
    hanging = _arc(dolphin, 2.0, seconds=3.0, cut=1.3)  # falling, 0.7 m above the water
    e_landed, t_landed = _trick_cost(dolphin, "bellyflop", landed)
    e_hanging, t_hanging = _trick_cost(dolphin, "bellyflop", hanging)
    assert e_landed < e_hanging
    assert t_hanging.get("final_height", 0.0) > 0.0 == t_landed["final_height"]


def test_a_face_splashes_once_at_its_re_entry_not_each_time_it_beats_across_the_surface():
    """The splash is the body hitting the water on re-entry: a face that leaves the water and
    comes back counts once; beating up and down across the surface afterwards adds nothing
    (a body wallowing at the surface for a second outscored a bellyflop when every downward
    crossing counted); a face that never left the water makes no splash."""
    splash = TERMS["splash"].fn
    fall = 1.0 - 3.0 * np.arange(21) * 0.02  # from 1 m up, 3 m/s down to -0.2 m
    beat = -0.2 + 0.3 * np.sin(np.arange(1, 41) * 0.5)  # then across the surface, 40 records
    once = float(splash(np, _signals(*_plate(False, fall), 0.02), TermParams())[0])
    wallow = _signals(*_plate(False, np.concatenate([fall, beat])), 0.02)
    assert float(wallow.crossing_flux.clip(min=0).sum()) > 3 * once  # it crosses again and again
    assert float(splash(np, wallow, TermParams())[0]) == pytest.approx(once, rel=1e-9)
    # from under water: up and out, then back in (counted once), then beating
    leap = np.concatenate([fall[::-1], fall, beat])
    assert float(splash(np, _signals(*_plate(False, leap), 0.02), TermParams())[0]) == (
        pytest.approx(once, rel=1e-9)
    )
    # never out: a face beating just under the surface only
    under = _signals(*_plate(False, beat - 0.2), 0.02)
    assert float(splash(np, under, TermParams())[0]) == 0.0
