"""Fish species as data files: body, colour, habits, mental-state constants and motor skills.

A species file (TOML) names a body (a zoo animal of the water or an animal file's path, relative
to the species file), a colour, whether it is a predator (and of whom), its habits, the
constants of its mind (in SI; see the built-in files in ``species/`` for how the artificial
fish's constants were rescaled), its senses and its motor skills. ``load_species`` reads one
strictly: unknown keys, wrong types and out-of-range numbers are refused with the file and the
entry named. Built-in species are the files in ``species/``; a user adds one without code.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from zoetic.behavior.learned_motor import LEARNED_BASES
from zoetic.errors import ZoeticError
from zoetic.io import Table, is_path, load_toml, suggest, write_toml

SPECIES_DIR = Path(__file__).parent / "species"
HABIT_WORDS = ("company", "crowd", "obstacles")
COWARD_FEAR = 2.5  # a coward fears from 2.5 times as far (the re-implementation's 500 vs 200)
BUILT_IN = "built-in"  # the calibrated steered wave (``locomotion.MotorLocomotion``)
# the learned repertoire shipped for the species' body: ``skills/<body>/``, trained by
# scripts/train_aquarium_skills.py (``zoetic repertoire train <body>``, seed 0)
LEARNED = "learned"
SKILLS_DIR = Path(__file__).parent / "skills"
# the learned repertoire entries the motor controllers play (``learned_motor.LearnedMotor``)
SKILL_ENTRIES = LEARNED_BASES


class SpeciesError(ZoeticError):
    """A species file is malformed."""


@dataclass(frozen=True)
class Habits:
    """Fixed habits: schooling, cowardice, likes and dislikes, and what counts as a crowd."""

    schooling: bool = False
    coward: bool = False
    likes: tuple[str, ...] = ()
    dislikes: tuple[str, ...] = ()
    crowd: int = 4
    personal_space: float = 1.5


@dataclass(frozen=True)
class MindConstants:
    """The mental-state and intention constants in SI (rates 1/s, distances m, ramps 1/m)."""

    alpha: float = 1.0
    hunger_rate: float = 0.01675
    libido_rate: float = 0.0625
    fear_distance: float = 2.0
    hunger_ramp: tuple[float, float] = (5.0, 20.0)
    libido_ramp: tuple[float, float] = (2.5, 10.0)
    fear_threshold: float = 0.5
    panic_threshold: float = 0.8
    desire_threshold: float = 0.25
    persistence: float = 1.0
    initial_hunger: float = 0.3


@dataclass(frozen=True)
class Senses:
    """The perception oracle's view volume: angle (degrees), range and smell radius (m); and
    the collision sensitivity region (``routines.fish_threats``): how far ahead of the nose
    and to either side (m) another fish threatens a collision, and how far ahead (s) the
    fishes' motion is anticipated (a larger region makes a timid fish, a tight one a
    courageous fish)."""

    view_angle: float = 300.0
    view_range: float = 6.0
    smell_range: float = 3.0
    collision_reach: float = 0.7
    collision_half_width: float = 0.35
    collision_anticipation: float = 2.0


@dataclass(frozen=True)
class Motor:
    """Motor skills: which controllers ("built-in", "learned": the repertoire shipped for the
    body, or a learned repertoire's directory),
    cruising and top speed (m/s), a predator's catch radius."""

    skills: str = BUILT_IN
    frequency: float | None = None  # Hz of the wave; None: the body's own stroke frequency
    cruise_speed: float = 0.25
    max_speed: float = 0.5
    catch_radius: float = 0.3


@dataclass(frozen=True)
class Species:
    """A fish species: everything a fish of it shares."""

    name: str
    body: str
    color: tuple[int, int, int]
    predator: bool
    prey: tuple[str, ...]
    habits: Habits
    mind: MindConstants  # as in the file; ``fear_constants`` applies cowardice
    senses: Senses
    motor: Motor
    description: str = ""
    source: str = "<memory>"

    def fear_constants(self) -> MindConstants:
        """Return the mind constants the fish lives by: a coward's fear distance is
        ``COWARD_FEAR`` times the file's."""
        if not self.habits.coward:
            return self.mind
        return replace(self.mind, fear_distance=COWARD_FEAR * self.mind.fear_distance)

    def to_dict(self) -> dict[str, Any]:
        """Return the species as the table its file holds."""
        d = asdict(self)
        d.pop("source")
        d["color"] = list(self.color)
        d["prey"] = list(self.prey)
        for k in ("likes", "dislikes"):
            d["habits"][k] = list(d["habits"][k])
        for k in ("hunger_ramp", "libido_ramp"):
            d["mind"][k] = list(d["mind"][k])
        if d["motor"]["frequency"] is None:  # the body's own: TOML has no null, so leave it out
            del d["motor"]["frequency"]
        body = Path(self.body).stem if is_path(self.body) else self.body
        if d["motor"]["skills"] == str(SKILLS_DIR / body):  # the shipped one, not its path
            d["motor"]["skills"] = LEARNED
        return d

    def save(self, path: str | Path) -> Path:
        """Write the species as a TOML file (atomically); returns the path."""
        return write_toml(path, self.to_dict())


def _words(t: Table, key: str) -> tuple[str, ...]:
    value = t.raw(key, [])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise t.fail(f"{key!r} must be a list of words, got {value!r}")
    for v in value:
        if v not in HABIT_WORDS:
            raise t.fail(
                f"{key!r}: unknown habit {v!r}{suggest(v, HABIT_WORDS)} "
                f"(choose from {', '.join(HABIT_WORDS)})"
            )
    return tuple(value)


def _ramp(t: Table, key: str, default) -> tuple[float, float]:
    q = t.numbers(key, list(default), size=2)
    if not 0 <= q[0] < q[1]:
        raise t.fail(f"{key!r} = {q}: need 0 <= q1 < q2")
    return (q[0], q[1])


def _section(top: Table, key: str, source: str) -> Table:
    """Return the sub-table ``[key]`` of a species file, its errors naming it."""
    t = top.table(key)
    t.where = f"{source}: [{key}]"
    return t


def _habits(h: Table) -> Habits:
    """Return the [habits] of a species file."""
    habits = Habits(
        h.boolean("schooling", False),
        h.boolean("coward", False),
        _words(h, "likes"),
        _words(h, "dislikes"),
        h.integer("crowd", 4, lo=0),
        h.number("personal_space", 1.5, positive=True),
    )
    h.finish()
    return habits


def _mind(m: Table) -> MindConstants:
    """Return the [mind] constants of a species file (defaults: ``MindConstants``)."""
    d = MindConstants()
    mind = MindConstants(
        alpha=m.number("alpha", d.alpha, positive=True),
        hunger_rate=m.number("hunger_rate", d.hunger_rate, lo=0.0),
        libido_rate=m.number("libido_rate", d.libido_rate, lo=0.0),
        fear_distance=m.number("fear_distance", d.fear_distance, positive=True),
        hunger_ramp=_ramp(m, "hunger_ramp", d.hunger_ramp),
        libido_ramp=_ramp(m, "libido_ramp", d.libido_ramp),
        fear_threshold=m.number("fear_threshold", d.fear_threshold, lo=0.0, hi=1.0),
        panic_threshold=m.number("panic_threshold", d.panic_threshold, lo=0.0, hi=1.0),
        desire_threshold=m.number("desire_threshold", d.desire_threshold, lo=0.0, hi=1.0),
        persistence=m.number("persistence", d.persistence, lo=0.0, hi=60.0),
        initial_hunger=m.number("initial_hunger", d.initial_hunger, lo=0.0, hi=1.0),
    )
    if mind.panic_threshold < mind.fear_threshold:
        raise m.fail(
            f"'panic_threshold' ({mind.panic_threshold:g}) must be at least 'fear_threshold' "
            f"({mind.fear_threshold:g})"
        )
    m.finish()
    return mind


def _senses(s: Table) -> Senses:
    """Return the [senses] of a species file: view angle (deg), view and smell range (m),
    the collision sensitivity region (m, m, s)."""
    d = Senses()
    senses = Senses(
        s.number("view_angle", d.view_angle, positive=True, hi=360.0),
        s.number("view_range", d.view_range, positive=True, hi=1000.0),
        s.number("smell_range", d.smell_range, lo=0.0, hi=1000.0),
        s.number("collision_reach", d.collision_reach, lo=0.0, hi=100.0),
        s.number("collision_half_width", d.collision_half_width, lo=0.0, hi=100.0),
        s.number("collision_anticipation", d.collision_anticipation, lo=0.0, hi=60.0),
    )
    s.finish()
    return senses


def _motor(mo: Table) -> Motor:
    """Return the [motor] of a species file: skills, frequency (Hz), speeds (m/s), catch (m)."""
    motor = Motor(
        mo.string("skills", BUILT_IN),
        mo.number("frequency", None, positive=True, hi=20.0),
        mo.number("cruise_speed", 0.25, positive=True, hi=20.0),
        mo.number("max_speed", 0.5, positive=True, hi=20.0),
        mo.number("catch_radius", 0.3, positive=True, hi=10.0),
    )
    if motor.max_speed < motor.cruise_speed:
        raise mo.fail("'max_speed' must be at least 'cruise_speed'")
    mo.finish()
    return motor


def parse_species(doc: dict[str, Any], source: str = "<memory>") -> Species:
    """Return the Species a parsed TOML document describes; SpeciesError if malformed."""
    top = Table(doc, f"{source}: top level", SpeciesError)
    name = top.string("name")
    description = top.raw("description", "")
    if not isinstance(description, str):
        raise top.fail(f"'description' must be text, got {description!r}")
    body = top.string("body")
    color = top.numbers("color", size=3)
    if not all(0 <= c <= 255 for c in color):
        raise top.fail(f"'color' = {color}: each of red, green, blue must be in 0..255")
    predator = top.boolean("predator", False)
    prey = top.raw("prey", [])
    if not isinstance(prey, list) or not all(isinstance(p, str) and p for p in prey):
        raise top.fail(f"'prey' must be a list of species names, got {prey!r}")
    if prey and not predator:
        raise top.fail("'prey' is given but 'predator' is false; a prey list needs predator = true")
    habits = _habits(_section(top, "habits", source))
    mind = _mind(_section(top, "mind", source))
    senses = _senses(_section(top, "senses", source))
    motor = _motor(_section(top, "motor", source))
    top.finish()
    rgb = (int(color[0]), int(color[1]), int(color[2]))
    return Species(
        name, body, rgb, predator, tuple(prey), habits, mind, senses, motor, description, source
    )


def list_species() -> list[str]:
    """Return the names of the built-in species."""
    return sorted(p.stem for p in SPECIES_DIR.glob("*.toml"))


def load_species(name_or_path: str | Path) -> Species:
    """Return the species of a built-in name (``minnow``) or of a species file's path."""
    text = str(name_or_path)
    if is_path(text):
        path = Path(text)
    else:
        path = SPECIES_DIR / f"{text}.toml"
        if not path.is_file():
            raise SpeciesError(
                f"unknown species {text!r}{suggest(text, list_species())}: choose one of "
                f"{', '.join(list_species())} or give the path of a species .toml file"
            )
    spec = parse_species(load_toml(path, "species file", SpeciesError), str(path))
    if is_path(spec.body) and not Path(spec.body).is_absolute():
        spec = Species(**{**spec.__dict__, "body": str(path.parent / spec.body)})
    if spec.motor.skills not in (BUILT_IN, LEARNED):
        skills = Path(spec.motor.skills).expanduser()
        if not skills.is_absolute():
            skills = path.parent / skills
        spec = with_skills(spec, skills)
    elif spec.motor.skills == LEARNED:
        spec = with_skills(spec, LEARNED)
    return spec


def with_skills(spec: Species, skills: str | Path, where: str | None = None) -> Species:
    """Return the species with its motor skills replaced: ``"built-in"``, ``"learned"`` (the
    repertoire shipped for its body, ``learned_skills``) or a learned repertoire's directory,
    checked (``check_skills``); ``where`` names where the value came from in an error (default
    the species file's ``[motor] skills``)."""
    if str(skills) == BUILT_IN:
        return replace(spec, motor=replace(spec.motor, skills=BUILT_IN))
    if str(skills) == LEARNED:
        skills = learned_skills(spec, where)
    spec = replace(spec, motor=replace(spec.motor, skills=str(skills)))
    check_skills(spec, where)
    return spec


def learned_skills(spec: Species, where: str | None = None) -> Path:
    """Return the directory of the learned repertoire shipped for the species' body
    (``SKILLS_DIR``/<body>); SpeciesError when none is shipped for it."""
    body = Path(spec.body).stem if is_path(spec.body) else spec.body
    directory = SKILLS_DIR / body
    if not (directory / "repertoire.json").is_file():
        shipped = (
            sorted(p.name for p in SKILLS_DIR.iterdir() if p.is_dir())
            if SKILLS_DIR.is_dir()
            else []
        )
        where = where or f"{spec.source}: [motor] skills"
        raise SpeciesError(
            f"{where}: no learned repertoire is shipped for body {spec.body!r} (there are for "
            f"{', '.join(shipped) or 'none'}); give {BUILT_IN!r} or a repertoire's directory "
            "(zoetic repertoire train ANIMAL --out DIR makes one)"
        )
    return directory


def check_skills(spec: Species, where: str | None = None) -> None:
    """Refuse (SpeciesError naming the file and the entry, or ``where``) a learned repertoire
    the fish cannot swim by: a missing directory, one that is not a repertoire, one for another
    body, or one lacking an entry the motor controllers play (``SKILL_ENTRIES``) or whose
    entries are not abstracted (sums of cosines, which blend)."""
    from zoetic.behavior.repertoire import Repertoire
    from zoetic.bodies import load_animal
    from zoetic.control.abstract import AbstractController

    where = where or f"{spec.source}: [motor] skills"
    directory = Path(spec.motor.skills)
    if not directory.is_dir():
        raise SpeciesError(
            f"{where}: {str(directory)!r} is not a directory; give {BUILT_IN!r} or a learned "
            "repertoire's directory (zoetic repertoire train ANIMAL --out DIR makes one)"
        )
    body = load_animal(spec.body)
    try:
        rep = Repertoire.load(directory, body)
    except ZoeticError as exc:
        raise SpeciesError(f"{where}: {exc}") from None
    missing = [n for n in SKILL_ENTRIES if n not in rep.controllers]
    if missing:
        raise SpeciesError(
            f"{where}: the repertoire in {directory} lacks the entries {', '.join(missing)} "
            f"that the motor controllers blend (it has {', '.join(rep.names) or 'none'})"
        )
    odd = [n for n in SKILL_ENTRIES if not isinstance(rep.controllers[n], AbstractController)]
    if odd:
        raise SpeciesError(
            f"{where}: the entries {', '.join(odd)} in {directory} are not abstracted "
            "controllers (sums of cosines), so they cannot be blended"
        )
