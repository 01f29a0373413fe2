"""``zoetic san ...`` through the real entry point, on real (MuJoCo) creatures, short runs."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zoetic.cli import main
from zoetic.san import load_creature
from zoetic.san.network import (
    SanPolicy,
    load_network,
    load_with_creature,
    random_network,
    save_network,
)
from zoetic.san.search import search, useful_mask
from zoetic.san.tune import tune
from zoetic.san.world import World

SECONDS = 1.0


@pytest.fixture(scope="module")
def cart():
    return load_creature("cart")


@pytest.fixture(scope="module")
def search_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("san") / "cart"
    argv = [
        "san",
        "search",
        "cart",
        "--trials",
        "8",
        "--top",
        "3",
        "--seed",
        "0",
        "--seconds",
        str(SECONDS),
        "--workers",
        "2",
        "--out",
        str(out),
        "--no-video",
    ]
    assert main(argv) == 0
    return out


def test_search_writes_ranked_reloadable_networks(search_run, cart):
    rows = np.loadtxt(search_run / "trials.csv", delimiter=",", skiprows=1)
    assert rows.shape == (8, 5)
    metrics = rows[:, 1]
    assert (search_run / "ranking.png").stat().st_size > 5000
    kept = [load_network(search_run / "sans" / f"{r:02d}.json", cart) for r in (1, 2, 3)]
    assert not (search_run / "sans" / "04.json").exists()
    recorded = [n.info["metric"] for n in kept]
    assert recorded == sorted(recorded, reverse=True)
    assert recorded[0] == pytest.approx(metrics.max(), rel=1e-5)
    # the saved network replays to the same metric
    world = World(cart)
    again = world.run(SanPolicy(kept[0], cart), seconds=SECONDS).metric
    assert again == pytest.approx(recorded[0], rel=1e-9, abs=1e-12)
    summary = json.loads((search_run / "summary.json").read_text())
    assert summary["creature"] == "cart" and summary["trials"] == 8
    n_abs = int(useful_mask(search(cart, trials=8, seed=0, seconds=SECONDS), 5.75).sum())
    assert (
        summary["useful_absolute"].startswith(f"{n_abs}/8 (")
        and ">= 5.75 cm/s" in summary["useful_absolute"]
    )


def test_fixed_seed_search_is_reproducible(cart):
    a = search(cart, trials=4, seed=3, seconds=0.5, workers=1)
    b = search(cart, trials=4, seed=3, seconds=0.5, workers=2)
    np.testing.assert_array_equal(a.metrics, b.metrics)
    np.testing.assert_array_equal(a.distances, b.distances)
    assert len(set(a.distances.tolist())) > 1  # different networks do move differently


def test_tuned_network_is_at_least_as_fast_and_replays(search_run, cart, tmp_path):
    out = tmp_path / "cart1"
    argv = [
        "san",
        "tune",
        str(search_run / "sans" / "01.json"),
        "--method",
        "sga",
        "--trials",
        "6",
        "--out",
        str(out),
        "--no-video",
    ]
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    net = load_network(out / "san.json", cart)
    start = load_network(out / "start.json", cart)
    np.testing.assert_array_equal(net.weights, start.weights)
    tuned = net.tuned_creature(cart)
    after = World(tuned).run(SanPolicy(net, tuned)).metric  # its own metric, full seconds
    before = World(cart).run(SanPolicy(start, cart)).metric
    assert after >= before
    assert summary["metric_after"] == pytest.approx(after, abs=1e-4)
    assert summary["metric_before"] == pytest.approx(before, abs=1e-4)


def test_annealing_tune_never_worse(cart):
    net = random_network(cart, np.random.default_rng(1))
    res = tune(net, cart, method="anneal", trials=4, seed=0, seconds=0.5)
    assert res.after >= res.before
    assert np.all(np.diff(res.best) >= 0)


def test_show_writes_a_video_with_the_network_beside(search_run, tmp_path):
    pytest.importorskip("zoetic.viz.san")
    video = tmp_path / "shown" / "show.mp4"  # --out is a directory, the video inside it
    argv = ["san", "show", str(search_run), "--seconds", "0.5", "--out", str(video.parent)]
    assert main(argv) == 0
    import imageio.v3 as iio

    frames = iio.imread(video)
    assert frames.shape[0] >= 14 and frames.shape[-1] == 3
    assert frames.shape[2] > frames.shape[1]  # wide: creature and side panel


def test_bad_weights_are_refused_naming_the_file(tmp_path, cart, capsys):
    net = random_network(cart, np.random.default_rng(0))
    data = net.to_dict()
    data["weights"][2][1] = 3
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    assert main(["san", "tune", str(bad), "--trials", "1", "--no-video"]) == 2
    err = capsys.readouterr().err
    assert "bad.json" in err and "out of range" in err


def test_network_for_another_creature_is_refused(tmp_path, cart, capsys):
    path = save_network(random_network(cart, np.random.default_rng(0)), tmp_path / "c.json")
    assert main(["san", "tune", str(path), "--creature", "walker", "--trials", "1"]) == 2
    err = capsys.readouterr().err
    assert "c.json" in err and "network is for creature 'cart', not 'walker'" in err


def test_bench_san_prints_json(capsys):
    code = main(["bench", "san", "--creature", "cart", "--trials", "4", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["cart_4_trials_seconds"] > 0 and out["steps_per_second"] > 0
    # set-up and one trial timed apart in this process (san.search.time_one_trial)
    assert out["compile_seconds"] > 0 and out["one_trial_seconds_in_process"] > 0


def test_unknown_method_terrain_or_creature_exit_2(capsys):
    assert main(["san", "tune", "x.json", "--method", "newton"]) == 2
    assert "unknown tuning method 'newton'" in capsys.readouterr().err
    assert main(["san", "search", "cart", "--terrain", "bumpy", "--trials", "1"]) == 2
    assert "unknown terrain 'bumpy'" in capsys.readouterr().err
    assert main(["san", "search", "unicorn", "--trials", "1"]) == 2
    assert "unicorn" in capsys.readouterr().err


def test_a_san_found_for_a_creature_file_is_tuned_shown_and_evolved(tmp_path):
    """The SAN file carries its creature: a creature that is in no zoo goes the whole way."""
    from zoetic.san.creature import ZOO_DIR

    text = (ZOO_DIR / "cart.toml").read_text()
    text = text.replace('name = "cart"', 'name = "longcart"')
    text = text.replace("length = 0.12", "length = 0.14", 1)
    mine = tmp_path / "my_creature.toml"
    mine.write_text(text)
    run = tmp_path / "r"
    search_argv = [
        "san",
        "search",
        str(mine),
        "--trials",
        "3",
        "--top",
        "2",
        "--seconds",
        "0.5",
        "--workers",
        "1",
        "--out",
        str(run),
        "--no-video",
    ]
    assert main(search_argv) == 0
    mine.unlink()  # the SAN file alone is enough from here on
    san = run / "sans" / "01.json"
    net, creature = load_with_creature(san)
    assert creature.name == "longcart" and creature.links[0].length == 0.14
    tuned = tmp_path / "t"
    argv = ["san", "tune", str(san), "--trials", "2", "--out", str(tuned), "--no-video"]
    assert main(argv) == 0
    assert load_with_creature(tuned / "san.json")[1].links[0].length == 0.14
    show = [
        "san",
        "show",
        str(tuned / "san.json"),
        "--seconds",
        "0.2",
        "--out",
        str(tmp_path / "shown"),
    ]
    assert main(show) == 0
    assert (tmp_path / "shown" / "show.mp4").stat().st_size > 1000
    evolve = [
        "san",
        "evolve",
        "--network",
        str(san),
        "--trials",
        "2",
        "--out",
        str(tmp_path / "e"),
        "--no-video",
    ]
    assert main(evolve) == 0


def test_an_old_san_file_naming_a_zoo_creature_still_loads(search_run, tmp_path):
    data = json.loads((search_run / "sans" / "01.json").read_text())
    del data["creature_def"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    net, creature = load_with_creature(old)
    assert creature.name == "cart" and creature.path.name == "cart.toml"
    assert net == load_network(search_run / "sans" / "01.json")
