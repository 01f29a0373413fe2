"""The last brain periods before every fish-fish touch of the default tank, both fishes'.

For each fish-fish ``collision`` event of the seeds given: one line a brain period over the
``--before`` s up to the touch, with the centres' distance (m) and, for each of the two
fishes, its intention, target, side of avoidance (+1 left), whether something lies ahead
(``h``: an obstacle or a fish, then whether only a fish threatens), how near (m) the nearest
threatening fish's contact is (``nr``, ``fish_threats``), its horizontal speed (m/s), the
bearing of the other fish from its heading (degrees, left positive) and the motor demand its
routine asked (speed m/s, turn rad, left positive); then the touch's marks (``marks``):
    python experiments/aquarium_touch_trace.py [--seeds 0 1 ...] [--before 1.5]
"""

from __future__ import annotations

import argparse

import numpy as np

from zoetic.behavior.aquarium import shoal as sh
from zoetic.behavior.aquarium.tank import TankConfig, build_tank, live

Row = dict  # one fish's line at one brain period


def recorder(log: list[list[Row | None]]) -> None:
    """Wrap ``Shoal._ahead`` and ``Shoal._respond`` so that every brain period appends each
    fish's line (None: dead) to ``log``."""
    ahead, respond = sh.Shoal._ahead, sh.Shoal._respond
    seen: dict[str, tuple] = {}

    def ahead_kept(self, pc, selves, meals, alive, food):
        seen["ahead"] = ahead(self, pc, selves, meals, alive, food)
        return seen["ahead"]

    def respond_logged(self, living, minds, targets, now):
        moves, heights = respond(self, living, minds, targets, now)
        hits, _, near, only = seen["ahead"]
        b, rows = self.bodies, []
        for i, m in enumerate(minds):
            rows.append(
                None
                if m is None
                else {
                    "it": m.intention,
                    "target": targets[i],
                    "side": self.brains[i].avoid_side,
                    "hit": int(hits[i]),
                    "only": int(only[i]),
                    "near": float(near[i]),
                    "com": b.com[i].copy(),
                    "fwd": b.fwd[i].copy(),
                    "v": float(np.hypot(b.vel[i][0], b.vel[i][2])),
                    "ask": moves.get(i, (0.0, 0.0)),
                }
            )
        log.append(rows)
        return moves, heights

    sh.Shoal._ahead, sh.Shoal._respond = ahead_kept, respond_logged


def bearing(a: Row, b: Row) -> float:
    """Return the bearing (degrees, left positive) of b's centre from a's heading."""
    rel = b["com"] - a["com"]
    x = np.degrees(np.arctan2(rel[2], rel[0]) - np.arctan2(a["fwd"][2], a["fwd"][0]))
    return float((x + 180.0) % 360.0 - 180.0)


def marks(rows: list[tuple[Row, Row]]) -> set[str]:
    """Return what the two fishes did before the touch: ``rock+fish`` (one avoided a rock
    or wall with the other's contact under 0.5 m), ``brake`` (one asked no forward speed
    while avoiding), ``flip`` (one's side of avoidance changed), ``toward`` (one going to
    food or a mate asked a turn of more than 1 rad to the side the other lay on),
    ``court`` (one courted), ``slow`` (one under 0.1 m/s at the touch)."""
    out = set()
    for k in (0, 1):
        sides = {r[k]["side"] for r in rows if r[k]["it"] == "avoid"}
        out |= {"flip"} if len(sides) > 1 else set()
        for r in rows:
            me, other = r[k], r[1 - k]
            avoid = me["it"] == "avoid"
            if avoid and me["hit"] and not me["only"] and me["near"] < 0.5:
                out.add("rock+fish")
            if avoid and me["ask"][0] == 0.0:
                out.add("brake")
            b, turn = bearing(me, other), me["ask"][1]
            if (
                me["it"] in ("eat", "mate")
                and abs(turn) > 1.0
                and turn * b > 0
                and 20 < abs(b) < 160
            ):
                out.add("toward")
            if me["it"] == "mate":
                out.add("court")
    if rows and min(rows[-1][0]["v"], rows[-1][1]["v"]) < 0.1:
        out.add("slow")
    return out


def line(t: float, a: Row, b: Row) -> str:
    """One brain period of the two fishes, as the module's docstring says."""
    parts = [f"{t:5.1f} d={np.linalg.norm(a['com'] - b['com']):.2f}"]
    for me, other in ((a, b), (b, a)):
        parts.append(
            f"{me['it'][:5]:5} tg={me['target']} sd={me['side']:+d} h={me['hit']}{me['only']}"
            f" nr={me['near']:.2f} v={me['v']:.2f} brg={bearing(me, other):4.0f}"
            f" ask=({me['ask'][0]:.2f},{me['ask'][1]:+.2f})"
        )
    return " | ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(24)))
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--before", type=float, default=1.5)
    args = ap.parse_args()
    log: list[list[Row | None]] = []
    recorder(log)
    counts: dict[str, int] = {}
    for seed in args.seeds:
        log.clear()
        cfg = TankConfig(seed=seed, seconds=args.seconds)
        tank = build_tank(cfg)
        names = [f.name for f in tank.fishes]
        life = live(tank)
        for t, a, e, d in life.events:
            if e != "collision" or d not in names:
                continue
            i, j = names.index(a), names.index(d)
            k = int(round(t / cfg.control_period)) - 1
            first = max(k - int(round(args.before / cfg.control_period)), 0)
            rows = [
                (r[i], r[j]) for r in log[first : k + 1] if r[i] is not None and r[j] is not None
            ]
            print(f"== seed {seed} t={t:.1f} {a} {d}")
            for m, (x, y) in enumerate(rows):
                print(line((first + m) * cfg.control_period, x, y))
            found = marks(rows)
            print("marks:", sorted(found), flush=True)
            for name in found:
                counts[name] = counts.get(name, 0) + 1
    print("counts:", dict(sorted(counts.items())))


if __name__ == "__main__":
    main()
