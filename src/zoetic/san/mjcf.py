"""Creature -> MJCF: the MuJoCo model of a planar creature and its ground.

The plane is MuJoCo's x-z plane. The root link gets a planar root (slide x, slide z, hinge
about -y, so positive angles turn x towards z, counter-clockwise as drawn with x right and z
up); the other links are nested bodies with hinge (about -y), slide (along the child's own x)
or no joint (fixed). Each link is one geom spanning its frame from (start, 0) to
(start + length, 0).
Links collide with the ground only, never with each other. Actuators are MuJoCo position
servos (kp = ks, kv = kd) whose control is the desired joint coordinate, so the PD law runs
in C at every physics step. Vertical creatures stand on a plane (``flat``) or on a height field
(``rough``, a piecewise-linear profile); horizontal (top-view) creatures have no gravity and
no contacts: their media act through ``World`` as applied forces.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import quoteattr

import numpy as np

from zoetic.san.creature import Creature

__all__ = ["GRAVITY", "HILL_SLOPE", "build_mjcf", "hill_profile", "plane_quat", "rough_profile"]

GRAVITY = 9.81
HILL_SLOPE = 0.1  # rise over run of ``hill_profile`` (5.7 degrees)


def plane_quat(angle: float) -> str:
    """Return the MJCF quaternion of a rotation by ``angle`` (rad) in the x-z plane."""
    return f"{math.cos(angle / 2):.17g} 0 {-math.sin(angle / 2):.17g} 0"


def _f(*vals: float) -> str:
    return " ".join(f"{float(v):.17g}" for v in vals)


def rough_profile(
    height: float, seed: int, half_width: float = 40.0, spacing: float = 0.05, flat: float = 0.5
) -> np.ndarray:
    """Return a seeded uneven ground profile (K, 2) of [x, z] points, flat near x = 0.

    Heights are smoothed uniform noise in [0, ``height``] (m), ramped in over 0.5 m beyond
    the flat start zone |x| < ``flat``.
    """
    rng = np.random.default_rng(seed)
    x = np.arange(-half_width, half_width + spacing / 2, spacing)
    coarse = rng.uniform(0.0, 1.0, size=x.size // 4 + 2)
    z = np.interp(np.arange(x.size) / 4.0, np.arange(coarse.size), coarse)
    z = np.convolve(z, np.ones(3) / 3.0, mode="same")
    ramp = np.clip((np.abs(x) - flat) / 0.5, 0.0, 1.0)
    return np.stack([x, height * z * ramp], axis=1)


def hill_profile(
    slope: float = HILL_SLOPE, half_width: float = 10.0, spacing: float = 0.05, flat: float = 0.5
) -> np.ndarray:
    """Return a valley profile (K, 2): flat for |x| < ``flat``, then uphill either way (Fig. 13).

    The creature starts on the flat floor and, whichever way it goes, climbs at ``slope``.
    """
    x = np.arange(-half_width, half_width + spacing / 2, spacing)
    return np.stack([x, slope * np.clip(np.abs(x) - flat, 0.0, None)], axis=1)


def _geom(link, contact: str) -> str:
    L, r, x0, xc = link.length, link.radius, link.start, link.centre
    if link.inertia is not None:
        mass_attr = 'density="0"'
    else:
        mass_attr = f'mass="{_f(link.mass)}"'
    if link.shape == "capsule":
        g = f'type="capsule" fromto="{_f(x0)} 0 0 {_f(x0 + L)} 0 0" size="{_f(r)}"'
    elif link.shape == "box":
        g = f'type="box" pos="{_f(xc)} 0 0" size="{_f(L / 2, link.out_of_plane / 2, r)}"'
    else:
        g = f'type="sphere" pos="{_f(xc)} 0 0" size="{_f(r)}"'
    out = f"<geom name={quoteattr(link.name)} {g} {mass_attr} {contact}/>"
    if link.inertia is not None:
        i = link.inertia
        out = (
            f'<inertial pos="{_f(xc)} 0 0" mass="{_f(link.mass)}" diaginertia="{_f(i, i, i)}"/>'
            + out
        )
    return out


def _joints_xml(joint, root_z: float) -> tuple[str, str, list[str]]:
    """Return a body's position, orientation and joint elements for the joint that attaches
    it to its parent (None: the root, which slides and turns freely in the plane)."""
    if joint is None:
        # the root's joint axes live in its own frame: keep it unrotated; World sets the
        # start angle through the root hinge's qpos
        return (
            _f(0, 0, root_z),
            "1 0 0 0",
            [
                '<joint name="root_x" type="slide" axis="1 0 0" limited="false"/>',
                '<joint name="root_z" type="slide" axis="0 0 1" limited="false"/>',
                '<joint name="root_a" type="hinge" axis="0 -1 0" limited="false"/>',
            ],
        )
    ca, sa = math.cos(joint.angle), math.sin(joint.angle)
    ax, az = joint.anchor
    pos = _f(ax + joint.offset * ca, 0, az + joint.offset * sa)
    if joint.kind == "fixed":
        return pos, plane_quat(joint.angle), []
    typ, axis = ("hinge", "0 -1 0") if joint.kind == "hinge" else ("slide", "1 0 0")
    extra = f'stiffness="{_f(joint.stiffness)}" damping="{_f(joint.damping)}"'
    if joint.range is not None:
        extra += f' limited="true" range="{_f(*joint.range)}"'
    else:
        extra += ' limited="false"'
    element = f'<joint name={quoteattr(joint.name)} type="{typ}" axis="{axis}" {extra}/>'
    return pos, plane_quat(joint.angle), [element]


def _bodies_xml(creature: Creature, contact: str, root_z: float) -> list[str]:
    """Return the nested <body> elements of the creature's link tree, root first."""
    children: dict[str, list] = {}
    for j in creature.joints:
        children.setdefault(j.parent, []).append(j)
    links = {ln.name: ln for ln in creature.links}

    def body(name: str, joint, indent: str) -> list[str]:
        pos, quat, jx = _joints_xml(joint, root_z)
        lines = [f'{indent}<body name={quoteattr(name)} pos="{pos}" quat="{quat}">']
        lines += [indent + "  " + x for x in jx]
        lines.append(indent + "  " + _geom(links[name], contact))
        for cj in children.get(name, []):
            lines += body(cj.child, cj, indent + "  ")
        lines.append(indent + "</body>")
        return lines

    return body(creature.links[0].name, None, "    ")


def _ground_xml(terrain: np.ndarray | None, fr: str) -> tuple[str, str]:
    """Return the <asset> (a height field for a terrain profile) and the ground's <geom>."""
    if terrain is None:
        plane = f'<geom name="ground" type="plane" size="0 0 1" {fr} contype="1" conaffinity="2"/>'
        return "", plane
    x, z = terrain[:, 0], terrain[:, 1]
    top = max(float(z.max()), 1e-6)
    rx = (x[-1] - x[0]) / 2
    asset = (
        f'<asset><hfield name="terrain" nrow="3" ncol="{len(x)}" '
        f'size="{_f(rx, 1.0, top, 0.1)}"/></asset>'
    )
    floor = (
        '<geom name="ground" type="hfield" hfield="terrain" '
        f'pos="{_f((x[0] + x[-1]) / 2)} 0 0" {fr} contype="1" conaffinity="2"/>'
    )
    return asset, floor


def build_mjcf(creature: Creature, terrain: np.ndarray | None = None, root_z: float = 0.0) -> str:
    """Return the MJCF text of ``creature`` on flat ground or on the ``terrain`` profile (K, 2)."""
    c = creature
    vertical = c.plane == "vertical"
    gravity = f"0 0 {-GRAVITY}" if vertical else "0 0 0"
    # MuJoCo combines two geoms' friction with max(): the links carry the ground's coefficient
    # too, or their default 1.0 would override any lower ``friction``
    fr = f'friction="{_f(c.friction)} 0.005 0.0001"'
    contact = f'contype="2" conaffinity="0" {fr}' if vertical else 'contype="0" conaffinity="0"'
    asset, floor = _ground_xml(terrain, fr) if vertical else ("", "")
    acts = [
        f"<position name={quoteattr(a.name)} joint={quoteattr(a.joint)} "
        f'kp="{_f(a.ks)}" kv="{_f(a.kd)}" ctrllimited="false" forcelimited="false"/>'
        for a in c.actuators
    ]
    flags = "" if vertical else '<flag contact="disable"/>'
    parts = [
        f"<mujoco model={quoteattr(c.name)}>",
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{_f(c.dt)}" gravity="{gravity}" integrator="implicitfast">{flags}'
        "</option>",
        f"  {asset}",
        "  <worldbody>",
        f"    {floor}",
        *_bodies_xml(c, contact, root_z),
        "  </worldbody>",
        "  <actuator>",
        *["    " + a for a in acts],
        "  </actuator>",
        "</mujoco>",
    ]
    return "\n".join(parts)
