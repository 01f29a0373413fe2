"""Gait modes (``zoetic san search --gaits``) and evolution of body and network (``san evolve``)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from zoetic.cli import main
from zoetic.san import load_creature
from zoetic.san.creature_file import list_creatures
from zoetic.san.creature_file import load_creature as strict_load
from zoetic.san.evolve import (
    MUSCLE,
    EvolveError,
    body_from_genes,
    evolve,
    load_checkpoint,
    save_checkpoint,
    start_genes,
    write_evolve,
)
from zoetic.san.gaits import describe_gaits, feature_matrix, gait_features, mode_label
from zoetic.san.network import random_network
from zoetic.san.world import Rollout


@pytest.fixture(scope="module")
def cart():
    return load_creature("cart")


def _gait(rng, direction, speed, turns, airborne, bounce, contact, periodicity, noise):
    j = lambda v, s=1.0: float(v + noise * s * rng.standard_normal())  # noqa: E731
    return {
        "direction": direction,
        "speed_cm_s": speed,
        "log2_speed": math.log2(speed),
        "turns": j(turns),
        "airborne": min(max(j(airborne, 0.3), 0.0), 1.0),
        "bounce": j(bounce, 0.05),
        "periodicity": j(periodicity),
        "contact": {k: min(max(j(v), 0.0), 1.0) for k, v in contact.items()},
        "period_s": 0.5,
    }


def test_clustering_separates_distinct_gaits_and_merges_near_identical_ones():
    rng = np.random.default_rng(0)
    hop = dict(
        direction=1,
        speed=20.0,
        turns=0.1,
        airborne=0.4,
        bounce=0.08,
        contact={"L1": 0.3, "L2": 0.3},
        periodicity=0.9,
    )
    roll = dict(
        direction=1,
        speed=20.0,
        turns=3.0,
        airborne=0.0,
        bounce=0.01,
        contact={"L1": 0.6, "L2": 0.6},
        periodicity=0.8,
    )
    gaits = [_gait(rng, **hop, noise=0.02) for _ in range(6)]
    gaits += [_gait(rng, **roll, noise=0.02) for _ in range(5)]
    modes = describe_gaits(gaits)
    assert len(modes) == 2
    groups = sorted(sorted(m.members) for m in modes)
    assert groups == [list(range(6)), list(range(6, 11))]
    labels = {m.label.split(" (")[0].split(",")[0] for m in modes}
    assert labels == {"big hops", "cartwheels"}
    # near-identical gaits are one mode, however many
    same = [_gait(rng, **hop, noise=0.01) for _ in range(12)]
    assert len(describe_gaits(same)) == 1
    # the same gait in the other direction is another mode
    back = [_gait(rng, **{**hop, "direction": -1}, noise=0.01) for _ in range(3)]
    assert len(describe_gaits(same + back)) == 2


def _rollout(cart, angles, heights, seconds=2.0, other=None):
    """A made-up rollout: the root link at ``angles``, the other at ``other`` (default: the
    root's angle + 1.2 rad, the body turning as one)."""
    n = len(angles)
    poses = np.zeros((n, 2, 3))
    poses[:, :, 0] = np.linspace(0, 0.2, n)[:, None]
    poses[:, :, 1] = np.asarray(heights)[:, None]
    poses[:, 0, 2] = angles
    poses[:, 1, 2] = np.asarray(angles) + 1.2 if other is None else other
    return Rollout(
        metric=0.2,
        fell=False,
        distance=0.2,
        seconds=seconds,
        times=np.linspace(0, seconds, n),
        poses=poses,
        sensors=np.zeros((n, 6), bool),
        commands=np.zeros((n, 1)),
        targets=np.zeros((n, 1)),
    )


def test_gait_features_see_rolling_hopping_and_direction(cart):
    n = 200
    rolling = _rollout(cart, np.linspace(0, -4 * np.pi, n), np.full(n, 0.05))
    f = gait_features(cart, rolling)
    assert f["turns"] == pytest.approx(2.0, abs=1e-6)
    assert f["direction"] == 1 and f["speed_cm_s"] == pytest.approx(10.0)
    t = np.linspace(0, 2, n)
    high = _rollout(cart, np.zeros(n), 0.2 + 0.05 * np.sin(2 * np.pi * 2 * t))
    g = gait_features(cart, high)
    assert g["airborne"] == 1.0 and all(v == 0 for v in g["contact"].values())
    assert g["periodicity"] > 0.8 and g["period_s"] == pytest.approx(0.5, abs=0.03)
    low = _rollout(cart, np.zeros(n), np.zeros(n))  # lying flat: both links down
    assert all(v == 1.0 for v in gait_features(cart, low)["contact"].values())


def test_gait_features_see_a_chain_flipping_onto_its_back(cart):
    n = 400
    t = np.linspace(0, 4, n)
    # jumps over onto its back and back again each second: upside down half the time
    flips = _rollout(cart, np.pi * (0.5 - 0.5 * np.cos(2 * np.pi * t)), np.full(n, 0.05))
    f = gait_features(cart, flips)
    assert f["upside"] == pytest.approx(0.5, abs=0.02) and f["turns"] < 0.01
    assert mode_label(f).startswith("repeated flips onto its back")
    rocking = _rollout(cart, np.radians(40) * np.sin(2 * np.pi * t), np.full(n, 0.05))
    g = gait_features(cart, rocking)
    assert g["upside"] == 0.0 and not mode_label(g).startswith("flips")
    X, names = feature_matrix([f, g])
    assert abs(X[0, names.index("upside")] - X[1, names.index("upside")]) >= 2.0
    assert f["flips"] == 8 and g["flips"] == 0  # over and back each second, for 4 s


def test_one_link_swung_over_the_other_is_not_a_flip_onto_the_back(cart):
    n = 400
    t = np.linspace(0, 4, n)
    lift = np.radians(120) * (0.5 - 0.5 * np.cos(2 * np.pi * t))
    # the root link heaved over the other and back each second; the other lies flat
    heave = _rollout(cart, lift, np.full(n, 0.05), other=np.zeros(n))
    f = gait_features(cart, heave)
    assert f["upside"] == 0.0 and f["flips"] == 0
    assert not mode_label(f).startswith(("flips", "repeated"))
    # the other link folded right over the root one (a 180 degree joint): not turned over
    fold = _rollout(
        cart, np.zeros(n), np.full(n, 0.05), other=np.pi * (0.5 - 0.5 * np.cos(np.pi * t))
    )
    assert gait_features(cart, fold)["flips"] == 0


def test_repeated_flips_onto_the_back_are_named_apart_from_one_flip(cart):
    n = 600
    t = np.linspace(0, 6, n)
    # over onto its back at 1 s, back onto its front at 3 s, over again at 5 s
    side = np.clip(t - 0.5, 0, 1) - np.clip(t - 2.5, 0, 1) + np.clip(t - 4.5, 0, 1)
    f = gait_features(cart, _rollout(cart, np.pi * side, np.full(n, 0.05), seconds=6.0))
    assert f["flips"] == 3 and f["turns"] == pytest.approx(0.5, abs=1e-6)
    assert mode_label(f).startswith("repeated flips onto its back")
    once = np.pi * np.clip(t - 0.5, 0, 1)  # over once, then lies on its back
    g = gait_features(cart, _rollout(cart, once, np.full(n, 0.05), seconds=6.0))
    assert g["flips"] == 1 and mode_label(g).startswith("flips onto its back")
    # over and back once (onto its back only once): not repeated
    there_and_back = np.pi * (np.clip(t - 0.5, 0, 1) - np.clip(t - 2.5, 0, 1))
    h = gait_features(cart, _rollout(cart, there_and_back, np.full(n, 0.05), seconds=6.0))
    assert h["flips"] == 2 and mode_label(h).startswith("flips onto its back")


def test_search_gaits_cli_writes_modes_with_a_count(tmp_path):
    out = tmp_path / "cart"
    argv = [
        "san",
        "search",
        "cart",
        "--trials",
        "6",
        "--top",
        "4",
        "--seconds",
        "0.6",
        "--workers",
        "1",
        "--out",
        str(out),
        "--no-video",
        "--gaits",
    ]
    assert main(argv) == 0
    doc = json.loads((out / "modes.json").read_text())
    assert doc["creature"] == "cart" and 1 <= doc["modes_found"] <= doc["gaits"] <= 4
    assert doc["modes_found"] == len(doc["modes"])
    assert sum(m["count"] for m in doc["modes"]) == doc["gaits"]
    assert doc["threshold"] > 0 and len(doc["scaled"]) == doc["gaits"]


# --- evolution -------------------------------------------------------------------------------


def test_body_coupling_longer_links_and_stronger_actuators_weigh_more(cart):
    genes = start_genes(cart)
    same = body_from_genes(cart, genes)
    assert [ln.mass for ln in same.links] == [ln.mass for ln in cart.links]
    longer = {**genes, "length": np.array([1.5, 1.0])}
    body = body_from_genes(cart, longer)
    assert body.links[0].mass == pytest.approx(1.5 * cart.links[0].mass)
    assert body.links[0].length == pytest.approx(1.5 * cart.links[0].length)
    assert body.sensors[1].at == pytest.approx(1.5 * cart.sensors[1].at)  # probe on the tip
    thicker = body_from_genes(cart, {**genes, "section": np.array([1.0, 2.0])})
    # L2 carries A1's muscle: only its structural share doubles
    assert thicker.links[1].mass == pytest.approx(cart.links[1].mass * (2 - MUSCLE))
    ks = np.array([2 * cart.actuators[0].ks])
    strong = body_from_genes(cart, genes, ks)
    assert strong.links[1].mass == pytest.approx(cart.links[1].mass * (1 + MUSCLE))
    assert strong.links[0].mass == cart.links[0].mass and strong.actuators[0].ks == ks[0]


def _reach(target):
    """A toy objective: the closer L1 is to ``target`` metres long, the better."""

    def evaluate(network, creature):
        return -abs(creature.links[0].length - target)

    return evaluate


def test_evolve_improves_its_objective_and_resumes_to_the_same_result(cart):
    net = random_network(cart, np.random.default_rng(0))
    full = evolve(net, cart, trials=40, seed=2, evaluate=_reach(0.2))
    assert full.after > full.before
    assert full.creature.links[0].length > cart.links[0].length
    assert full.creature.links[0].mass > cart.links[0].mass  # longer, so heavier
    saved = {}
    evolve(
        net,
        cart,
        trials=20,
        seed=2,
        evaluate=_reach(0.2),
        checkpoint=lambda t, _sa, h: saved.update({t: h}),
    )
    again = evolve(net, cart, trials=40, seed=2, evaluate=_reach(0.2), resume=saved[20])
    assert again.after == full.after
    np.testing.assert_array_equal(again.best, full.best)


def test_evolve_writes_a_valid_creature_file(cart, tmp_path):
    net = random_network(cart, np.random.default_rng(1))
    res = evolve(net, cart, trials=3, seed=0, seconds=0.3)
    summary = write_evolve(res, tmp_path)
    body = strict_load(tmp_path / "creature.toml")
    assert body.name == "cart-evolved" and len(body.links) == 2
    assert summary["speed_after_cm_s"] >= summary["speed_before_cm_s"]
    rows = {r["parameter"]: r for r in summary["changes"]}
    assert rows["L1 length (m)"]["before"] == cart.links[0].length
    # the checkpoint round-trips and refuses another run's
    history = {
        "before": 1.0,
        "accepted": 2,
        "done": 3,
        "temperature": 0.1,
        "current": [1.0, 1.0, 2.0],
        "best": [1.0, 1.0, 2.0],
        "tried": [np.nan, 1.0, 2.0],
        "state": {"x": np.ones((1, 3)), "T": 0.1, "rng": {"a": 1}},
    }
    save_checkpoint(tmp_path / "c.npz", {"seed": 0}, history)
    back = load_checkpoint(tmp_path / "c.npz", {"seed": 0})
    assert back["done"] == 3 and back["state"]["rng"] == {"a": 1}
    with pytest.raises(EvolveError, match="differs in seed"):
        load_checkpoint(tmp_path / "c.npz", {"seed": 1})


def test_evolve_cli_end_to_end_and_bad_input_exits_2(tmp_path, capsys):
    out = tmp_path / "ev"
    argv = [
        "san",
        "evolve",
        "cart",
        "--search",
        "4",
        "--trials",
        "4",
        "--out",
        str(out),
        "--no-video",
        "--workers",
        "1",
    ]
    assert main(argv) == 0
    assert strict_load(out / "creature.toml").name == "cart-evolved"
    assert "what evolution changed" in capsys.readouterr().out
    assert main(argv + ["--resume"]) == 0  # a finished run resumes to the same result
    assert main(["san", "evolve", "nosuch"]) == 2
    assert "unknown creature 'nosuch'" in capsys.readouterr().err
    assert (
        main(
            [
                "san",
                "evolve",
                "crawler",
                "--search",
                "2",
                "--trials",
                "2",
                "--out",
                str(tmp_path / "cr"),
                "--no-video",
            ]
        )
        == 2
    )
    assert "slide joints" in capsys.readouterr().err
    bad = argv[:-3] + ["--seed", "5", "--resume", "--no-video", "--workers", "1"]
    assert main(bad) == 2
    assert "different run" in capsys.readouterr().err


def test_the_folding_twolink_differs_from_the_zoos_only_in_its_servos_range_and_damping():
    from pathlib import Path

    zoo = load_creature("twolink")
    path = Path(__file__).parents[1] / "src/zoetic/san/zoo/variants/twolink-fold.toml"
    fold = strict_load(f"{path}")
    assert fold.name == "twolink-fold" and "twolink-fold" not in list_creatures()
    assert (fold.links, fold.joints, fold.sensors) == (zoo.links, zoo.joints, zoo.sensors)
    assert (fold.seconds, fold.friction, fold.expected_cycle) == (
        zoo.seconds,
        zoo.friction,
        zoo.expected_cycle,
    )
    (a,), (b,) = zoo.actuators, fold.actuators
    assert b.ks == pytest.approx(a.ks)  # the zoo's stiffness
    assert b.kd == pytest.approx(0.05 * b.ks)  # the cart's Fig. 11 kd/ks, s
    assert (b.lo, b.hi) == pytest.approx((-math.pi, math.pi))  # it may fold shut
