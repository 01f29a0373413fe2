"""Which fish-fish collisions happen in the default tank, and what the fishes were doing.

For every fish-fish ``collision`` event: the pair's species, each fish's intention in the
period of the touch and whether it avoided within the 2 s before, the angle between their
headings (0: same way, 180: head on), where each lay from the other (bearing from the heading,
0: dead ahead) and their closing speed 0.5 s before. One JSON line a seed (the bench's
figures and the collisions), then counts by kind:
    python experiments/aquarium_collisions.py [--seeds 0 1 ... 11] [--seconds 60]
"""

from __future__ import annotations

import argparse
import collections
import json

import numpy as np
from aquarium_forage import timed_life  # this directory's: run as a script

from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live
from zoetic.behavior.mind import INTENTIONS


def _motion(life, i: int, r: int, back: int) -> tuple[np.ndarray, np.ndarray]:
    """Return fish i's centre at record r and its horizontal velocity over ``back`` records."""
    c = life.positions[i].mean(axis=1)
    r0 = max(r - back, 0)
    v = (c[r] - c[r0]) / max(life.times[r] - life.times[r0], 1e-9)
    v[1] = 0.0
    return c[r], v


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arctan2(a[0] * b[2] - a[2] * b[0], a @ b)))


def _along(nodes: np.ndarray, v: np.ndarray, point: np.ndarray) -> float:
    """Return where ``point`` lies along a body of ``nodes`` (N, 3) swimming along ``v``
    (horizontal): +1 at its foremost node (the nose), -1 at its rearmost (the tail)."""
    f = v / max(float(np.linalg.norm(v)), 1e-9)
    x = (nodes - nodes.mean(axis=0)) @ f
    half = max(float(x.max() - x.min()) / 2.0, 1e-9)
    return round(float((point - nodes.mean(axis=0)) @ f / half), 1)


def _contact(life, i: int, j: int, r: int, vi: np.ndarray, vj: np.ndarray) -> list[float]:
    """Return where the two bodies came nearest at record r, along each (``_along``)."""
    a, b = life.positions[i][r], life.positions[j][r]
    d = np.linalg.norm(a[:, None] - b[None], axis=-1)
    p, q = np.unravel_index(int(d.argmin()), d.shape)
    return [_along(a, vi, a[p]), _along(b, vj, b[q])]


def kind_of(c: dict) -> str:
    """The collision's kind: a predator against the prey it caught (the body stays in the
    water), a fish against the body of one caught before (a dead body), else by where each
    body was touched: a fish's head (+0.5 to +1 along it) into the other's flank or tail is
    a strike by it; both heads, nose to nose; neither head, side by side (flank or tail
    swept into the other)."""
    if c["caught"]:
        return "caught prey"
    if c.get("dead"):
        return "dead body"
    head = [x >= 0.5 for x in c["contact"]]
    if all(head):
        return "nose to nose"
    if any(head):
        return "strike"
    return "side by side"


def _errand(life, k0: int, k: int, i: int) -> list:
    """Return fish i's last intention other than avoid over brain periods k0..k and its
    target then (-1: none); ["avoid", -1] when it avoided throughout."""
    avoid = INTENTIONS.index("avoid")
    for m in range(k, k0 - 1, -1):
        if life.intentions[m, i] != avoid:
            return [INTENTIONS[life.intentions[m, i]], int(life.targets[m, i])]
    return ["avoid", -1]


def describe(tank, life, t: float, a: str, b: str) -> dict:
    """Return what the two fishes did at the collision at time t."""
    names = [f.name for f in tank.fishes]
    i, j = names.index(a), names.index(b)
    caught = any(
        e[2] == "catch" and {e[1], e[3]} == {a, b} and e[0] <= t + 1e-6 for e in life.events
    )
    # one of the two was caught before by another fish: its body lay in the water
    dead = any(e[2] == "catch" and e[3] in (a, b) and e[0] < t - 1e-6 for e in life.events)
    k = int(np.searchsorted(life.brain_times, t - 1e-6) - 1)
    k0 = max(k - 20, 0)
    r = int(np.searchsorted(life.times, t - 1e-6))
    r = min(r, len(life.times) - 1)
    (ci, vi), (cj, vj) = _motion(life, i, r, 3), _motion(life, j, r, 3)
    pi, pvi = _motion(life, i, max(r - 5, 0), 3)
    pj, pvj = _motion(life, j, max(r - 5, 0), 3)
    rel = pj - pi
    closing = -float(rel @ (pvj - pvi)) / max(float(np.linalg.norm(rel)), 1e-9)
    avoid = INTENTIONS.index("avoid")
    return {
        "t": round(t, 1),
        "pair": [tank.fishes[i].species.name, tank.fishes[j].species.name],
        "intentions": [INTENTIONS[life.intentions[k, i]], INTENTIONS[life.intentions[k, j]]],
        # each fish's errand (its last intention other than avoid in the 2 s before, and its
        # target then: a food particle for eat): two fishes after one particle show here
        "errands": [_errand(life, k0, k, i), _errand(life, k0, k, j)],
        "avoided_before": [
            bool((life.intentions[k0:k, i] == avoid).any()),
            bool((life.intentions[k0:k, j] == avoid).any()),
        ],
        "heading_deg": round(abs(_angle(vi, vj))),
        "bearing_deg": [round(_angle(vi, cj - ci)), round(_angle(vj, ci - cj))],
        "speeds": [round(float(np.linalg.norm(vi)), 2), round(float(np.linalg.norm(vj)), 2)],
        "closing_m_s": round(closing, 2),
        "contact": _contact(life, i, j, r, vi, vj),
        "caught": caught,
        "dead": dead and not caught,
    }


def run(seed: int, seconds: float) -> dict:
    """Live the default scene from ``seed``; return its figures and its fish collisions."""
    tank, life, s, cpu = timed_life(seed, seconds)
    fish = {f.name for f in tank.fishes}
    hits = [
        describe(tank, life, t, a, d)
        for t, a, e, d in life.events
        if e == "collision" and d in fish
    ]
    return {
        "seed": seed,
        "food_eaten": round(s["food_eaten_fraction"], 3),
        "fish_collisions_per_minute": round(60 * s["collisions_between_fishes"] / s["seconds"], 2),
        "caught_prey_touches": sum(kind_of(c) == "caught prey" for c in hits),
        "dead_body_touches": sum(kind_of(c) == "dead body" for c in hits),
        "avoid": round(s["intention_share"]["avoid"], 3),
        "cpu_realtime_factor": round(seconds / cpu, 2),
        "collisions": hits,
    }


def kinds(rows: list[dict]) -> dict:
    """Count the collisions by kind: species pair, intentions, heading class."""
    out: dict[str, collections.Counter] = {
        k: collections.Counter()
        for k in ("kind", "striker", "pair", "intentions", "avoided_before", "heading")
    }
    for row in rows:
        for c in row["collisions"]:
            out["kind"][kind_of(c)] += 1
            if kind_of(c) == "strike":  # the striking fish's species and intention
                s = 0 if c["contact"][0] >= 0.5 else 1
                out["striker"][f"{c['pair'][s]} {c['intentions'][s]}"] += 1
            out["pair"]["-".join(sorted(c["pair"]))] += 1
            out["intentions"]["+".join(sorted(c["intentions"]))] += 1
            out["avoided_before"][str(sum(c["avoided_before"]))] += 1
            h = c["heading_deg"]
            out["heading"][
                "same way <60" if h < 60 else "head on >120" if h > 120 else "crossing"
            ] += 1
    return {k: dict(v.most_common()) for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(12)))
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    live(build_tank(TankConfig(fishes=2, food=1, obstacles=1, seconds=0.2)))  # compile
    rows = []
    for s in args.seeds:
        rows.append(run(s, args.seconds))
        print(json.dumps(rows[-1]), flush=True)
    print(
        json.dumps(
            {
                "mean_food_eaten": round(float(np.mean([r["food_eaten"] for r in rows])), 3),
                "mean_fish_collisions_per_minute": round(
                    float(np.mean([r["fish_collisions_per_minute"] for r in rows])), 2
                ),
                # a predator touching the prey it caught is a catch, not a failed avoidance
                "mean_without_caught_prey_per_minute": round(
                    float(
                        np.mean(
                            [
                                r["fish_collisions_per_minute"]
                                - 60 * r["caught_prey_touches"] / args.seconds
                                for r in rows
                            ]
                        )
                    ),
                    2,
                ),
                # nor a fish against a dead fish's body in the water (``dead_body_touches``;
                # the fishes steer round bodies as obstacles, ``shoal.carcasses``)
                "mean_without_caught_prey_or_dead_bodies_per_minute": round(
                    float(
                        np.mean(
                            [
                                r["fish_collisions_per_minute"]
                                - 60
                                * (r["caught_prey_touches"] + r["dead_body_touches"])
                                / args.seconds
                                for r in rows
                            ]
                        )
                    ),
                    2,
                ),
                "kinds": kinds(rows),
            }
        )
    )


if __name__ == "__main__":
    main()
