"""Fish species files: the built-in ones load, a file round-trips, a bad one is refused."""

from __future__ import annotations

import pytest

from zoetic.behavior.aquarium.species import SpeciesError, list_species, load_species
from zoetic.bodies import load_animal


def test_builtin_species_load_with_a_water_body_and_a_predator_among_them():
    names = list_species()
    assert {"minnow", "shark"} <= set(names)
    specs = [load_species(n) for n in names]
    assert any(s.predator for s in specs) and any(not s.predator for s in specs)
    for s in specs:
        assert load_animal(s.body).medium in ("water", "sea")
    shark = load_species("shark")
    assert shark.prey == ("minnow",) and shark.motor.catch_radius > 0
    minnow = load_species("minnow")
    assert minnow.habits.schooling and minnow.mind.fear_threshold == 0.5


def test_a_species_file_round_trips(tmp_path):
    s = load_species("minnow")
    path = s.save(tmp_path / "fish.toml")
    back = load_species(path)
    assert back.to_dict() == s.to_dict()
    # the shipped learned skills are written by name, not by where this install keeps them
    assert 'skills = "learned"' in path.read_text() and back.motor.skills == s.motor.skills


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("[mind]", "[mind]\nhungr_rate = 0.1"), "hungr_rate"),
        (("hunger_rate = 0.01675", "hunger_rate = -1.0"), "hunger_rate must be at least 0"),
        (('dislikes = ["crowd"]', 'dislikes = ["crowds"]'), "did you mean 'crowd'"),
        (("fear_threshold = 0.5 ", "fear_threshold = 0.9 "), "panic_threshold"),
        (('skills = "learned"', 'skills = "learnd"'), "[motor] skills"),
    ],
)
def test_a_bad_species_file_is_refused_naming_the_file_and_entry(tmp_path, edit, message):
    text = open(load_species("minnow").source).read()
    assert edit[0] in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(SpeciesError) as err:
        load_species(bad)
    assert str(bad) in str(err.value) and message in str(err.value)


def test_an_unknown_species_name_suggests_the_closest():
    with pytest.raises(SpeciesError, match="did you mean 'minnow'"):
        load_species("minow")


def test_a_coward_fears_from_farther():
    from dataclasses import replace

    from zoetic.behavior.aquarium.species import COWARD_FEAR
    from zoetic.behavior.mind import fear

    s = load_species("minnow")
    brave = s.fear_constants().fear_distance
    coward = replace(s, habits=replace(s.habits, coward=True)).fear_constants().fear_distance
    assert coward == pytest.approx(COWARD_FEAR * brave)
    assert fear([4.0], coward) > fear([4.0], brave)
