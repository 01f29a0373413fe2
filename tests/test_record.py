"""The run record: what is written is what is read, field by field; a damaged or foreign file is
refused with a ZoeticError that names it."""

from __future__ import annotations

import dataclasses
import io
import json
import zipfile

import numpy as np
import pytest

from zoetic.errors import RunDirError, ZoeticError
from zoetic.record import (
    FILE,
    Animal,
    Creature,
    Event,
    Link,
    Record,
    Thing,
    read_record,
    write_record,
)


def _record() -> Record:
    rng = np.random.default_rng(0)
    t, n = 5, 4
    times = np.linspace(0.0, 0.4, t)
    fish = Animal(
        "fish 1",
        "minnow",
        np.array([[0, 1, 2], [1, 2, 3]], np.int32),
        rng.normal(size=(t, n, 3)).astype(np.float32),
        np.array([1, 2, 1, 2], np.float32),
        (200, 100, 50),
        ("left", "right"),
        rng.uniform(size=(t, 2)).astype(np.float32),
    )
    shark = Animal(
        "shark",
        "shark",
        np.array([[0, 1, 2]], np.int32),
        rng.normal(size=(t, 3, 3)).astype(np.float32),
        np.ones(3, np.float32),
    )
    link = Link(
        "torso",
        (10, 20, 30),
        rng.normal(size=(6, 3)).astype(np.float32),
        np.array([[0, 1, 2], [3, 4, 5]], np.int32),
        rng.normal(size=(t, 3)).astype(np.float32),
        rng.normal(size=t).astype(np.float32),
        "z",
    )
    walker = Creature(
        "walker",
        (link,),
        rng.normal(size=(t, 3)).astype(np.float32),
        ("hip",),
        rng.uniform(size=(t, 1)).astype(np.float32),
    )
    things = (
        Thing(
            "food",
            "food 1",
            "sphere",
            (0.1,),
            rng.normal(size=(t, 3)).astype(np.float32),
            visible=np.array([True, True, False, False, False]),
        ),
        Thing("rock", "rock0", "box", (0.5, 0.4, 0.3), np.array([[1, 2, 3]], np.float32)),
        Thing("seaweed", "seaweed1", "cylinder", (0.04, 1.2), np.zeros((1, 3), np.float32), "y"),
        Thing("target", "target 1", "point", (), np.ones((1, 3), np.float32)),
    )
    scalars = {
        "fish 1": {
            "hunger": rng.uniform(size=3).astype(np.float32),
            "intention": np.array([0, 2, 1], np.float32),
        },
        "shark": {"gaze": rng.normal(size=(3, 4)).astype(np.float32)},
    }
    return Record(
        "aquarium",
        "a tank",
        "water",
        times,
        (fish, shark),
        (walker,),
        things,
        (Event(0.1, "shark", "eat", "food 1"), Event(0.3, "fish 1", "escape")),
        np.array([0.0, 0.2, 0.4]),
        scalars,
        {"intention": ["wander", "eat", "flee"]},
        {"hunger": "", "gaze": "rad"},
        {"survivors": 2, "note": "x", "ok": True},
        {"E": np.float32([3, np.inf, 1, 2]), "best_E": np.float32([3, 3, 1, 1])},
    )


def _equal(a, b, where: str = "record") -> None:
    """Assert two records' fields (nested dataclasses, arrays, dicts) are equal."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            _equal(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _equal(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _equal(x, y, f"{where}[{k}]")
    elif isinstance(a, np.ndarray):
        assert a.shape == np.shape(b) and np.array_equal(a, b), where
    else:
        assert a == b, where


def test_what_is_written_is_read_field_by_field(tmp_path):
    rec = _record()
    path = write_record(tmp_path, rec)
    assert path == tmp_path / FILE
    back = read_record(tmp_path)
    _equal(rec, back)
    assert back.animals[0].positions.dtype == np.float32 and back.times.dtype == np.float64
    assert back.objects[0].visible.dtype == bool
    assert not list(tmp_path.glob("*.tmp"))  # written through a temporary file and a rename


def test_a_record_without_a_search_history_reads_with_none(tmp_path):
    path = write_record(tmp_path, _record())
    _rewrite(path, lambda m, a: [m.pop("history"), a.pop("history/E"), a.pop("history/best_E")])
    assert read_record(path).history == {}


def _rewrite(path, change) -> None:
    """Rewrite a record file with its header or arrays changed by ``change(meta, arrays)``."""
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(arrays.pop("meta").tobytes())
    change(meta, arrays)
    buf = io.BytesIO()
    np.savez(buf, meta=np.frombuffer(json.dumps(meta).encode(), np.uint8), **arrays)
    path.write_bytes(buf.getvalue())


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda m, a: m.update(format="something-else"), "format = 'zoetic-record'"),
        (lambda m, a: m.update(version=99), "record version 99"),
        (lambda m, a: a.pop("animal/0/positions"), "no array 'animal/0/positions'"),
        (
            lambda m, a: a.update({"animal/0/faces": np.array([[0, 1, 9]], np.int32)}),
            "animal/0/faces indexes vertices outside 0..3",
        ),
        (
            lambda m, a: a.update({"animal/1/mass": np.ones(7, np.float32)}),
            "animal/1/mass has shape",
        ),
        (lambda m, a: a.update({"times": np.array([0.0, 0.2, 0.1, 0.3, 0.4])}), "non-decreasing"),
        (
            lambda m, a: a.update({"animal/0/mass": np.float32([1, np.nan, 1, 2])}),
            "animal/0/mass holds non-finite values",
        ),
        (lambda m, a: m["objects"][1].update(shape="cone"), "objects[1]: shape must be"),
        (lambda m, a: m["objects"][1].update(size=[0.5, -1, 0.3]), "3 positive sizes"),
        (lambda m, a: m["events"].append(["soon", "x", "y", "z"]), "an event must be"),
        (
            lambda m, a: a.update({"scalar/shark/gaze": np.ones((2, 4), np.float32)}),
            "scalar/shark/gaze must be float with 3 rows",
        ),
        (lambda m, a: m.pop("numbers"), "the header needs"),
        (lambda m, a: a.pop("history/E"), "history/E must be a float array (K,)"),
    ],
)
def test_a_damaged_record_is_refused_naming_the_file(tmp_path, change, message):
    path = write_record(tmp_path, _record())
    _rewrite(path, change)
    with pytest.raises(RunDirError) as err:
        read_record(path)
    assert str(path) in str(err.value) and message in str(err.value)


def test_a_foreign_or_truncated_file_is_refused_naming_it(tmp_path):
    path = write_record(tmp_path, _record())
    data = path.read_bytes()
    cases = {
        "truncated.npz": data[: len(data) // 2],
        "text.npz": b"not a zip at all",
        "empty.npz": b"",
    }
    buf = io.BytesIO()
    np.savez(buf, times=np.zeros(3))  # a NumPy archive, but not a record
    cases["foreign.npz"] = buf.getvalue()
    zbuf = io.BytesIO()
    with zipfile.ZipFile(zbuf, "w") as zf:
        zf.writestr("meta.npy", b"\x93NUMPY garbage")
    cases["garbage.npz"] = zbuf.getvalue()
    for name, raw in cases.items():
        bad = tmp_path / name
        bad.write_bytes(raw)
        with pytest.raises(ZoeticError, match=str(bad).replace(".", r"\.")):
            read_record(bad)
    with pytest.raises(ZoeticError, match="no run record"):
        read_record(tmp_path / "nowhere")


def test_a_record_that_could_not_be_read_is_not_written(tmp_path):
    rec = dataclasses.replace(_record(), times=np.array([0.0, 1.0]))  # 2 times, 5 positions
    with pytest.raises(RunDirError, match="animal/0/positions has shape"):
        write_record(tmp_path, rec)
    assert not (tmp_path / FILE).exists()


def test_a_record_larger_than_the_memory_limit_is_refused_unread(tmp_path, monkeypatch):
    import zoetic.record as record

    path = write_record(tmp_path, _record())
    monkeypatch.setattr(record, "LIMITS", dataclasses.replace(record.LIMITS, memory_bytes=100))
    with pytest.raises(RunDirError, match=r"MiB of arrays, more than a run record may hold"):
        read_record(path)


def test_a_simulate_run_records_its_motion_as_measured_from_its_positions(tmp_path):
    """A shark at rest dropped at the sea's surface sinks: its record carries, per recorded
    instant, a depth that grows, no roll, and what the measure gives of its positions."""
    from zoetic.bodies import load_animal
    from zoetic.control.measure import motion_scalars
    from zoetic.physics import get_medium
    from zoetic.runs import simulate_run

    simulate_run("shark", "rest", 0.6, tmp_path, medium="sea")
    rec = read_record(tmp_path)
    got = rec.scalars["shark"]
    assert set(got) == {"speed", "depth", "heading", "pitch", "roll"}
    np.testing.assert_array_equal(rec.period_times, rec.times)
    assert rec.units["depth"] == "m" and rec.units["speed"] == "m/s"
    assert rec.units["heading"] == rec.units["pitch"] == rec.units["roll"] == "deg"
    depth = got["depth"]
    assert depth[-1] > depth[0] + 0.05 and np.all(np.diff(depth[:20]) > 0)  # it sinks
    assert np.abs(got["roll"]).max() < 0.5  # deg: upright, a symmetric body at rest
    want = motion_scalars(
        load_animal("shark"), rec.animals[0].positions[None], rec.times, get_medium("sea")
    )
    for q, v in want.items():
        np.testing.assert_allclose(got[q], v[0], atol=1e-5)
