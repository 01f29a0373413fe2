"""A run directory as a scene to look at: animals' surfaces over time, the medium, targets.

The glTF exporter (``viz.gltf``) and the web viewer (``zoetic.web``) both start from a Scene, so
a run is read (and, where it keeps only a controller, simulated again) in one place:

- ``trajectory.npz`` with the animal recorded (``zoetic simulate``, ``repertoire sequence``);
- ``controller.json`` with ``config.toml`` (``zoetic learn``) or ``summary.json`` naming the
  animal (``zoetic track``, ``zoetic macro``): the controller is simulated again from rest.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.bodies import Body, load_animal
from zoetic.errors import RunDirError
from zoetic.io import read_json, read_toml
from zoetic.physics import Medium, get_medium


@dataclass(frozen=True)
class Animal:
    """One animal of a scene: its surface and its recorded motion at the scene's frame times."""

    name: str
    color: tuple[int, int, int]
    faces: np.ndarray  # (F, 3) int triangles, counter-clockwise seen from outside
    positions: np.ndarray  # (R, N, 3) float32 m
    com: np.ndarray  # (R, 3) float32 m, centre of mass
    actuators: tuple[str, ...] = ()
    activations: np.ndarray | None = None  # (R, A) in [0, 1], the controller at each frame


@dataclass(frozen=True)
class Rigid:
    """One rigid link: a prism mesh in its own frame, moved by a pose per frame."""

    name: str
    color: tuple[int, int, int]
    vertices: np.ndarray  # (V, 3) float32 m, in the link's frame (zoetic axes)
    faces: np.ndarray  # (F, 3) int, counter-clockwise seen from outside
    translations: np.ndarray  # (R, 3) float32 m, the frame's origin (zoetic axes)
    angles: np.ndarray  # (R,) rad, about ``axis``, from +x toward the plane's second axis
    axis: str  # "z": a vertical plane (x forward, y up); "y": a top view (x forward, z left)


@dataclass(frozen=True)
class Creature:
    """A rigid-link creature (a sensor-actuator network's): its links and what drives them."""

    name: str
    links: tuple[Rigid, ...]
    com: np.ndarray  # (R, 3) float32 m
    actuators: tuple[str, ...] = ()
    activations: np.ndarray | None = None  # (R, A) commands mapped to [0, 1]


@dataclass(frozen=True)
class Scene:
    """What a viewer shows: animals at frame times ``times`` (R,), in a medium, with markers."""

    title: str
    kind: str  # simulate, learn, track, macro
    times: np.ndarray  # (R,) s, evenly spaced at ``fps``
    fps: float
    medium: Medium
    animals: tuple[Animal, ...]
    markers: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # (M, 3) targets
    numbers: dict = field(default_factory=dict)  # run figures shown beside the view
    creatures: tuple[Creature, ...] = ()

    @property
    def movers(self) -> tuple:
        """Return the animals and the creatures: each has a name, com, actuators, activations."""
        return tuple(self.animals) + tuple(self.creatures)

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0]) if len(self.times) else 0.0


def _animal(body: Body, positions: np.ndarray, times: np.ndarray, fps: float, ctrl) -> tuple:
    """Return the frame times at ``fps`` and an Animal resampled there from recorded positions."""
    from zoetic.viz.render3d import body_color, resample

    t_new, (pos,) = resample([positions], times, fps)
    com = np.einsum("rnk,n->rk", pos, body.mass / body.total_mass)
    act = None
    if ctrl is not None:
        act = np.clip(np.asarray(ctrl.sample(t_new), np.float32), 0.0, 1.0)
    animal = Animal(
        name=body.name, color=tuple(int(c) for c in body_color(body)),
        faces=np.asarray(body.faces, np.int64), positions=pos.astype(np.float32),
        com=com.astype(np.float32), actuators=tuple(body.actuator_names), activations=act,
    )  # fmt: skip
    return t_new, animal


def _travelled(com: np.ndarray) -> float:
    good = com[np.isfinite(com).all(axis=1)]
    return float(np.linalg.norm(good[-1, [0, 2]] - good[0, [0, 2]])) if len(good) else 0.0


def _from_trajectory(run: Path, fps: float) -> Scene:
    from zoetic.control import from_dict

    path = run / "trajectory.npz"
    try:
        with np.load(path) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise RunDirError(f"{path}: not a readable trajectory ({exc})") from None
    if "animal" not in data:
        raise RunDirError(
            f"{path}: the trajectory does not name its animal (written by an older zoetic); "
            "run `zoetic simulate` again to view it"
        )
    body = load_animal(str(data["animal"]))
    medium = get_medium(str(data["medium"])) if "medium" in data else get_medium(body.medium)
    ctrl = None
    if "controller" in data:
        ctrl = from_dict(json.loads(str(data["controller"])), where=f"{path}: controller")
    times, positions = data["times"], data["positions"]
    if positions.ndim != 3 or positions.shape[1:] != (body.n_nodes, 3):
        raise RunDirError(f"{path}: positions {positions.shape} do not fit the {body.name}")
    t, animal = _animal(body, positions, times, fps, ctrl)
    numbers = {"distance_m": round(_travelled(animal.com), 3)}
    return Scene(f"{body.name} ({run.name})", "simulate", t, fps, medium, (animal,),
                 numbers=numbers)  # fmt: skip


def _best_E(history: Path) -> float | None:
    """Return the smallest E in a learning run's history.csv (None when there is none)."""
    if not history.exists():
        return None
    with history.open(newline="") as fh:
        values = [float(row["E"]) for row in csv.DictReader(fh) if row.get("E")]
    finite = [v for v in values if np.isfinite(v)]
    return min(finite) if finite else None


def _from_controller(run: Path, fps: float) -> Scene:
    from zoetic.control import load_controller
    from zoetic.runs import run_controller

    markers = np.zeros((0, 2))
    numbers: dict = {}
    if (run / "config.toml").exists():
        doc = read_toml(run / "config.toml", what="run configuration")
        try:
            animal, seconds = doc["run"]["animal"], float(doc["task"]["horizon"])
            medium_name, kind = doc["run"].get("medium"), "learn"
        except (KeyError, TypeError, ValueError) as exc:
            raise RunDirError(
                f"{run / 'config.toml'}: no run.animal or task.horizon ({exc})"
            ) from None
        best = _best_E(run / "history.csv")
        if best is not None:
            numbers["best_E"] = round(best, 4)
        numbers["task"] = str(doc["task"].get("name", ""))
    else:
        summary = read_json(run / "summary.json", what="run summary")
        if not isinstance(summary, dict) or "animal" not in summary:
            raise RunDirError(f"{run / 'summary.json'}: no 'animal' entry")
        animal, medium_name = summary["animal"], None
        kind = "macro" if "goal_xz" in summary else "track"
        seconds = float(summary.get("simulated_s", summary.get("horizon_s", 0.0)) or 0.0)
        if "reached" in summary:
            numbers["targets_reached"] = f"{summary['reached']}/{summary.get('targets', '?')}"
        if "targets_xz" in summary:
            markers = np.asarray(summary["targets_xz"], float).reshape(-1, 2)
        elif "goal_xz" in summary:
            markers = np.asarray(summary["goal_xz"], float).reshape(-1, 2)
    body = load_animal(animal)
    ctrl = load_controller(run / "controller.json", body)
    if seconds <= 0:
        seconds = float(getattr(ctrl, "duration", 10.0))
    medium = get_medium(medium_name or body.medium)
    traj = run_controller(body, ctrl, seconds, medium, body.dt)
    t, anim = _animal(body, traj.positions[0], traj.times, fps, ctrl)
    numbers["distance_m"] = round(_travelled(anim.com), 3)
    depth = float(anim.com[0, 1])
    mk = np.column_stack([markers[:, 0], np.full(len(markers), depth), markers[:, 1]])
    return Scene(f"{body.name} {kind} ({run.name})", kind, t, fps, medium, (anim,), mk, numbers)


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
    faces = np.concatenate([
        fan, fan[:, ::-1] + k,
        np.column_stack([i, i + k, j]), np.column_stack([j, i + k, j + k]),
    ])  # fmt: skip
    return np.concatenate([top, bottom]).astype(np.float32), faces


def _from_san(run: Path, fps: float) -> Scene:
    from PIL import ImageColor

    from zoetic.san.network import load_with_creature
    from zoetic.san.search import speed_cm_s
    from zoetic.san.show import replay, resolve_network
    from zoetic.viz.san import LINK_COLOURS, link_outline

    file = resolve_network(run)
    net, c = load_with_creature(file)
    tuned = net.tuned_creature(c)
    terrain, seed = str(net.info.get("terrain", "flat")), int(net.info.get("seed", 0))
    seconds = net.info.get("seconds")
    rollout = replay(net, c, float(seconds) if seconds else None, terrain, seed, fps)
    from zoetic.viz.render3d import resample

    poses = np.asarray(rollout.poses, float).copy()  # (R, L, 3): [x, z, angle]
    poses[..., 2] = np.unwrap(poses[..., 2], axis=0)
    recorded = np.asarray(rollout.times, float)
    times, (poses,) = resample([poses], recorded, fps)  # recorded every few control ticks
    near = np.clip(np.searchsorted(recorded, times + 1e-9) - 1, 0, len(recorded) - 1)
    vertical = getattr(tuned, "plane", "vertical") != "horizontal"
    axis = "z" if vertical else "y"
    links, centres = [], []
    for li, link in enumerate(tuned.links):
        outline = link_outline(link, np.zeros(3))
        verts, faces = _prism(outline, link.out_of_plane, axis)
        x, p, ang = poses[:, li, 0], poses[:, li, 1], poses[:, li, 2]
        height = np.full_like(x, link.out_of_plane / 2 if not vertical else 0.0)
        tr = np.column_stack([x, p, np.zeros_like(x)] if vertical else [x, height, p])
        colour = ImageColor.getrgb(LINK_COLOURS[li % len(LINK_COLOURS)])[:3]
        links.append(Rigid(link.name, colour, verts, faces,
                           tr.astype(np.float32), ang.astype(np.float32), axis))  # fmt: skip
        cx = x + np.cos(ang) * link.centre
        cp = p + np.sin(ang) * link.centre
        centres.append((link.mass, np.column_stack([cx, cp, np.zeros_like(cx)] if vertical
                                                   else [cx, height, cp])))  # fmt: skip
    total = sum(m for m, _ in centres)
    com = sum(m * c_ for m, c_ in centres) / total
    cmds = np.asarray(rollout.commands, float)
    cmds = cmds[near] if cmds.ndim == 2 and len(cmds) == len(recorded) else np.zeros((0, 0))
    acts = np.clip((cmds + 2.0) / 4.0, 0.0, 1.0).astype(np.float32) if cmds.size else None
    names = tuple(a.name for a in tuned.actuators)
    creature = Creature(tuned.name, tuple(links), com.astype(np.float32), names, acts)
    medium = get_medium("ground" if tuned.medium == "ground" else "water")
    speed = speed_cm_s(tuned, rollout.metric, rollout.distance, rollout.seconds)
    numbers = {"metric": round(float(rollout.metric), 4), "speed_cm_s": round(speed, 2),
               "fell": bool(rollout.fell), "distance_m": round(_travelled(com), 3)}  # fmt: skip
    return Scene(f"{tuned.name} SAN ({run.name})", "san", times - times[0], fps, medium, (),
                 numbers=numbers, creatures=(creature,))  # fmt: skip


def load_scene(run_dir: str | Path, fps: float = 30.0) -> Scene:
    """Return the Scene of a run directory, its motion resampled at ``fps`` frames per second."""
    run, fps = Path(run_dir), float(fps)
    if not run.is_dir():
        raise RunDirError(f"{run}: not a directory")
    if fps <= 0:
        raise RunDirError(f"the frame rate must be positive, got {fps}")
    if (run / "trajectory.npz").exists():
        return _from_trajectory(run, fps)
    if (run / "controller.json").exists() and (
        (run / "config.toml").exists() or (run / "summary.json").exists()
    ):
        return _from_controller(run, fps)
    if (run / "san.json").exists() or (run / "sans" / "01.json").exists():
        return _from_san(run, fps)
    raise RunDirError(
        f"{run}: no trajectory.npz, nor controller.json with config.toml or summary.json, nor "
        "san.json or sans/01.json; views come from simulate, learn, track, macro, sequence and "
        "san search/tune runs"
    )
