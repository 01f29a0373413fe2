"""The compiled model: one animal's physics in one medium at one step, as named arrays.

``compile_model(body, medium, dt)`` turns a Body (what the animal IS) into what every backend
steps by: node masses, springs and muscles, water panels, fins, the stiff/slow spring split of
``multirate.split`` and the medium's constants. A ``Model`` is a ``typing.NamedTuple``: the
Numba kernel takes it as one tuple argument and reads its fields by name in compiled code, the
NumPy reference and the JAX mirror read the same fields through ``physics.law``, and it is a
JAX pytree. No backend depends on the order of its fields.

Arrays are in the model's precision (float32 for the kernel and JAX, float64 for the NumPy
reference) or int64 indices, C-contiguous and read-only; the medium's constants and the step
are Python floats. Each field's kind is in its annotation (``Reals``/``Index`` and the number
of axes), which ``compile_model`` enforces, so that every model has the same Numba type.
"""

from __future__ import annotations

import dataclasses
import typing
import weakref
from typing import Annotated, NamedTuple

import numpy as np

from zoetic.bodies import Body
from zoetic.physics.media import Medium, get_medium
from zoetic.physics.multirate import split

REAL, INDEX = "real", "index"
NO_WATER = -1e8  # a water level at or below this (``media.FAR`` below zero) means no water
Reals1 = Annotated[np.ndarray, REAL, 1]
Reals2 = Annotated[np.ndarray, REAL, 2]
Index1 = Annotated[np.ndarray, INDEX, 1]
Index2 = Annotated[np.ndarray, INDEX, 2]


class Model(NamedTuple):
    """A body's arrays, its spring split and its medium, as every backend steps them.

    N nodes, S springs, A actuators, P water panels, K fins. A spring's rest length at
    activation a (its actuator's column ``spring_col``) is relaxed + a * (contracted - relaxed).
    """

    # nodes
    mass: Reals1  # (N,) kg
    node_damping: Reals1  # (N,) N s/m, implicit in the step
    rest_pos: Reals2  # (N, 3) m: where the kernel puts a lane that blew up
    axis_front: Index1  # (N,) the neighbour ahead (the local axis the floor's friction uses)
    axis_back: Index1  # (N,) the neighbour behind
    # springs and muscles
    spring_a: Index1  # (S,)
    spring_b: Index1  # (S,)
    stiffness: Reals1  # (S,) N/m
    spring_damping: Reals1  # (S,) N s/m
    relaxed: Reals1  # (S,) m
    contracted: Reals1  # (S,) m, equal to relaxed for passive springs
    shorten: Reals1  # (S,) m: contracted - relaxed rounded once from double (the kernel's)
    spring_col: Index1  # (S,) the activation column a spring reads (0 for passive springs)
    # the multirate split at dt: the fast springs are sub-stepped (``multirate.split``)
    slow_springs: Index1
    fast_springs: Index1
    slow_nodes: Index1  # touched by no fast spring: stepped once a step
    fast_nodes: Index1  # touched by a fast spring: one kick, then the sub-steps
    substeps: int
    # water panels: a triangle repeats its third node with weight 0
    panels: Index2  # (P, 4)
    panel_weights: Reals2  # (P, 4) each node's share (1/3 or 1/4, 0 for the repeat)
    panel_drag: Reals1  # (P,) a factor on the medium's drag
    panel_mass_dt: Reals1  # (P,) the panel's own mass over dt (the most a step can stop)
    # fins: flat plates at an angle set by their actuator
    fin_nodes: Index2  # (K, 4) padded with -1
    fin_weights: Reals2  # (K, 4) each node's share (0 for padding)
    fin_mass: Reals1  # (K,) kg: the fin's nodes together
    fin_forward: Index2  # (K, 2) the forward axis is x[0] - x[1]
    fin_span: Index2  # (K, 2) the span axis is x[0] - x[1]
    fin_area: Reals1  # (K,) m^2
    fin_angle: Reals2  # (K, 2) rad at activation 0 and 1
    fin_actuator: Index1  # (K,)
    # the medium (``media.Medium``) and the step
    gravity: float
    water_level: float
    buoyancy: float
    water_drag: float
    floor: bool
    floor_stiffness: float
    floor_damping: float
    friction_forward: float
    friction_backward: float
    friction_lateral: float
    dt: float

    @property
    def water(self) -> bool:
        """Return True if the medium has water that drags (a level above -FAR, some drag)."""
        return self.water_drag > 0 and self.water_level > NO_WATER


def field_kinds() -> dict[str, tuple[str, int] | type]:
    """Return each Model field's kind: (REAL or INDEX, number of axes) for an array, else
    its Python type (float, bool, int)."""
    hints = typing.get_type_hints(Model, include_extras=True)
    return {
        name: tuple(hint.__metadata__) if hasattr(hint, "__metadata__") else hint
        for name, hint in hints.items()
    }


_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def compile_model(
    body: Body, medium: Medium | str | None = None, dt: float | None = None, dtype=np.float32
) -> Model:
    """Return the Model of ``body`` in ``medium`` (default its own) at step ``dt`` (default its
    own), with real arrays in ``dtype``; built once per body object, medium, step and dtype."""
    med = get_medium(medium or body.medium)
    dt = float(dt or body.dt)
    key = (med, dt, np.dtype(dtype).str)
    per_body = _MODELS.setdefault(body, {})
    if key not in per_body:
        per_body[key] = _compile(body, med, dt, np.dtype(dtype))
    return per_body[key]


def _compile(body: Body, med: Medium, dt: float, dtype: np.dtype) -> Model:
    raw = _body_arrays(body, dt) | _split_arrays(body, dt) | _medium_fields(med, dt)
    fields = {}
    for name, kind in field_kinds().items():
        value = raw[name]
        if isinstance(kind, tuple):
            value = np.array(value, dtype=dtype if kind[0] == REAL else np.int64, order="C")
            if value.ndim != kind[1]:
                raise ValueError(f"Model.{name}: {value.ndim} axes, expected {kind[1]}")
            value.setflags(write=False)
        else:
            value = kind(value)
        fields[name] = value
    return Model(**fields)


def _body_arrays(body: Body, dt: float) -> dict:
    """The body's arrays in double precision, by Model field name: those the Body holds under
    the same name, and what the backends derive from them."""
    same = {
        name: getattr(body, name)
        for name in Model._fields
        if isinstance(getattr(body, name, None), np.ndarray)
    }
    muscle = body.spring_actuator >= 0
    w = body.panel_weights
    mask = body.fin_nodes >= 0
    return same | dict(
        shorten=np.where(muscle, body.contracted - body.relaxed, 0.0),
        spring_col=np.where(muscle, body.spring_actuator, 0),
        panel_mass_dt=np.einsum("pk,pk->p", body.mass[body.panels], w) / (w[:, 0] * dt),
        fin_weights=mask / np.maximum(mask.sum(axis=1), 1)[:, None],
        fin_mass=(body.mass[np.where(mask, body.fin_nodes, 0)] * mask).sum(axis=1),
    )


def _split_arrays(body: Body, dt: float) -> dict:
    sp = split(body, dt)
    return dict(
        slow_springs=sp.slow_springs,
        fast_springs=sp.fast_springs,
        slow_nodes=sp.slow_nodes,
        fast_nodes=sp.fast_nodes,
        substeps=sp.substeps,
    )


def _medium_fields(med: Medium, dt: float) -> dict:
    """The medium's constants (each a Model field of the Medium field's name) and the step."""
    shared = [f.name for f in dataclasses.fields(med) if f.name in Model._fields]
    return {name: getattr(med, name) for name in shared} | {"dt": dt}

