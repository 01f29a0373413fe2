"""Gait discovery: sort kept SANs into distinct modes of locomotion by what the body does.

Each gait is replayed and described by a few features of the rollout (``gait_features``):

- ``direction``: the sign of the centre of mass's net displacement along x (0 when it moves
  less than ``STILL_CM_S``);
- ``log2_speed``: log2 of the speed (cm/s, floored at ``STILL_CM_S``);
- ``turns``: how many whole turns the root link makes (net rotation / 2 pi, absolute):
  rolling and cartwheels; clustered as ``min(turns, ROLL_CAP)`` (1.5), so that a cartwheel
  of 2 turns and one of 5 (a faster one) are the same mode;
- ``upside``: the fraction of the time the whole body lies turned over: every link turned
  more than 90 degrees from its start angle (a chain that jumps or flips onto its back; one
  link swung over the others, the body still on its front, is not turned over);
- ``flips``: how many times the body turns over, onto its back or back onto its front
  (every link past ``FLIP_COS`` of a half turn from its last side); three (onto its back
  twice) make "repeated flips onto its back"; not clustered (``upside`` and ``turns`` are),
  only named;
- ``airborne``: the fraction of the time no link touches the ground (hopping);
- ``bounce``: the standard deviation of the centre of mass's height over the body's size
  (the sum of the link lengths): small hops against big hops;
- ``contact_<link>``: per link, the fraction of the time it touches the ground (which link
  carries the weight);
- ``periodicity``: the highest autocorrelation of the body's shape and height at a lag
  between 0.2 s and half the run (1: the motion repeats exactly, 0: no repeat).

**Distinct.** Every feature is divided by a stated scale (``SCALES``: the change one sees in
a video: a whole change of direction, a factor of 2.8 in speed, half a turn, 15% more time
in the air, a bounce of 6% of the body's size, a link down 35% more of the time, ...), and
two gaits belong to different modes when the average-linkage (``scipy.cluster.hierarchy``)
distance between their groups exceeds ``THRESHOLD`` = 2 scaled units (a change of direction
alone is 2 units, so a mode has one direction). The scales are fixed rather than taken from
the set's own spread, so that a set of near-identical gaits stays one mode and the meaning
of "distinct" does not depend on what else was found.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "SCALES",
    "THRESHOLD",
    "GaitMode",
    "cluster_features",
    "describe_gaits",
    "feature_matrix",
    "gait_features",
    "mode_label",
    "write_modes",
]

STILL_CM_S = 0.5  # slower than this, a gait has no direction
CONTACT_CLEAR = 0.003  # m: a link this close to the ground touches it
ROLL_CAP = 1.5  # turns: more turns than this is the same rolling mode
FLIPPED = 0.1  # of the time upside down (every link turned past 90 degrees): flips onto its back
FLIP_COS = 0.3  # a side counts once every link's cos(turn) is past -0.3 (back) or 0.3 (front)
REPEATED = 3  # turned over this often (onto its back, front, back): repeated flips onto its back
THRESHOLD = 2.0  # average-linkage distance (scaled units) from which modes are distinct
SCALES = {  # one unit of each feature: a difference one can see in a video
    "direction": 1.0,
    "log2_speed": 1.5,
    "turns": 0.5,
    "upside": 0.25,
    "airborne": 0.15,
    "bounce": 0.06,
    "contact": 0.35,
    "periodicity": 0.5,
}


def _com(creature, poses: np.ndarray) -> np.ndarray:
    """Return the centre of mass (R, 2) from link poses (R, L, 3)."""
    m = np.array([ln.mass for ln in creature.links])
    c = np.array([ln.centre for ln in creature.links])
    x = poses[:, :, 0] + np.cos(poses[:, :, 2]) * c
    z = poses[:, :, 1] + np.sin(poses[:, :, 2]) * c
    return np.stack([(x * m).sum(1), (z * m).sum(1)], axis=1) / m.sum()


def _clearance(creature, poses: np.ndarray, terrain: np.ndarray | None) -> np.ndarray:
    """Return each link's lowest point above the ground (R, L), m."""
    out = np.empty(poses.shape[:2])
    for k, ln in enumerate(creature.links):
        x0, z0, a = poses[:, k, 0], poses[:, k, 1], poses[:, k, 2]
        ends = (ln.centre,) if ln.shape == "sphere" else (ln.start, ln.start + ln.length)
        pts_x = np.stack([x0 + np.cos(a) * e for e in ends], axis=1)
        pts_z = np.stack([z0 + np.sin(a) * e for e in ends], axis=1)
        if terrain is not None:
            pts_z = pts_z - np.interp(pts_x, terrain[:, 0], terrain[:, 1])
        thick = ln.radius * (np.abs(np.cos(a)) if ln.shape == "box" else 1.0)
        out[:, k] = pts_z.min(axis=1) - thick
    return out


def _periodicity(signals: np.ndarray, dt: float) -> tuple[float, float]:
    """Return the best mean autocorrelation of the (R, K) signals at lags 0.2 s .. R/2, and
    that lag (s); (0, 0) when the run is too short."""
    n = len(signals)
    lo, hi = max(1, round(0.2 / dt)), n // 2
    if hi <= lo or n < 8:
        return 0.0, 0.0
    x = signals[n // 5 :] if n // 5 + 2 * hi <= n else signals  # skip the start-up
    x = x - x.mean(axis=0)
    keep = x.std(axis=0) > 1e-6
    if not keep.any():
        return 1.0, 0.0  # motionless shape: trivially periodic, and slow gaits get no credit
    x = x[:, keep] / x[:, keep].std(axis=0)
    m = len(x)
    best, lag = -1.0, 0
    for k in range(lo, min(hi, m - 2)):
        r = float(np.mean(np.sum(x[:-k] * x[k:], axis=0) / (m - k)))
        if r > best:
            best, lag = r, k
    return max(best, 0.0), lag * dt


def _flips(turned: np.ndarray) -> int:
    """Return how many times the body turned over, from each link's cos(turn) (R, L)."""
    back = (turned < -FLIP_COS).all(axis=1)
    front = (turned > FLIP_COS).all(axis=1)
    side, count = 0, 0  # 0 on its front (where it started), 1 on its back
    for b, f in zip(back, front, strict=True):
        if (side == 0 and b) or (side == 1 and f):
            side, count = 1 - side, count + 1
    return count


def gait_features(creature, rollout) -> dict:
    """Return what the body does over a recorded rollout (see the module's docstring)."""
    poses = np.asarray(rollout.poses, dtype=float)
    if len(poses) < 2:
        raise ValueError("the rollout recorded fewer than two samples")
    t = float(rollout.seconds)
    speed = 100.0 * abs(float(rollout.distance)) / t
    direction = 0 if speed < STILL_CM_S else (1 if rollout.distance > 0 else -1)
    root = np.unwrap(poses[:, 0, 2])
    turns = abs(root[-1] - root[0]) / (2 * math.pi)
    turned = np.cos(np.unwrap(poses[:, :, 2], axis=0) - poses[0, :, 2])  # (R, L)
    upside = float(np.mean((turned < 0.0).all(axis=1)))
    clear = _clearance(creature, poses, rollout.terrain)
    touching = clear <= CONTACT_CLEAR
    com = _com(creature, poses)
    ground = 0.0 if rollout.terrain is None else np.interp(com[:, 0], *rollout.terrain.T)
    height = com[:, 1] - ground
    size = creature.size
    shape = poses[:, 1:, 2] - poses[:, :1, 2]  # link angles relative to the root
    signals = np.column_stack([np.sin(shape), np.cos(shape), height / size])
    dt = float(rollout.times[1] - rollout.times[0])
    period, lag = _periodicity(signals, dt)
    return {
        "direction": direction,
        "speed_cm_s": round(speed, 2),
        "log2_speed": round(math.log2(max(speed, STILL_CM_S)), 3),
        "turns": round(float(turns), 3),
        "upside": round(upside, 3),
        "flips": _flips(turned),
        "airborne": round(float(np.mean(~touching.any(axis=1))), 3),
        "bounce": round(float(np.std(height) / size), 4),
        "contact": {
            ln.name: round(float(v), 3)
            for ln, v in zip(creature.links, touching.mean(axis=0), strict=True)
        },
        "periodicity": round(period, 3),
        "period_s": round(lag, 3),
    }


def feature_matrix(features: list[dict]) -> tuple[np.ndarray, list[str]]:
    """Return the gaits' features divided by ``SCALES`` (N, F) and the column names."""
    if not features:
        return np.zeros((0, 0)), []
    links = list(features[0]["contact"])
    names = ["direction", "log2_speed", "turns", "upside", "airborne", "bounce"]
    names += [f"contact_{n}" for n in links] + ["periodicity"]
    rows = []
    for f in features:
        row = [min(f[k], ROLL_CAP) if k == "turns" else f.get(k, 0.0) for k in names[:6]]
        row = [v / SCALES[k] for v, k in zip(row, names[:6], strict=True)]
        row += [f["contact"][n] / SCALES["contact"] for n in links]
        rows.append(row + [f["periodicity"] / SCALES["periodicity"]])
    return np.array(rows, dtype=float), names


def cluster_features(X: np.ndarray, threshold: float = THRESHOLD) -> np.ndarray:
    """Return a mode number (1, 2, ...) per row of scaled features ``X``: average-linkage
    clusters cut at ``threshold``, numbered in order of first appearance."""
    X = np.asarray(X, dtype=float)
    if len(X) == 0:
        return np.zeros(0, dtype=int)
    if len(X) == 1:
        return np.ones(1, dtype=int)
    from scipy.cluster.hierarchy import fcluster, linkage

    raw = fcluster(linkage(X, method="average"), t=threshold, criterion="distance")
    order: dict[int, int] = {}
    return np.array([order.setdefault(int(c), len(order) + 1) for c in raw], dtype=int)


def mode_label(f: dict) -> str:
    """Name a gait from its features, by what one sees: rolls, hops, walks, drags; direction."""
    arrow = {1: "+x", -1: "-x", 0: "in place"}[int(f["direction"])]
    contact = f["contact"]
    carried = [n for n, v in contact.items() if v >= 0.5]
    if f["turns"] >= 1.0:
        kind = f"cartwheels ({f['turns']:.1f} turns)"
    elif f.get("flips", 0) >= REPEATED:
        kind = "repeated flips onto its back"
    elif f.get("upside", 0.0) >= FLIPPED:
        kind = "flips onto its back"
    elif f["airborne"] >= 0.15:
        kind = "big hops" if f["airborne"] >= 0.3 else "small hops"
    elif len(carried) >= 2:
        kind = "walks on " + "+".join(carried)
    elif len(carried) == 1:
        kind = f"drags on {carried[0]}"
    else:
        kind = "shuffles"
    return f"{kind}, {arrow}"


@dataclass(frozen=True)
class GaitMode:
    """One distinct mode: its label, its members (indices into the gaits) and the fastest."""

    number: int
    label: str
    members: list[int]
    best: int


def describe_gaits(features: list[dict], threshold: float = THRESHOLD) -> list[GaitMode]:
    """Cluster gaits (their ``gait_features``) into modes, the fastest mode first."""
    X, _ = feature_matrix(features)
    labels = cluster_features(X, threshold)
    modes = []
    for c in sorted(set(labels.tolist())):
        members = [i for i, k in enumerate(labels) if k == c]
        best = max(members, key=lambda i: features[i]["speed_cm_s"])
        modes.append((features[best]["speed_cm_s"], members, best))
    modes.sort(key=lambda m: -m[0])
    return [GaitMode(k, mode_label(features[b]), m, b) for k, (_, m, b) in enumerate(modes, 1)]


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9+-]+", "-", text.lower()).strip("-")[:48]


def mode_caption(entry: dict, n_modes: int) -> str:
    """Return the text shown beside a mode's clip: its label and its best gait's features."""
    f = entry["best"]
    lines = [f"mode {entry['mode']} of {n_modes}", entry["label"], f"{entry['count']} network(s)"]
    lines += [f"{f['speed_cm_s']:.1f} cm/s", f"turns {f['turns']:.2f}"]
    lines += [f"airborne {100 * f['airborne']:.0f}%", f"period {f['period_s']:.2f} s"]
    lines += [f"turned over {f.get('flips', 0)} times"]
    lines += [f"periodicity {f['periodicity']:.2f}"]
    lines += [f"{n} down {100 * v:.0f}%" for n, v in f["contact"].items()]
    return "\n".join(lines)


def write_modes(
    creature,
    networks: list,
    info: list[dict],
    out,
    seconds: float | None = None,
    terrain: str = "flat",
    seed: int = 0,
    threshold: float = THRESHOLD,
    video: bool = True,
) -> dict:
    """Replay ``networks`` (with ``info`` per network: rank, trial, ...), cluster their gaits,
    write ``out``/modes.json and return it. With ``video`` each mode names its clip
    (modes/NN-label.mp4), drawn by ``zoetic.viz.san.draw_modes``."""
    from zoetic.io import write_json
    from zoetic.san.show import replay

    out = Path(out)
    features = []
    for net in networks:
        ro = replay(net, creature, seconds, terrain, seed, fps=50)
        features.append(gait_features(net.tuned_creature(creature), ro))
    modes = describe_gaits(features, threshold)
    X, names = feature_matrix(features)
    doc_modes = []
    for m in modes:
        entry = {"mode": m.number, "label": m.label, "count": len(m.members)}
        entry["best"] = {**info[m.best], **features[m.best]}
        entry["members"] = [{**info[i], **features[i]} for i in m.members]
        entry["network"] = m.best  # its index in ``networks``
        if video:
            entry["clip"] = str(out / "modes" / f"{m.number:02d}-{_slug(m.label)}.mp4")
        doc_modes.append(entry)
    doc = {
        "creature": creature.name,
        "gaits": len(networks),
        "modes_found": len(modes),
        "kinds": sorted({m.label.split(",")[0].split(" (")[0] for m in modes}),
        "threshold": threshold,
        "linkage": "average",
        "scales": SCALES,
        "features": names,
        "scaled": np.round(X, 3).tolist(),
        "modes": doc_modes,
    }
    write_json(out / "modes.json", doc)
    return doc
