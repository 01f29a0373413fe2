"""Binocular foveated eyes on an animal's head (Terzopoulos & Rabie's animat vision).

Each eye images ``levels`` coaxial component images of ``size`` x ``size`` pixels, the field of
view halving per level: l = 0 .. levels-2 peripheral, the last the high-acuity fovea; they are
composited into one retinal image with white borders (seed 003, Fig. 5). An eye turns by theta
(azimuth, left positive) and phi (elevation, up positive) relative to the head. The head frame
is the best rotation (Kabsch) carrying the head node and its spring neighbours from the rest
pose onto the current one, so it wags with the body as the fish undulates.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from zoetic.bodies import Body
from zoetic.errors import ZoeticError
from zoetic.render import Cameras, look_rotation, render
from zoetic.render.scene import Mesh

LEFT, RIGHT = 0, 1


@dataclass(frozen=True)
class EyeSpec:
    """Two eyes: component image size (px), levels, level-0 field of view (rad), the left
    eye's offset (3,) m from the node they ride on along the head's forward, up and left axes
    (the right eye mirrored across left), and the water's visibility (fog e-folding distance,
    m; 0 clear). An animal's eyes come from its file's [eyes] table: ``EyeSpec.of(body)``."""

    size: int
    levels: int
    fov: float
    offset: tuple[float, float, float]
    visibility: float = 6.0

    @classmethod
    def of(cls, body: Body, visibility: float = 6.0) -> EyeSpec:
        """Return the eyes declared in the body's animal file; raise ZoeticError if it has
        none."""
        if body.eye_node is None or body.eye_offset is None:
            raise ZoeticError(
                f"{body.source}: animal {body.name!r} has no eyes; add an [eyes] "
                "table (see docs/animals.md)"
            )
        return cls(
            int(body.eye_pixels),
            int(body.eye_levels),
            float(body.eye_fov),
            tuple(float(v) for v in body.eye_offset),
            visibility,
        )

    @property
    def fovs(self) -> np.ndarray:
        """Return the (levels,) fields of view in rad, halving per level."""
        return self.fov / 2.0 ** np.arange(self.levels)

    @property
    def focals(self) -> np.ndarray:
        """Return the (levels,) focal lengths in pixels."""
        return 0.5 * self.size / np.tan(0.5 * self.fovs)


@dataclass(frozen=True)
class HeadFrame:
    """Where the head is: origin (3,) m (the head node), and forward, up, left unit axes."""

    origin: np.ndarray
    forward: np.ndarray
    up: np.ndarray
    left: np.ndarray

    @property
    def matrix(self) -> np.ndarray:
        """Return the (3, 3) rows forward, up, left."""
        return np.stack([self.forward, self.up, self.left])


def eye_node(body: Body) -> int:
    """Return the node the eyes ride on (the head node for an animal without eyes)."""
    return body.head if body.eye_node is None else body.eye_node


def head_cluster(body: Body) -> np.ndarray:
    """Return the indices of the eyes' node and the nodes it is sprung to."""
    h = eye_node(body)
    nb = np.concatenate([body.spring_b[body.spring_a == h], body.spring_a[body.spring_b == h]])
    return np.unique(np.concatenate([[h], nb]))


def head_frame(body: Body, positions: np.ndarray) -> HeadFrame:
    """Return the head frame of one animal's pose (N, 3), its origin at the eyes' node."""
    return _fitted_frame(body, positions, _head_cluster(body), eye_node(body))


@lru_cache(maxsize=64)
def _head_cluster(body: Body) -> np.ndarray:
    """``head_cluster`` of a body, found once (a brain period asks for it every frame)."""
    return head_cluster(body)


def body_frame(body: Body, positions: np.ndarray) -> HeadFrame:
    """Return the whole body's frame (the best rotation of all its nodes, origin at the head
    node): its mean heading, which hardly wags as the body undulates."""
    return _fitted_frame(body, positions, np.arange(len(body.rest_pos)), body.head)


def _fitted_frame(body: Body, positions: np.ndarray, idx: np.ndarray, origin: int) -> HeadFrame:
    r0 = body.rest_pos[idx] - body.rest_pos[idx].mean(0)
    x = positions[idx] - positions[idx].mean(0)
    u, _, vt = np.linalg.svd(r0.T @ x)
    rot = (u @ vt).T  # carries rest vectors onto current ones
    if np.linalg.det(rot) < 0:
        vt[2] *= -1
        rot = (u @ vt).T
    f0 = body.forward
    up0 = np.array([0.0, 1.0, 0.0]) - f0[1] * f0
    f, up = rot @ f0, rot @ (up0 / np.linalg.norm(up0))
    return HeadFrame(np.asarray(positions[origin], float), f, up, np.cross(f, up))


def gaze_direction(frame: HeadFrame, theta, phi) -> np.ndarray:
    """Return unit gaze directions (..., 3) for angles theta, phi (rad) relative to the head."""
    th, ph = np.asarray(theta, float)[..., None], np.asarray(phi, float)[..., None]
    return (
        np.cos(ph) * (np.cos(th) * frame.forward + np.sin(th) * frame.left) + np.sin(ph) * frame.up
    )


def gaze_angles(frame: HeadFrame, direction) -> tuple[np.ndarray, np.ndarray]:
    """Return (theta, phi) in rad of world directions (..., 3) relative to the head."""
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    th = np.arctan2(d @ frame.left, d @ frame.forward)
    return th, np.arcsin(np.clip(d @ frame.up, -1.0, 1.0))


def eye_positions(frame: HeadFrame, spec: EyeSpec) -> np.ndarray:
    """Return the (2, 3) positions of the left and right eyes in m."""
    fwd, up, side = spec.offset
    c = frame.origin + fwd * frame.forward + up * frame.up
    return np.stack([c + side * frame.left, c - side * frame.left])


def eye_cameras(frame: HeadFrame, angles: np.ndarray, spec: EyeSpec) -> Cameras:
    """Return the 2 x levels cameras (left eye's levels first) for gaze angles (2, 2) rows
    (theta, phi) per eye."""
    a = np.asarray(angles, float)
    rot = look_rotation(gaze_direction(frame, a[:, 0], a[:, 1]), frame.up)  # (2, 3, 3)
    pos = eye_positions(frame, spec)
    n = spec.levels
    return Cameras(
        np.repeat(pos, n, 0), np.repeat(rot, n, 0), np.tile(spec.fovs, 2), (spec.size, spec.size)
    )


def look(
    mesh: Mesh, frame: HeadFrame, angles: np.ndarray, spec: EyeSpec, fog_color=(0.05, 0.25, 0.35)
) -> tuple[np.ndarray, Cameras]:
    """Return both eyes' component images (2, levels, size, size, 3) uint8 and their cameras."""
    cams = eye_cameras(frame, angles, spec)
    img = render(mesh.vertices, mesh.triangles, mesh.colors, cams, fog_color, spec.visibility)
    return img.reshape(2, spec.levels, spec.size, spec.size, 3), cams


def pixel_direction(cameras: Cameras, index: int, col: float, row: float) -> np.ndarray:
    """Return the world direction (3,) seen at continuous pixel (col, row) of a camera."""
    w, h = cameras.size
    f = cameras.focal[index]
    d = np.array([(col - 0.5 * w) / f, (0.5 * h - row) / f, 1.0])
    d = cameras.rotation[index].T @ d
    return d / np.linalg.norm(d)


def composite(levels: np.ndarray, out: int = 256, border: bool = True) -> np.ndarray:
    """Return one retinal image (out, out, 3) from component images (L, S, S, 3): level l
    drawn over the centre out / 2**l pixels (nearest neighbour), borders in white."""
    img = np.zeros((out, out, 3), np.uint8)
    n_lev, s = levels.shape[0], levels.shape[1]
    for lev in range(n_lev):
        w = max(1, out >> lev)
        o = (out - w) // 2
        idx = (np.arange(w) * s) // w
        img[o : o + w, o : o + w] = levels[lev][idx[:, None], idx[None, :]]
        if border and lev > 0:
            img[o, o : o + w] = img[o + w - 1, o : o + w] = 255
            img[o : o + w, o] = img[o : o + w, o + w - 1] = 255
    return img
