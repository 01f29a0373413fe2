"""The hand-made repertoire: the animal's own travelling wave as abstracted entries (not
learned), the baseline that learned repertoires are compared with and what tracking, macro
plans and the motor controllers fall back on without training.
"""

from __future__ import annotations

import numpy as np

from zoetic.behavior.repertoire import Repertoire
from zoetic.bodies import Body
from zoetic.control.abstract import AbstractController
from zoetic.learning.abstraction import mirror_abstract

FIN_TILT = 0.05  # the hand-made swim-up's fin setting above level (swim-down: below)


def wave_abstraction(
    body: Body, right_scale: float = 1.0, left_bias: float = 0.0, fin_tilt: float = 0.0
):
    """Return the animal's travelling wave as an AbstractController, right side scaled.

    The wave offset + a (1 + sin(2 pi (f t - p))) / 2 is one cosine mode per actuator; scaling
    the right actuators' signal down and adding a bias to the left ones bends and turns the
    animal to the left (+z); ``fin_tilt`` is added to the fins' level setting (positive
    pitches the shark's nose up, so it climbs).
    """
    a = body.wave_amplitude
    right = np.array([s == "right" for s in body.actuator_side])
    left = np.array([s == "left" for s in body.actuator_side])
    scale = np.where(right, right_scale, 1.0)
    offset = (body.wave_offset + 0.5 * a) * scale + np.where(left, left_bias, 0.0)
    amp = (0.5 * a * scale)[:, None]
    phase = (-2 * np.pi * np.asarray(body.wave_phase, float) - np.pi / 2)[:, None]
    held = ~np.isnan(body.wave_held)  # not driven by the wave: relaxed muscles, level fins
    offset = np.where(held, np.nan_to_num(body.wave_held) + fin_tilt, offset)
    amp[held] = 0.0
    freq = np.full_like(amp, body.wave_frequency)
    return AbstractController(
        body.name, body.actuator_names, offset, freq, amp, phase, 1.0 / body.wave_frequency
    )


def handmade_repertoire(body: Body) -> Repertoire:
    """Return hand-made entries (not learned): do-nothing, go-straight and four turns, and
    for an animal with fins swim-up and swim-down.

    Turns weaken one side's wave and bias the other (sharp: right x0.2, left +0.3; wide:
    right x0.5, left +0.1); right turns mirror left ones; swim-up and swim-down tilt the fins
    by +-0.05 from level. For the shark: straight about 0.37 m/s, sharp turns about 6 deg/s
    (radius ~1.6 m), wide turns about 4 deg/s, swim-up and -down about 0.25 m in 3 s.
    """
    rep = Repertoire(body.name, tuple(body.actuator_names))
    period = 1.0 / body.wave_frequency
    straight = wave_abstraction(body)
    sharp = wave_abstraction(body, 0.2, 0.3)
    wide = wave_abstraction(body, 0.5, 0.1)
    rest = AbstractController(
        body.name,
        body.actuator_names,
        np.nan_to_num(body.wave_held),  # fins level
        np.zeros((body.n_actuators, 1)),
        np.zeros((body.n_actuators, 1)),
        np.zeros((body.n_actuators, 1)),
        period,
    )
    mirror = body.actuator_mirror
    for name, ctrl in (
        ("do-nothing", rest),
        ("go-straight", straight),
        ("sharp-turn-left", sharp),
        ("sharp-turn-right", mirror_abstract(sharp, mirror)),
        ("wide-turn-left", wide),
        ("wide-turn-right", mirror_abstract(wide, mirror)),
    ):
        rep.add(name, ctrl, 4 * period, source="hand-made")
    if body.fin_area is not None and len(body.fin_area):
        for name, tilt in (("swim-up", FIN_TILT), ("swim-down", -FIN_TILT)):
            rep.add(name, wave_abstraction(body, fin_tilt=tilt), 4 * period, source="hand-made")
    return rep
