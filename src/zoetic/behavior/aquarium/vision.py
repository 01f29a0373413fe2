"""Animat vision for the seeing fishes of the tank (``--perception vision``, the first
``--seeing`` predators): the perception issue's two foveated eyes (``perception.eyes``),
colour-model recognition (``perception.recognition``) and gaze control
(``perception.gaze``), as ``zoetic pursue`` uses them (``perception.pursuit``).

Every brain period the fish renders what its eyes see of the tank (fishes in their species'
colours, rocks, seaweed and walls through the water's fog), foveates whatever matches the
colour histogram of its prey species and verges both eyes on it. The prey it perceives is the
live prey fish the gaze rests on (some node within twice the fovea's half angle of a gaze
ray), at the range the eyes triangulate (or, with one eye locked, along that eye's ray at the
distance of the fish's nearest node to it), and placed at the point the gaze fixates: the
brain hunts what it sees, where it sees it. Everything else it perceives stays the oracle's.
``TankEyes`` makes all the seeing fishes' retinas at once: one mesh, one rasteriser call and
one recognition pass for the two finest levels of every eye, and one more for the coarser
levels of the fishes whose fine levels miss their prey (the same images and numbers as each
fish's eyes alone, ``FishEyes.see``, wherever the gaze looks).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zoetic.bodies import Body
from zoetic.perception.eyes import EyeSpec, HeadFrame, eye_cameras, head_frame
from zoetic.perception.gaze import GazeController, GazeState, fixation
from zoetic.perception.pursuit import FOG, Scenery, learn_model
from zoetic.perception.recognition import N_BINS, Recognition, recognise
from zoetic.physics.world import World
from zoetic.render import Cameras, render
from zoetic.render.scene import Mesh


@dataclass(frozen=True)
class Sighting:
    """What the eyes report: the prey fish seen (index in the tank), its range (m) and the
    point fixated (3,)."""

    fish: int
    distance: float
    point: np.ndarray


@dataclass
class FishEyes:
    """One fish's eyes in a tank: ``see`` once a brain period (alone), or ``aim`` its cameras
    and ``react`` to the images they took (``TankEyes`` renders all fishes' eyes at once)."""

    animal: int
    body: Body
    scenery: Scenery
    gaze: GazeController
    state: GazeState = field(default_factory=GazeState)
    frames: int = 0

    @classmethod
    def build(
        cls,
        animal: int,
        body: Body,
        colors,
        prey_body: Body,
        prey_color,
        view_range: float,
        floor: float,
        extent: float,
    ) -> FishEyes:
        """Return eyes for animal ``animal`` (``body``) of a world whose animals wear
        ``colors`` (RGB in [0, 1]), hunting ``prey_body`` in ``prey_color``; the water's
        visibility is ``view_range`` m, the seabed at height ``floor`` spans ``extent`` m."""
        spec = EyeSpec.of(body, visibility=view_range)
        model = learn_model(prey_body, prey_body.rest_pos, prey_color, spec)
        scenery = Scenery(tuple(tuple(c) for c in colors), floor=(0.0, 0.0, floor, extent))
        return cls(animal, body, scenery, GazeController(model, spec))

    def see(self, world: World, prey: np.ndarray) -> Sighting | None:
        """Render, recognise, move the eyes; return the prey fish the gaze rests on (among
        the indices ``prey``: live prey fishes) or None."""
        frame, cams = self.aim(world)
        spec = self.gaze.spec
        images = render_eyes(self.scenery.mesh(world), cams, spec)
        return self.react(world, frame, images[0], cams, prey)

    def aim(self, world: World) -> tuple[HeadFrame, Cameras]:
        """Return the head frame now and the eyes' cameras, the gaze held on its world
        directions through the head's motion since the last frame."""
        frame = head_frame(self.body, world.positions(self.animal)[0])
        self.state = self.gaze.hold(self.state, frame)
        return frame, eye_cameras(frame, self.state.angles, self.gaze.spec)

    def react(
        self,
        world: World,
        frame: HeadFrame,
        images: np.ndarray,
        cams: Cameras,
        prey: np.ndarray,
        seen: Recognition | None = None,
    ) -> Sighting | None:
        """Recognise the prey in the images (2, levels, size, size, 3) the cameras ``cams``
        took (or take what ``recognise`` found in them: ``seen``), move the eyes; return the
        prey fish the gaze rests on or None."""
        spec = self.gaze.spec
        self.state = self.gaze.step(self.state, frame, images, cams, seen)
        self.frames += 1
        locked = self.state.locked
        if not locked.any() or len(prey) == 0:
            return None
        return self._sighting(world, frame, cams.eye[:: spec.levels], prey)

    def _sighting(
        self, world: World, frame: HeadFrame, eyes: np.ndarray, prey: np.ndarray
    ) -> Sighting | None:
        """Return the prey fish some locked eye's gaze ray passes within twice the fovea's
        half angle of, nearest first, at the triangulated range (or along the ray)."""
        spec = self.gaze.spec
        locked = self.state.locked
        dirs = self.state.directions
        use = np.flatnonzero(locked)
        half = 0.5 * spec.fovs[-1]
        # every prey node's angle off the nearest locked gaze ray, all prey at once
        rows, starts = prey_rows(world.offsets, prey)
        to = world.node_positions()[rows][None] - eyes[use, None]
        to /= np.sqrt((to * to).sum(-1))[..., None]
        cos = np.clip((to * dirs[use, None]).sum(-1), -1, 1).max(0)
        near = np.maximum.reduceat(cos, starts)
        k = int(np.argmax(near))  # the first prey fish nearest a gaze ray
        off = float(np.arccos(near[k]))
        best = int(prey[k]) if off < 2.0 * half else None
        if best is None:
            return None
        point, rng = fixation(frame, self.state.angles, spec) if locked.all() else (None, np.inf)
        if not np.isfinite(rng) or rng > 2.0 * spec.visibility:
            e, d = eyes[use[0]], dirs[use[0]]
            nodes = world.positions(best)[0]
            along = (nodes - e) @ d
            miss = np.linalg.norm(nodes - e - along[:, None] * d, axis=1)
            rng = float(max(along[np.argmin(miss)], 0.0))
            point = e + rng * d
        return Sighting(best, float(rng), np.asarray(point, float))


def prey_rows(offsets: np.ndarray, prey: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows of the fishes ``prey`` in ``World.node_positions`` (``offsets``: its
    ``World.offsets``), one fish after another, and where each fish's rows start among them."""
    prey = np.asarray(prey, np.int64)
    first, counts = offsets[prey], offsets[prey + 1] - offsets[prey]
    starts = np.cumsum(counts) - counts
    return np.repeat(first - starts, counts) + np.arange(counts.sum()), starts


def render_eyes(mesh: Mesh, cams: Cameras, spec: EyeSpec) -> np.ndarray:
    """Return the images (F, 2, levels, size, size, 3) uint8 of F fishes' eyes' cameras
    (2 levels cameras a fish, in ``eye_cameras``' order, one after another) in one pass."""
    img = render(mesh.vertices, mesh.triangles, mesh.colors, cams, FOG, spec.visibility)
    return img.reshape(-1, 2, spec.levels, spec.size, spec.size, 3)


@dataclass
class TankEyes:
    """The eyes of every seeing fish of a tank, rendered together once a brain period: the
    world's triangles built once (``scenery``), all fishes' cameras drawn in one or two
    rasteriser calls (``_look``; per eye design, should the seeing species differ)."""

    eyes: list[FishEyes]
    scenery: Scenery

    @property
    def animals(self) -> list[int]:
        """Return the seeing fishes' indices in the tank."""
        return [e.animal for e in self.eyes]

    def see(self, world: World, prey: dict[int, np.ndarray]) -> dict[int, Sighting | None]:
        """Render every seeing fish of ``prey`` (animal -> indices of the live prey fishes it
        hunts), recognise, move the eyes; return per fish the prey its gaze rests on."""
        seers = [e for e in self.eyes if e.animal in prey]
        if not seers:
            return {}
        aims = [e.aim(world) for e in seers]
        mesh = self.scenery.mesh(world)
        images: list = [None] * len(seers)
        seen: list = [None] * len(seers)
        for spec in dict.fromkeys(e.gaze.spec for e in seers):
            idx = [k for k, e in enumerate(seers) if e.gaze.spec == spec]
            drawn, found = _look(mesh, [seers[k] for k in idx], [aims[k][1] for k in idx], spec)
            for n, k in enumerate(idx):
                images[k], seen[k] = drawn[n], found[n]
        return {
            e.animal: e.react(world, frame, images[k], c, prey[e.animal], seen[k])
            for k, (e, (frame, c)) in enumerate(zip(seers, aims, strict=True))
        }


def _look(
    mesh: Mesh, seers: list[FishEyes], cams: list[Cameras], spec: EyeSpec
) -> tuple[np.ndarray, list[Recognition]]:
    """Return the images (F, 2, levels, size, size, 3) of F fishes' eyes of one design and
    what each fish's prey model finds in them (``recognise``, per fish its 2 x levels
    images). The two finest levels of every eye are drawn and recognised first, all fishes
    in one rasteriser call; the coarser ones only for the fishes with an eye whose fine
    levels miss the prey, since the gaze looks in a coarser level only then
    (``GazeController.step``). The others' coarser images stay blank and unrecognised."""
    n, f, size = spec.levels, len(seers), spec.size
    images = np.zeros((f, 2, n, size, size, 3), np.uint8)
    hist = np.zeros((f, 2, n, N_BINS))
    grays = np.zeros((f, 2, n, size, size))
    targets = np.zeros((f, 2, n, size, size))
    dets = np.full((f, 2, n), None, object)
    strength = np.zeros((f, 2, n))
    every = _stack(cams)
    models = np.stack([e.gaze.model for e in seers])

    def draw(sel: np.ndarray, compared: bool) -> None:
        """Draw and recognise the cameras ``sel`` (F, 2, levels) marks; their grays and
        target images too if ``compared``."""
        use = np.flatnonzero(sel)
        sub = Cameras(every.eye[use], every.rotation[use], every.fov[use], every.size)
        img = render(mesh.vertices, mesh.triangles, mesh.colors, sub, FOG, spec.visibility)
        keep = None if compared else np.zeros(len(img), bool)
        found = recognise(img, models[use // (2 * n)], keep=keep)
        images[sel], hist[sel] = img, found.histograms
        grays[sel], targets[sel] = found.grays, found.targets
        listed = np.empty(len(use), object)
        listed[:] = found.detections
        dets[sel] = listed
        strength[sel] = [d.strength for d in found.detections]

    fine = np.broadcast_to(np.arange(n) >= n - 2, (f, 2, n))
    draw(fine, True)
    thresholds = np.array([e.gaze.threshold for e in seers])[:, None, None]
    missed = ~((strength >= thresholds) & fine).any(2).all(1)  # a fish with an eye that misses
    if missed.any() and n > 2:
        draw(~fine & missed[:, None, None], False)
    found = [
        Recognition(
            hist[k].reshape(2 * n, N_BINS),
            list(dets[k].ravel()),
            grays[k].reshape(2 * n, size, size),
            targets[k].reshape(2 * n, size, size),
        )
        for k in range(f)
    ]
    return images, found


def _stack(cams: list[Cameras]) -> Cameras:
    """Return one Cameras holding several's (all of one image size)."""
    if len(cams) == 1:
        return cams[0]
    return Cameras(
        np.concatenate([c.eye for c in cams]),
        np.concatenate([c.rotation for c in cams]),
        np.concatenate([c.fov for c in cams]),
        cams[0].size,
    )
