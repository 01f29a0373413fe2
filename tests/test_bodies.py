"""Animal files: the zoo matches the papers, and bad files get errors that name the problem."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from zoetic.bodies import ZOO_DIR, compile_body, list_animals, load_animal, parse_animal
from zoetic.errors import BodyError
from zoetic.io import read_toml


def test_zoo_lists_the_four_animals_of_the_paper():
    assert list_animals()[:4] == ["snake", "shark", "ray", "dolphin"]


@pytest.mark.parametrize(
    "name, nodes, springs, muscles, actuators, medium",
    [
        ("snake", 45, 190, 40, 20, "ground"),
        ("shark", 23, 91, 12, 8, "water"),
        ("ray", 42, 208, 16, 4, "water"),
        ("dolphin", 23, 91, 12, 8, "sea"),
        ("shark-1995", 23, 91, 12, 6, "water"),
        ("dolphin-1995", 23, 91, 12, 8, "sea"),
    ],
)
def test_zoo_counts(name, nodes, springs, muscles, actuators, medium):
    b = load_animal(name)
    assert (b.n_nodes, b.n_springs, b.n_muscles, b.n_actuators, b.medium) == (
        nodes, springs, muscles, actuators, medium,
    )  # fmt: skip


def test_shark_muscles_match_model_facts():
    b = load_animal("shark")
    short = 1 - b.contracted / b.relaxed
    muscles = b.spring_actuator >= 0
    back = np.array([b.actuator_names[a].startswith("back") for a in b.spring_actuator])
    assert np.allclose(short[muscles & back], 0.1)
    assert np.allclose(short[muscles & ~back], 0.2)
    assert np.sum(muscles & back) == 4
    # each actuator is a pair of muscles on one side
    for k, name in enumerate(b.actuator_names):
        if b.actuator_kind[k] == "fin":
            continue
        ids = np.flatnonzero(b.spring_actuator == k)
        assert len(ids) == 2
        z = b.rest_pos[np.r_[b.spring_a[ids], b.spring_b[ids]], 2]
        assert np.all(z > 0) if name.endswith("left") else np.all(z < 0)
    # masses (relative): MODEL-FACTS's nose 1.1, rings 6.6, 11, 6.6, 1.1, 1.1, tips 0.165 with
    # mass moved from the middle ring into the tail (docs/animals.md: 9 and 3.3, tips 0.5)
    rel = b.mass / b.mass[0]
    expected = np.array([1.1, 6.6, 9.0, 6.6, 3.3, 3.3, 0.5]) / 1.1
    assert np.allclose(rel[[0, 1, 5, 9, 13, 17, 21]], expected)


def test_snake_and_ray_masses_are_even_and_muscles_shorten_as_the_paper_says():
    for name, f in (("snake", 0.3), ("ray", 0.2)):
        b = load_animal(name)
        assert np.allclose(b.mass, b.mass[0])
        m = b.spring_actuator >= 0
        assert np.allclose(1 - b.contracted[m] / b.relaxed[m], f)


def test_zoo_animals_are_left_right_symmetric_and_mirrors_pair_up():
    for name in list_animals():
        b = load_animal(name)
        assert b.is_mirror_symmetric, name
        assert np.array_equal(b.actuator_mirror[b.actuator_mirror], np.arange(b.n_actuators))


def test_faces_point_outward_for_the_closed_fish():
    b = load_animal("shark")
    p = b.rest_pos[b.faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    volume = np.einsum("fk,fk->f", p[:, 0], n).sum() / 6.0
    assert volume > 0  # outward winding gives a positive enclosed volume


def _shark_doc():
    return read_toml(ZOO_DIR / "shark.toml")


def _expect(doc, match):
    with pytest.raises(BodyError, match=match) as info:
        parse_animal(doc, source="bad.toml")
    assert "bad.toml" in str(info.value)


def test_unknown_node_is_named():
    doc = _shark_doc()
    doc["springs"][3]["nodes"] = ["nose", "fin_9"]
    _expect(doc, r"springs\[3\].*unknown node 'fin_9'")


def test_non_positive_mass():
    doc = _shark_doc()
    doc["nodes"][2]["mass"] = 0.0
    _expect(doc, r"node 'r1_1'.*mass must be positive")


def test_contracted_not_shorter_than_relaxed():
    doc = _shark_doc()
    muscle = next(s for s in doc["springs"] if "actuator" in s)
    muscle["max_shortening"] = -0.1
    _expect(doc, "not shorter than relaxed")


def test_duplicate_spring():
    doc = _shark_doc()
    doc["springs"].append(copy.deepcopy(doc["springs"][0]))
    _expect(doc, "duplicate spring")


def test_zero_length_spring():
    doc = _shark_doc()
    doc["springs"][0]["length"] = 0.0
    _expect(doc, "zero-length spring")


def test_non_finite_number():
    doc = _shark_doc()
    doc["nodes"][4]["pos"][1] = math.nan
    _expect(doc, "non-finite")


def test_actuator_with_no_muscle():
    doc = _shark_doc()
    doc["actuators"].append({"name": "spare", "kind": "muscle"})
    _expect(doc, "actuator 'spare'.*actuator with no muscle")


def test_missing_file_and_bad_toml_name_the_file(tmp_path):
    with pytest.raises(BodyError, match="no such animal file"):
        load_animal(tmp_path / "none.toml")
    bad = tmp_path / "broken.toml"
    bad.write_text("name = \n")
    with pytest.raises(BodyError, match="broken.toml.*not valid TOML"):
        load_animal(bad)
    with pytest.raises(BodyError, match="unknown animal 'unicorn'"):
        load_animal("unicorn")


def test_a_user_file_loads_like_the_zoo(tmp_path):
    import tomli_w

    doc = _shark_doc()
    doc["name"] = "myshark"
    path = tmp_path / "myshark.toml"
    path.write_text(tomli_w.dumps(doc))
    b = load_animal(path)
    assert b.name == "myshark" and b.n_springs == 91


def test_body_arrays_are_immutable():
    b = load_animal("shark")
    with pytest.raises(ValueError):
        b.mass[0] = 1.0


def test_the_eyes_table_compiles_into_the_body():
    doc = _shark_doc()
    doc["eyes"] = {"node": "r1_1", "offset": [0.01, 0.02, 0.03], "fov": 90.0, "levels": 3,
                   "pixels": 32}  # fmt: skip
    b = compile_body(parse_animal(doc, source="eyed.toml"))
    assert b.eye_node == b.node_names.index("r1_1") != b.head
    assert np.allclose(b.eye_offset, [0.01, 0.02, 0.03]) and np.isclose(b.eye_fov, np.pi / 2)
    assert (b.eye_levels, b.eye_pixels) == (3, 32)
    del doc["eyes"]
    eyeless = compile_body(parse_animal(doc, source="eyeless.toml"))
    assert eyeless.eye_node is None and eyeless.eye_offset is None and eyeless.eye_fov is None


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"colour": "blue"}, r"\[eyes\].*unknown key 'colour'"),
        ({"node": "r9_9"}, r"\[eyes\].*'node': unknown node 'r9_9'"),
        ({"fov": -30.0}, r"\[eyes\].*fov must be positive"),
        ({"fov": 200.0}, r"\[eyes\].*'fov' = 200 degrees must be below 180"),
        ({"levels": 0}, r"\[eyes\].*levels must be at least 1"),
        ({"offset": [0.0, 0.1]}, r"\[eyes\].*offset"),
    ],
)
def test_a_bad_eyes_entry_is_refused_naming_the_file_and_entry(change, match):
    doc = _shark_doc()
    doc["eyes"].update(change)
    _expect(doc, match)


def test_a_face_may_declare_its_own_drag_coefficient():
    doc = _shark_doc()
    doc["faces"][5]["drag"] = 0.25
    body = compile_body(parse_animal(doc, source="ok.toml"))
    assert body.panel_drag[5] == 0.25
    assert np.all(np.delete(body.panel_drag, 5) == 1.0)  # the default: the medium's own
    doc["faces"][5]["drag"] = -1.0
    _expect(doc, r"faces\[5\]: drag must be at least 0")
    doc["faces"][5]["drag"] = 1.0
    doc["faces"][5]["drgg"] = 2.0
    _expect(doc, r"faces\[5\].*drgg")


def test_the_1995_shark_carries_its_references_constants():
    """shark-1995 is the MODEL-FACTS fish unchanged in proportion: stiffness 38 : 28 : 30
    (cross, muscle, every other spring, the caudal fin's included), masses 1.1 / 6.6 / 11 /
    6.6 / 1.1 / 1.1 per node and 0.165 at the fin tips, muscles shortening by 20 % (10 % the
    posterior four), six muscle actuators and no pectoral fins (the 1995 paper's Fig. 10)."""
    b = load_animal("shark-1995")
    assert (b.n_nodes, b.n_springs, b.n_actuators, len(b.fin_area)) == (23, 91, 6, 0)
    unit = b.stiffness[b.spring_kind.index("structural")] / 30.0
    kinds = {"cross": 38.0, "muscle": 28.0, "structural": 30.0, "fin": 30.0}
    for k, kind in enumerate(b.spring_kind):
        assert b.stiffness[k] == pytest.approx(kinds[kind] * unit), (k, kind)
    units = np.array([1.1] + [6.6] * 4 + [11.0] * 4 + [6.6] * 4 + [1.1] * 8 + [0.165] * 2)
    assert np.allclose(b.mass / b.mass[0], units / 1.1)
    muscle = b.spring_actuator >= 0
    shortening = 1.0 - b.contracted[muscle] / b.relaxed[muscle]
    back = np.array(["back" in b.actuator_names[a] for a in b.spring_actuator[muscle]])
    assert np.allclose(shortening[back], 0.1) and np.allclose(shortening[~back], 0.2)
    # same lattice and size as today's shark: only the constants differ
    assert np.allclose(b.rest_pos, load_animal("shark").rest_pos)
    # and the 1995 dolphin is this shark on its side, with the same constants
    d = load_animal("dolphin-1995")
    assert np.allclose(np.sort(d.stiffness), np.sort(b.stiffness))
    assert np.allclose(d.mass, b.mass) and len(d.fin_area) == 2
    assert np.allclose(d.rest_pos[:, 1], b.rest_pos[:, 2])  # left (+z) is now up (+y)
