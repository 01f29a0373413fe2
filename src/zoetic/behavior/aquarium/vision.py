"""Animat vision for a fish of the tank (``--perception vision``): the perception issue's two
foveated eyes (``perception.eyes``), colour-model recognition (``perception.recognition``) and
gaze control (``perception.gaze``), as ``zoetic pursue`` uses them (``perception.pursuit``).

Every brain period the fish renders what its eyes see of the tank (fishes in their species'
colours, rocks, seaweed and walls through the water's fog), foveates whatever matches the
colour histogram of its prey species and verges both eyes on it. The prey it perceives is the
live prey fish the gaze rests on (some node within twice the fovea's half angle of a gaze
ray), at the range the eyes triangulate (or, with one eye locked, along that eye's ray at the
distance of the fish's nearest node to it), and placed at the point the gaze fixates: the
brain hunts what it sees, where it sees it. Everything else it perceives stays the oracle's.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from zoetic.bodies import Body
from zoetic.perception.eyes import EyeSpec, head_frame, look
from zoetic.perception.gaze import GazeController, GazeState, fixation
from zoetic.perception.pursuit import FOG, Scenery, learn_model
from zoetic.physics.world import World


@dataclass(frozen=True)
class Sighting:
    """What the eyes report: the prey fish seen (index in the tank), its range (m) and the
    point fixated (3,)."""

    fish: int
    distance: float
    point: np.ndarray


@dataclass
class FishEyes:
    """One fish's eyes in a tank: ``see`` once a brain period."""

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
        spec = self.gaze.spec
        frame = head_frame(self.body, world.positions(self.animal)[0])
        self.state = self.gaze.hold(self.state, frame)
        images, cams = look(self.scenery.mesh(world), frame, self.state.angles, spec, FOG)
        self.state = self.gaze.step(self.state, frame, images, cams)
        self.frames += 1
        locked = self.state.locked
        if not locked.any() or len(prey) == 0:
            return None
        eyes = cams.eye[:: spec.levels]
        dirs = self.state.directions
        use = np.flatnonzero(locked)
        half = 0.5 * spec.fovs[-1]
        best, best_off = None, 2.0 * half
        for j in prey:
            nodes = world.positions(int(j))[0]
            to = nodes[None] - eyes[use, None]
            to /= np.linalg.norm(to, axis=-1, keepdims=True)
            off = float(np.arccos(np.clip((to * dirs[use, None]).sum(-1), -1, 1)).min())
            if off < best_off:
                best, best_off = int(j), off
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
