"""Property tests: mutated zoo files fed to every reader give a ZoeticError or a valid result.

Each example takes a real file (a zoo animal, a zoo creature, a learned-style controller, a
network, a repertoire index, a run configuration), changes one to three entries anywhere in
it (deletes them, changes their type, puts NaN, infinities or huge numbers in) and reads it.
Any exception other than a ZoeticError is a bug in the reader.
"""

from __future__ import annotations

import copy
import json
import math
import tempfile
import tomllib
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from zoetic.bodies import ZOO_DIR, compile_body, load_animal, parse_animal
from zoetic.control import from_dict, time_domain
from zoetic.errors import ZoeticError
from zoetic.io import load_json, load_toml

SETTINGS = settings(
    max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)

DELETE = object()
VALUES = [
    DELETE,
    "x",
    "",
    True,
    None,
    [],
    {},
    [1, 2],
    math.nan,
    math.inf,
    -math.inf,
    1e308,
    -1e308,
    10**30,
    -1,
    0,
    0.0,
    1e-300,
    "nan",
    2**63,
    [[[[1]]]],
    {"a": 1},
]


def _locations(obj, prefix=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield prefix + (k,)
            yield from _locations(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:12]):  # the first entries of long lists are enough
            yield prefix + (i,)
            yield from _locations(v, prefix + (i,))


def _mutate(doc, data) -> object:
    doc = copy.deepcopy(doc)
    for _ in range(data.draw(st.integers(1, 3))):
        locs = list(_locations(doc))
        if not locs:
            break
        path = data.draw(st.sampled_from(locs))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        value = data.draw(st.sampled_from(VALUES))
        if value is DELETE:
            del parent[path[-1]]
        else:
            parent[path[-1]] = copy.deepcopy(value)
    return doc


def _only_zoetic_errors(fn, *args) -> None:
    try:
        fn(*args)
    except ZoeticError:
        pass


SHARK = tomllib.loads((ZOO_DIR / "shark.toml").read_text())


@SETTINGS
@given(st.data())
def test_mutated_animals(data):
    doc = _mutate(SHARK, data)
    _only_zoetic_errors(lambda d: compile_body(parse_animal(d, "shark.toml")), doc)


def _creature_doc():
    from zoetic.san.creature import ZOO_DIR as SAN_ZOO

    return tomllib.loads((SAN_ZOO / "walker.toml").read_text())


WALKER = _creature_doc()


@SETTINGS
@given(st.data())
def test_mutated_creatures(data):
    from zoetic.san.creature_file import creature_from_dict

    _only_zoetic_errors(creature_from_dict, _mutate(WALKER, data), "walker.toml")


_BODY = load_animal("shark")
_CTRL = time_domain(_BODY, 6, 2.0).to_dict()
_MIRRORED = time_domain(_BODY, 4, 2.0).mirrored(_BODY.actuator_mirror).to_dict()


@SETTINGS
@given(st.data(), st.sampled_from([_CTRL, _MIRRORED]))
def test_mutated_controllers(data, ctrl):
    def load(d):
        c = from_dict(d, "c.json")
        c.table(10, 0.01)  # a controller that loads must also play

    _only_zoetic_errors(load, _mutate(ctrl, data))


def _network_doc():
    from zoetic.san import load_creature
    from zoetic.san.network import random_network

    net = random_network(load_creature("cart"), np.random.default_rng(0))
    return net.to_dict()


NETWORK = _network_doc()


@SETTINGS
@given(st.data())
def test_mutated_networks(data):
    from zoetic.san.network import network_from_dict

    _only_zoetic_errors(network_from_dict, _mutate(NETWORK, data), "n.json")


@SETTINGS
@given(st.data())
def test_mutated_repertoire_indexes(data):
    from zoetic.behavior.repertoire import INDEX, Repertoire

    index = {
        "animal": "shark",
        "actuators": list(_BODY.actuator_names),
        "entries": [{"name": "a", "file": "a.json", "duration": 2.0}],
    }
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "a.json").write_text(json.dumps(_CTRL))
        (Path(tmp) / INDEX).write_text(json.dumps(_mutate(index, data)))
        _only_zoetic_errors(Repertoire.load, tmp, _BODY)


@SETTINGS
@given(st.data())
def test_mutated_run_configs(data):
    from zoetic.runs import check_learn_config

    run = {
        "animal": "shark",
        "task": "swim-straight",
        "optimizer": "cmaes",
        "budget": 48,
        "seed": 0,
        "controller": "time",
        "nodes": 8,
        "chains": 1,
    }
    _only_zoetic_errors(check_learn_config, _mutate({"run": run}, data).get("run"), "c.toml")


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.binary(max_size=300), st.sampled_from(["toml", "json"]))
def test_any_bytes_are_read_or_refused(raw, fmt):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"f.{fmt}"
        path.write_bytes(raw)
        _only_zoetic_errors(load_toml if fmt == "toml" else load_json, path)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.data())
def test_text_edits_of_an_animal_file_are_read_or_refused(data):
    text = (ZOO_DIR / "shark.toml").read_text()
    lines = text.splitlines()
    i = data.draw(st.integers(0, len(lines) - 1))
    lines[i] = data.draw(
        st.sampled_from(
            [
                "",
                "x = ",
                "[[nodes]]",
                "mass = 'a'",
                lines[i][::-1],
                lines[i] + lines[i],
                "\x00",
                "é",
            ]
        )
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "a.toml"
        path.write_text("\n".join(lines))
        _only_zoetic_errors(load_animal, str(path))
