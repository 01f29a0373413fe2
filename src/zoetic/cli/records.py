"""The run record of each command that simulates, built at the command line's edge from what
the library returned (tracking and macro results, stunts, the aquarium's life, a chase, a SAN
replay) and written through ``zoetic.runs.write_run_record``, which adds every animal's motion
(``control.measure``) before the one writer, ``zoetic.record.write_record``, writes it."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from zoetic.record import Creature, Event, Link, Record, Thing, write_record
from zoetic.runs import animal_record, write_run_record


def _kind(obj) -> str:
    """Return what an object is, from its name (rock3 -> rock) or else its shape."""
    kind = re.sub(r"[\d_\- ]+$", "", str(getattr(obj, "name", "")).lower())
    return kind or type(obj).__name__.lower()


def solid_things(objects, times: np.ndarray, balls: np.ndarray | None = None) -> list[Thing]:
    """Return the record's entries of balls, boxes and cylinders; ``balls`` (T, nb, 3) m are
    the balls' positions at ``times`` (T,) s, in the order they appear in ``objects``."""
    from zoetic.physics.objects import Ball, Box, Cylinder

    out, b = [], 0
    for o in objects:
        if isinstance(o, Ball):
            pos = np.asarray(o.position, float)[None] if balls is None else balls[:, b]
            out.append(Thing("ball", o.name, "sphere", (o.radius,), pos))
            b += 1
        elif isinstance(o, Box):
            out.append(Thing(_kind(o), o.name, "box", tuple(o.half_size), np.array([o.center])))
        elif isinstance(o, Cylinder):
            out.append(
                Thing(
                    _kind(o), o.name, "cylinder", (o.radius, o.length), np.array([o.center]), o.axis
                )
            )
    return out


def targets(points_xz: np.ndarray, depth: float, kind: str = "target") -> list[Thing]:
    """Return point markers at (x, depth, z) for plane points (M, 2) m."""
    pts = np.asarray(points_xz, float).reshape(-1, 2)
    return [
        Thing(kind, f"{kind} {k + 1}", "point", (), np.array([[x, depth, z]]))
        for k, (x, z) in enumerate(pts)
    ]


def obstacle_discs(obstacles_xzr: np.ndarray, depth: float) -> list[Thing]:
    """Return upright cylinders for a macro task's obstacle discs (x, z, r) m, 2 m tall."""
    return [
        Thing(
            "obstacle", f"obstacle {k + 1}", "cylinder", (float(r), 2.0), np.array([[x, depth, z]])
        )
        for k, (x, z, r) in enumerate(obstacles_xzr)
    ]


def write_sequence_record(
    out: Path,
    kind: str,
    body,
    times,
    positions,
    ctrl,
    things=(),
    numbers: dict | None = None,
    splash: bool = False,
) -> Path:
    """Write the record of one animal driven by a controller (track, macro, stunt); with
    ``splash``, its surface crossings per recorded instant (``splash_scalars``)."""
    times = np.asarray(times, float)
    animal = animal_record(body, positions, times, ctrl)
    extra = {animal.name: splash_scalars(body, positions, times)} if splash else {}
    rec = Record(
        kind,
        f"{body.name} {kind} ({Path(out).name})",
        body.medium,
        times,
        (animal,),
        objects=tuple(things),
        numbers=numbers or {},
        period_times=times if splash else np.zeros(0),
        scalars=extra,
        units={"splash": "m^3/s", "splash_at": "m"} if splash else {},
    )
    return write_run_record(out, rec, [body])[0]


def splash_scalars(body, positions, times: np.ndarray) -> dict:
    """Return the body's splash at each recorded instant: the surface crossings of its faces
    from that instant to the next (``viz.spray.surface_crossings``, the stunt video's spray
    sources) as their summed area x normal speed (m^3/s; 0 at the last instant or without a
    surface) and where they were (flux-weighted mean point, m; NaN where none)."""
    from zoetic.physics import get_medium
    from zoetic.viz.spray import surface_crossings

    t = len(times)
    flux, at = np.zeros(t), np.full((t, 3), np.nan)
    level = get_medium(body.medium).water_level
    if abs(level) < 1e8 and t > 1:
        s = surface_crossings(body, positions, times, level)
        row = np.clip(np.searchsorted(times, s.times) - 1, 0, t - 2)
        np.add.at(flux, row, s.flux)
        weighted = np.zeros((t, 3))
        np.add.at(weighted, row, s.points * s.flux[:, None])
        some = flux > 0
        at[some] = weighted[some] / flux[some, None]
    return {"splash": flux, "splash_at": at}


def figures(summary: dict) -> dict:
    """Return a summary's plain figures (finite numbers, strings, booleans) for the viewer."""
    return {
        k: v
        for k, v in summary.items()
        if isinstance(v, str | bool | int) or (isinstance(v, float) and np.isfinite(v))
    }


def write_aquarium_record(out: Path, tank, life, summary: dict) -> Path:
    """Write a tank's record: every fish, the food (eaten or not), rocks, seaweed (its strands'
    nodes where the plants are dynamic) and walls, the events, and per brain period each
    fish's drives, intention and whether it lives."""
    from zoetic.behavior.mind import INTENTIONS

    fishes = tank.fishes
    animals = tuple(
        animal_record(
            f.body, life.positions[i], life.times, name=f.name, color=tuple(f.species.color)
        )
        for i, f in enumerate(fishes)
    )
    things = solid_things(tank.world.statics, life.times)
    if life.plants is not None:  # dynamic seaweed: each strand's nodes at every record
        radius = 0.5 * tank.plants.weed.width
        things += [
            Thing("seaweed", f"seaweed strand {k + 1}", "strand", (radius,), life.plants[:, k])
            for k in range(life.plants.shape[1])
        ]
    for k, food in enumerate(tank.world.foods):
        things.append(
            Thing(
                "food",
                f"food {k + 1}",
                "sphere",
                (food.radius,),
                life.food[:, k],
                visible=~life.eaten[:, k],
            )
        )
    scalars = {
        f.name: {
            "hunger": life.drives[:, i, 0],
            "libido": life.drives[:, i, 1],
            "fear": life.drives[:, i, 2],
            "intention": life.intentions[:, i],
            "alive": life.alive[:, i],
            "target": life.targets[:, i],
        }
        for i, f in enumerate(fishes)
    }
    rec = Record(
        "aquarium",
        f"aquarium ({Path(out).name})",
        tank.world.medium.name,
        life.times,
        animals,
        objects=tuple(things),
        events=tuple(Event(float(t), w, what, d) for t, w, what, d in life.events),
        period_times=life.brain_times,
        scalars=scalars,
        labels={"intention": list(INTENTIONS)},
        numbers=figures(summary),
        units={"hunger": "", "libido": "", "fear": "", "intention": "", "alive": "", "target": ""},
    )
    return write_run_record(out, rec, [f.body for f in fishes])[0]


def write_chase_record(out: Path, chase, result, summary: dict) -> Path:
    """Write a chase's record: predator, prey and distractors, rocks and seaweed, the catch,
    and per vision frame the predator's gaze angles, turn angles and triangulated range."""
    world = chase.world
    roles = ["predator", "prey"] + [f"distractor {k}" for k in range(1, len(world.bodies) - 1)]
    animals = tuple(
        animal_record(
            body,
            result.positions[a],
            result.times,
            name=roles[a],
            color=tuple(int(round(255 * c)) for c in chase.scenery.colors[a]),
        )
        for a, body in enumerate(world.bodies)
    )
    log = result.log
    n = min(len(log), len(result.times))
    scalars = (
        {
            "predator": {
                "gaze": np.array([r.angles for r in log[:n]], float).reshape(n, -1),
                "locked": np.array([r.locked for r in log[:n]], float).reshape(n, -1),
                "theta_p": np.array([r.theta_p for r in log[:n]], float),
                "phi_p": np.array([r.phi_p for r in log[:n]], float),
                "range": np.array([r.range for r in log[:n]], float),
                "eye_pos": np.array([r.eye_pos for r in log[:n]], float).reshape(n, 2, 3),
                "eye_dirs": np.array([r.eye_dirs for r in log[:n]], float).reshape(n, 2, 3),
            }
        }
        if n
        else {}
    )
    events = (
        (Event(float(result.time_to_catch), "predator", "catch", "prey"),) if result.caught else ()
    )
    rec = Record(
        "pursuit",
        f"pursuit ({Path(out).name})",
        world.medium.name,
        result.times,
        animals,
        objects=tuple(solid_things(world.statics, result.times)),
        events=events,
        period_times=np.asarray(result.times[:n], float),
        scalars=scalars,
        units={
            "gaze": "rad",
            "locked": "",
            "theta_p": "rad",
            "phi_p": "rad",
            "range": "m",
            "eye_pos": "m",
            "eye_dirs": "",
        },
        numbers=figures(summary),
    )
    return write_run_record(out, rec, world.bodies)[0]


def _prism(outline: np.ndarray, depth: float, axis: str) -> tuple[np.ndarray, np.ndarray]:
    """Return vertices (2K, 3) and faces of a convex planar outline (K, 2) extruded by depth."""
    k = len(outline)
    h = np.full(k, depth / 2)
    if axis == "z":  # the outline lies in x-y, extruded along z
        top = np.column_stack([outline[:, 0], outline[:, 1], h])
        bottom = np.column_stack([outline[:, 0], outline[:, 1], -h])
    else:  # the outline lies in x-z, extruded along y
        top = np.column_stack([outline[:, 0], h, outline[:, 1]])
        bottom = np.column_stack([outline[:, 0], -h, outline[:, 1]])
    i = np.arange(k)
    j = (i + 1) % k
    fan = np.column_stack([np.zeros(k - 2, int), np.arange(1, k - 1), np.arange(2, k)])
    faces = np.concatenate(
        [
            fan,
            fan[:, ::-1] + k,
            np.column_stack([i, i + k, j]),
            np.column_stack([j, i + k, j + k]),
        ]
    )
    return np.concatenate([top, bottom]).astype(np.float32), faces


def _san_links(tuned, poses: np.ndarray) -> tuple[list[Link], np.ndarray]:
    """Return the links of a planar creature posed at ``poses`` (R, L, 3: x, plane coordinate,
    angle) and its centre of mass (R, 3) m."""
    from PIL import ImageColor

    from zoetic.viz.san import LINK_COLOURS, link_outline

    vertical = getattr(tuned, "plane", "vertical") != "horizontal"
    axis = "z" if vertical else "y"
    links, centres = [], []
    for li, link in enumerate(tuned.links):
        verts, faces = _prism(link_outline(link, np.zeros(3)), link.out_of_plane, axis)
        x, p, ang = poses[:, li, 0], poses[:, li, 1], poses[:, li, 2]
        height = np.full_like(x, link.out_of_plane / 2 if not vertical else 0.0)
        tr = np.column_stack([x, p, np.zeros_like(x)] if vertical else [x, height, p])
        colour = ImageColor.getrgb(LINK_COLOURS[li % len(LINK_COLOURS)])[:3]
        links.append(
            Link(
                link.name, colour, verts, faces, tr.astype(np.float32), ang.astype(np.float32), axis
            )
        )
        cx, cp = x + np.cos(ang) * link.centre, p + np.sin(ang) * link.centre
        centres.append(
            (
                link.mass,
                np.column_stack([cx, cp, np.zeros_like(cx)] if vertical else [cx, height, cp]),
            )
        )
    com = sum(m * c for m, c in centres) / sum(m for m, _ in centres)
    return links, com


def write_san_record(out: Path, network_file: Path, fps: float = 30.0) -> Path:
    """Replay a SAN run's network (its best, or the tuned or evolved one) on its creature and
    write the record: the links' poses, the commands (mapped to [0, 1]) and the run's figures."""
    from zoetic.san.network import load_with_creature
    from zoetic.san.search import speed_cm_s
    from zoetic.san.show import replay

    creature = None
    if (network_file.parent / "creature.toml").is_file():
        creature = str(network_file.parent / "creature.toml")  # an evolve run's own body
    net, c = load_with_creature(network_file, creature)
    tuned = net.tuned_creature(c)
    terrain, seed = str(net.info.get("terrain", "flat")), int(net.info.get("seed", 0))
    seconds = net.info.get("seconds")
    roll = replay(net, c, float(seconds) if seconds else None, terrain, seed, fps)
    poses = np.asarray(roll.poses, float).copy()  # (R, L, 3): [x, z, angle]
    poses[..., 2] = np.unwrap(poses[..., 2], axis=0)
    times = np.asarray(roll.times, float)
    links, com = _san_links(tuned, poses)
    cmds = np.asarray(roll.commands, float)
    acts = None
    if cmds.ndim == 2 and len(cmds) == len(times) and cmds.size:
        acts = np.clip((cmds + 2.0) / 4.0, 0.0, 1.0)
    names = tuple(a.name for a in tuned.actuators)
    creature_rec = Creature(tuned.name, tuple(links), com.astype(np.float32), names, acts)
    speed = speed_cm_s(tuned, roll.metric, roll.distance, roll.seconds)
    numbers = {
        "metric": round(float(roll.metric), 4),
        "speed_cm_s": round(speed, 2),
        "fell": bool(roll.fell),
        "network": str(network_file),
    }
    medium = "ground" if tuned.medium == "ground" else "water"
    rec = Record(
        "san",
        f"{tuned.name} SAN ({Path(out).name})",
        medium,
        times,
        creatures=(creature_rec,),
        numbers=numbers,
    )
    return write_record(out, rec)
