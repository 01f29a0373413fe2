"""Write tests/data/bad/: broken files of every format zoetic reads, one problem each.

Each file is a small valid file with one thing wrong (or a whole-file problem: binary, UTF-16,
truncated, empty). tests/test_bad_corpus.py runs every one through the real CLI. Run from the
repository root: ``python scripts/make_bad_corpus.py`` (it rewrites the folder).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "tests" / "data" / "bad"

ANIMAL = """name = "tri"
description = "three nodes, one muscle: the smallest animal"
medium = "water"
dt = 0.005
actuators = [{ name = "m", side = "center" }]

[defaults]
node_damping = 0.1
stiffness = 200.0
spring_damping = 0.5

[[nodes]]
name = "a"
pos = [0.0, 0.0, 0.0]
mass = 0.1

[[nodes]]
name = "b"
pos = [0.1, 0.0, 0.0]
mass = 0.1

[[nodes]]
name = "c"
pos = [0.05, 0.0, 0.08]
mass = 0.1

[[springs]]
nodes = ["a", "b"]
actuator = "m"
max_shortening = 0.2

[[springs]]
nodes = ["b", "c"]

[[springs]]
nodes = ["c", "a"]

[[faces]]
nodes = ["a", "b", "c"]

[wave]
frequency = 1.0
amplitude = 1.0
offset = 0.0

[wave.phases]
m = 0.0
"""

CREATURE = """[creature]
name = "twolink"
medium = "ground"
metric = "distance"
seconds = 6.0
dt = 0.0025
control_dt = 0.005

[[link]]
name = "L1"
shape = "capsule"
length = 0.25
radius = 0.012
mass = 0.20

[[link]]
name = "L2"
shape = "capsule"
length = 0.25
radius = 0.012
mass = 0.10

[[joint]]
name = "J1"
kind = "hinge"
parent = "L1"
child = "L2"
anchor = [0.25, 0.0]

[[sensor]]
name = "S1"
kind = "touch"
target = "L1"
at = 0.0

[[actuator]]
name = "A1"
kind = "angular"
joint = "J1"
lo_deg = -90.0
hi_deg = 90.0
ks_deg = 0.002
"""

SHARK_ACTS = [
    "front_left",
    "front_right",
    "middle_left",
    "middle_right",
    "back_left",
    "back_right",
    "fin_left",
    "fin_right",
]
NA = len(SHARK_ACTS)


def _constant(**over) -> dict:
    d = {"type": "constant", "animal": "shark", "actuators": SHARK_ACTS, "values": [0.5] * NA}
    return d | over


def _network(**over) -> dict:
    # the twolink from the zoo: 6 sensors, 1 actuator; 5 hidden nodes -> 6 nodes, 12 columns
    n, cols = 6, 12
    d = {
        "format": "zoetic-san",
        "version": 1,
        "creature": "twolink",
        "n_sensors": 6,
        "n_hidden": 5,
        "n_actuators": 1,
        "weights": [[(i + j) % 5 - 2 for j in range(cols)] for i in range(n)],
        "k1": [8.0] * n,
        "k2": [-8.0] * n,
    }
    return d | over


CONFIG = """[run]
animal = "shark"
task = "swim-straight"
optimizer = "cmaes"
budget = 48
seed = 0
controller = "time"
nodes = 8
interp = "linear"
chains = 1
evaluator = "batch"
coupling = "none"

[task]
name = "swim-straight"
requires = ["water"]
horizon = 4.0
nodes = 8
mu1 = 0.0
mu2 = 1.0

[[task.terms]]
kind = "distance_along_heading"
weight = -1.0
"""


def _sub(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


EYES = """
[eyes]
node = "a"
offset = [0.0, 0.01, 0.02]
fov = 90.0
levels = 2
pixels = 16
"""


def animals() -> dict[str, bytes | str]:
    a = ANIMAL
    med = 'medium = "water"'
    desc = 'description = "three nodes, one muscle: the smallest animal"'
    return {
        "misspelled-top-key.toml": _sub(a, "medium =", 'mediun = "water"\nmedium ='),
        "misspelled-node-key.toml": _sub(a, "mass = 0.1\n", "mas = 0.1\nmass = 0.1\n"),
        "misspelled-spring-key.toml": _sub(a, "[[faces]]", "stifness = 3.0\n\n[[faces]]"),
        "misspelled-default.toml": _sub(a, "stiffness = 200.0", "stiffnes = 200.0"),
        "string-mass.toml": _sub(a, "mass = 0.1", 'mass = "heavy"'),
        "nan-mass.toml": _sub(a, "mass = 0.1", "mass = nan"),
        "inf-stiffness.toml": _sub(a, "stiffness = 200.0", "stiffness = inf"),
        "negative-mass.toml": _sub(a, "mass = 0.1", "mass = -0.1"),
        "zero-stiffness.toml": _sub(a, "stiffness = 200.0", "stiffness = 0.0"),
        "dt-too-large.toml": _sub(a, "dt = 0.005", "dt = 0.5"),
        "dt-tiny.toml": _sub(a, "dt = 0.005", "dt = 1e-12"),
        "dt-negative.toml": _sub(a, "dt = 0.005", "dt = -0.005"),
        "dt-string.toml": _sub(a, "dt = 0.005", 'dt = "fast"'),
        "binary.toml": bytes(range(256)) * 4,
        "utf16.toml": a.encode("utf-16"),
        "latin1.toml": _sub(a, "the smallest", "le plus petit \xe9").encode("latin-1"),
        "empty.toml": "",
        "not-toml.toml": a[:200] + "\n[[nodes\n",
        "truncated.toml": a[: len(a) // 2].rsplit("\n", 3)[0] + '\nname = "',
        "duplicate-node.toml": _sub(a, 'name = "b"', 'name = "a"'),
        "duplicate-spring.toml": _sub(a, 'nodes = ["c", "a"]', 'nodes = ["b", "a"]'),
        "unknown-node.toml": _sub(a, 'nodes = ["b", "c"]', 'nodes = ["b", "cc"]'),
        "unknown-medium.toml": _sub(a, 'medium = "water"', 'medium = "watr"'),
        "actuator-without-muscle.toml": _sub(a, 'actuator = "m"\nmax_shortening = 0.2\n', ""),
        "phase-for-unknown-actuator.toml": _sub(a, "m = 0.0", "mm = 0.0"),
        "deep-nesting.toml": a + "junk = " + "[" * 200 + "]" * 200 + "\n",
        "head-out-of-range.toml": _sub(a, med, med + "\nhead = 999"),
        "forward-zero.toml": _sub(a, med, med + "\nforward = [0, 0, 0]"),
        "forward-wrong-length.toml": _sub(a, med, med + "\nforward = [1, 0]"),
        "muscle-not-shorter.toml": _sub(a, "max_shortening = 0.2", "max_shortening = -0.5"),
        "description-number.toml": _sub(a, desc, "description = 5"),
        "mirror-unknown.toml": _sub(a, 'side = "center"', 'side = "center", mirror = "n"'),
        "nodes-not-tables.toml": _sub(a, med, med + "\nfins = [1, 2]"),
        "one-node.toml": a.split("[[nodes]]")[0] + "[[nodes]]\npos = [0, 0, 0]\nmass = 1.0\n",
        "pos-nan.toml": _sub(a, "pos = [0.1, 0.0, 0.0]", "pos = [0.1, nan, 0.0]"),
        "huge-number.toml": _sub(a, "mass = 0.1", "mass = 1e400"),
        "eyes-unknown-node.toml": a + _sub(EYES, 'node = "a"', 'node = "eye"'),
        "eyes-negative-fov.toml": a + _sub(EYES, "fov = 90.0", "fov = -90.0"),
        "eyes-misspelled-key.toml": a + _sub(EYES, "pixels =", "pixel ="),
        "eyes-zero-levels.toml": a + _sub(EYES, "levels = 2", "levels = 0"),
    }


def creatures() -> dict[str, bytes | str]:
    c = CREATURE
    return {
        "misspelled-key.toml": _sub(c, "radius = 0.012", "raduis = 0.012"),
        "misspelled-header-key.toml": _sub(c, "seconds = 6.0", "secnds = 6.0"),
        "string-mass.toml": _sub(c, "mass = 0.20", 'mass = "0.2"'),
        "nan-mass.toml": _sub(c, "mass = 0.20", "mass = nan"),
        "tiny-dt.toml": _sub(c, "dt = 0.0025\ncontrol_dt = 0.005", "dt = 1e-9\ncontrol_dt = 0.005"),
        "too-many-steps.toml": _sub(c, "seconds = 6.0", "seconds = 1e6"),
        "binary.toml": b"\x00\x01\x02zoetic\xff" * 50,
        "utf16.toml": c.encode("utf-16"),
        "empty.toml": "",
        "no-links.toml": c.split("[[link]]")[0],
        "joint-cycle.toml": _sub(c, 'child = "L2"', 'child = "L1"'),
        "unknown-medium.toml": _sub(c, 'medium = "ground"', 'medium = "lava"'),
        "negative-hidden.toml": _sub(c, "seconds = 6.0", "seconds = 6.0\nhidden = -1"),
        "duplicate-link.toml": _sub(c, 'name = "L2"', 'name = "L1"'),
        "deep-nesting.toml": c + "\n[[link]]\nname = " + "[" * 300 + "]" * 300 + "\n",
        "no-actuators.toml": c.split("[[actuator]]")[0],
    }


def controllers() -> dict[str, bytes | str]:
    inner = _constant()
    for _ in range(40):
        inner = {
            "type": "mirrored",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "inner": inner,
            "mirror": [1, 0, 3, 2, 5, 4],
        }
    files = {
        "constant-wrong-length.json": _constant(values=[0.5] * 5),
        "mirror-out-of-range.json": {
            "type": "mirrored",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "inner": _constant(),
            "mirror": [1, 0, 3, 2, 5, 4, 7, 60],
        },
        "deep-nesting.json": inner,
        "non-finite.json": _constant(values=[0.5, 0.5, float("nan"), 0.5, 0.5, 0.5]),
        "wave-phases-wrong-length.json": {
            "type": "wave",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "frequency": 1.0,
            "amplitude": 1.0,
            "offset": 0.0,
            "phases": [0.0, 0.5],
        },
        "unknown-type.json": _constant(type="sine"),
        "type-is-a-list.json": _constant(type=["constant"]),
        "ragged-values.json": {
            "type": "time",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "duration": 2.0,
            "values": [[0.1, 0.2]] * 5 + [[0.1]],
        },
        "negative-duration.json": {
            "type": "time",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "duration": -2.0,
            "values": [[0.1, 0.2]] * NA,
        },
        "for-another-animal.json": _constant(animal="ray"),
        "wrong-actuators.json": _constant(actuators=[f"a{i}" for i in range(6)]),
        "misspelled-key.json": {
            "type": "constant",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "valeus": [0.5] * NA,
        },
        "string-values.json": _constant(values=["0.5"] * NA),
        "not-an-object.json": [1, 2, 3],
        "huge-duration.json": {
            "type": "time",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "duration": 1e300,
            "values": [[0.1, 0.2]] * NA,
        },
        "one-node.json": {
            "type": "time",
            "animal": "shark",
            "actuators": SHARK_ACTS,
            "duration": 2.0,
            "values": [[0.1]] * NA,
        },
    }
    out: dict[str, bytes | str] = {k: json.dumps(v) for k, v in files.items()}
    out["truncated.json"] = json.dumps(_constant())[:40]
    out["binary.json"] = bytes(range(200))
    out["utf16.json"] = json.dumps(_constant()).encode("utf-16")
    out["empty.json"] = ""
    return out


def networks() -> dict[str, bytes | str]:
    nan_tuning = {k: [0.1] for k in ("actuator_lo", "actuator_hi", "ks", "kd")}
    nan_tuning |= {"sensor_lo": [0.0] * 6, "sensor_hi": [float("nan")] * 6}
    files = {
        "string-counts.json": _network(n_hidden="five"),
        "unknown-creature.json": _network(creature="unicorn"),
        "weight-out-of-range.json": _network(weights=[[3] * 12] * 6),
        "k1-negative.json": _network(k1=[-1.0] * 6),
        "k2-positive.json": _network(k2=[1.0] * 6),
        "k1-wrong-length.json": _network(k1=[8.0] * 5),
        "nan-tuning.json": _network(tuning=nan_tuning),
        "wrong-format.json": _network(format="zoetic-sann"),
        "misspelled-key.json": _network(wieghts=[[0]]),
        "ragged-weights.json": _network(weights=[[0] * 12] * 5 + [[0] * 11]),
        "sensor-count-mismatch.json": _network(n_sensors=7),
        "wrong-size-for-creature.json": _network(weights=[[0] * 14] * 6, n_sensors=8),
        "string-weights.json": _network(weights=[["1"] * 12] * 6),
    }
    out: dict[str, bytes | str] = {k: json.dumps(v) for k, v in files.items()}
    out["binary.json"] = b"\x89PNG\r\n\x1a\n\x00\x00" * 20
    out["truncated.json"] = json.dumps(_network())[:100]
    return out


def repertoires() -> dict[str, dict[str, bytes | str]]:
    good = json.dumps(_constant())

    def index(*entries, **over):
        return json.dumps(
            {"animal": "shark", "actuators": SHARK_ACTS, "entries": list(entries)} | over
        )

    def entry(name="go-straight", file="go-straight.json", duration=4.0):
        return {"name": name, "file": file, "duration": duration}

    ray = json.dumps(_constant(animal="ray", actuators=[f"r{i}" for i in range(6)]))
    return {
        "negative-duration": {
            "repertoire.json": index(entry(duration=-4.0)),
            "go-straight.json": good,
        },
        "nan-duration": {
            "repertoire.json": index(entry(duration=float("nan"))),
            "go-straight.json": good,
        },
        "duplicated-entry": {"repertoire.json": index(entry(), entry()), "go-straight.json": good},
        "entry-is-directory": {
            "repertoire.json": index(entry(file="sub")),
            "sub/keep.txt": "a directory, not a controller\n",
        },
        "entry-for-another-animal": {
            "repertoire.json": index(entry(file="ray.json")),
            "ray.json": ray,
        },
        "missing-entry-file": {"repertoire.json": index(entry(file="gone.json"))},
        "misspelled-key": {"repertoire.json": index(entry(), entires=[]), "go-straight.json": good},
        "index-not-json": {"repertoire.json": "{animal: shark", "go-straight.json": good},
        "string-duration": {
            "repertoire.json": index(entry(duration="4 s")),
            "go-straight.json": good,
        },
        "entry-outside": {
            "repertoire.json": index(entry(file="../go-straight.json")),
            "go-straight.json": good,
        },
        "broken-controller": {"repertoire.json": index(entry()), "go-straight.json": good[:30]},
    }


def rundirs() -> dict[str, dict[str, bytes | str]]:
    c = CONFIG
    return {
        "string-budget": {"config.toml": _sub(c, "budget = 48", 'budget = "lots"')},
        "misspelled-key": {"config.toml": _sub(c, "optimizer =", "optimiser =")},
        "unknown-optimizer": {"config.toml": _sub(c, '"cmaes"', '"cmaess"')},
        "negative-budget": {"config.toml": _sub(c, "budget = 48", "budget = -5")},
        "one-node": {"config.toml": _sub(c, "nodes = 8", "nodes = 1")},
        "no-run-table": {"config.toml": c.split("[task]")[1]},
        "not-toml": {"config.toml": "[run\nanimal = shark\n"},
        "binary-config": {"config.toml": bytes(range(256))},
        "no-config": {"notes.txt": "not a run directory\n"},
        "float-seed": {"config.toml": _sub(c, "seed = 0", "seed = 0.5")},
        "huge-budget": {"config.toml": _sub(c, "budget = 48", "budget = 9000000")},
        "huge-popsize": {"config.toml": _sub(c, "seed = 0", "seed = 0\npopsize = 90000")},
        "huge-horizon": {"config.toml": _sub(c, "horizon = 4.0", "horizon = 1e9")},
    }


def _write(path: Path, data: bytes | str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data if isinstance(data, bytes) else data.encode())


def main() -> None:
    if ROOT.exists():
        shutil.rmtree(ROOT)
    for kind, files in (
        ("animal", animals()),
        ("creature", creatures()),
        ("controller", controllers()),
        ("network", networks()),
    ):
        for name, data in files.items():
            _write(ROOT / kind / name, data)
    for kind, dirs in (("repertoire", repertoires()), ("rundir", rundirs())):
        for name, files in dirs.items():
            for fname, data in files.items():
                _write(ROOT / kind / name / fname, data)
    n = sum(1 for p in ROOT.rglob("*") if p.is_file())
    print(f"wrote {n} files under {ROOT}")


if __name__ == "__main__":
    main()
