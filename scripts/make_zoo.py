"""Regenerate the built-in zoo's animal files (src/zoetic/bodies/zoo/*.toml).

The files are the source of truth that zoetic reads; this script only saves typing the
lattices by hand and records how they were built. Run: python scripts/make_zoo.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import tomli_w

ZOO = Path(__file__).resolve().parents[1] / "src" / "zoetic" / "bodies" / "zoo"


class Lattice:
    """A growing spring-mass animal description."""

    def __init__(self) -> None:
        self.nodes: list[dict] = []
        self.springs: list[dict] = []
        self.faces: list[list[int]] = []
        self._pairs: set[tuple[int, int]] = set()

    def node(self, name: str, pos, mass: float) -> int:
        self.nodes.append({"name": name, "pos": [round(float(p), 6) for p in pos], "mass": mass})
        return len(self.nodes) - 1

    def spring(self, a: int, b: int, stiffness: float, kind: str, **extra) -> None:
        key = (min(a, b), max(a, b))
        if key in self._pairs or a == b:
            return
        self._pairs.add(key)
        entry = {"nodes": [self.nodes[a]["name"], self.nodes[b]["name"]]}
        entry.update(stiffness=round(stiffness, 4), kind=kind, **extra)
        self.springs.append(entry)

    def face(self, ids, centre) -> None:
        """Add a face, wound so that its normal points away from ``centre``."""
        p = np.array([self.nodes[i]["pos"] for i in ids])
        n = np.cross(p[1] - p[0], p[2] - p[0])
        if np.dot(n, p.mean(axis=0) - np.asarray(centre)) < 0:
            ids = list(reversed(ids))
        self.faces.append([self.nodes[i]["name"] for i in ids])

    def pos(self) -> np.ndarray:
        return np.array([n["pos"] for n in self.nodes])

    def omega_max(self) -> float:
        """Highest natural frequency (rad/s) of the springs at rest, from M^-1 K."""
        idx = {n["name"]: k for k, n in enumerate(self.nodes)}
        x = self.pos()
        n = len(x)
        K = np.zeros((3 * n, 3 * n))
        for s in self.springs:
            a, b = (idx[v] for v in s["nodes"])
            d = x[b] - x[a]
            u = d / np.linalg.norm(d)
            k = s["stiffness"] * np.outer(u, u)
            for i, j, sgn in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                K[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += sgn * k
        m = np.repeat([nd["mass"] for nd in self.nodes], 3)
        w2 = np.linalg.eigvals(K / np.sqrt(m)[:, None] / np.sqrt(m)[None, :]).real
        return float(np.sqrt(max(w2.max(), 0.0)))

    def damp_springs(self, zeta: float) -> None:
        """Give each spring damping zeta * (lighter end's mass): explicit-step safe."""
        mass = {n["name"]: n["mass"] for n in self.nodes}
        for s in self.springs:
            s["damping"] = round(zeta * min(mass[v] for v in s["nodes"]), 5)

    def doc(self, **top) -> dict:
        out = dict(top)
        out["nodes"] = self.nodes
        out["springs"] = self.springs
        out["faces"] = [{"nodes": f} for f in self.faces]
        return out


# ----------------------------------------------------------------------------- fish lattice
FISH_L = 0.04  # metres per MODEL-FACTS length unit: a 1.04 m shark
FISH_M = 0.1  # kilograms per MODEL-FACTS mass unit: 11.7 kg in all
# (x, half-size, mass units) of the 5 rings. MODEL-FACTS gives 6.6, 11, 6.6, 1.1, 1.1: we move
# 2 units from the middle ring to each tail ring (3.3): a real shark's caudal peduncle is
# muscle, and the light tail nodes set the lattice's highest frequency, so heavier ones let
# the whole body be 3x stiffer (3x the muscle force) at the same 5 ms step.
FISH_RINGS = [(-5, 2.0, 6.6), (-10, 3.0, 9.0), (-15, 2.0, 6.6), (-20, 1.0, 3.3), (-22, 0.8, 3.3)]
FISH_TIP_MASS = 0.5  # mass units of each caudal fin tip (MODEL-FACTS 0.165; 3x, as the springs)
FISH_K = {"cross": 3900.0, "muscle": 3000.0, "structural": 3300.0, "fin": 2250.0}
FISH_WAVE_LAG = 0.1  # cycles of phase between successive segments of the built-in wave
FISH_WAVE_HZ = 5.0  # the built-in wave's (and the learned gait's base) stroke frequency
# the eyes the fish see with (zoetic.perception): on the nose, 8 cm behind it and 6 cm to each
# side; 4 levels of 64 x 64 pixels, 120 degrees wide down to the 15-degree fovea
FISH_EYES = {"node": "nose", "offset": [-0.08, 0.0, 0.06], "fov": 120.0, "levels": 4, "pixels": 64}


def fish_lattice(
    rotate_on_side: bool,
    ring_masses: list[float] | None = None,
    tip_mass: float = FISH_TIP_MASS,
    stiff: dict[str, float] | None = None,
) -> tuple[Lattice, list[list[int]]]:
    """The 23-node, 91-spring fish of MODEL-FACTS; returns the lattice and its 5 rings.

    ``ring_masses`` (mass units per node of each ring), ``tip_mass`` and ``stiff`` (N/m per spring
    kind) default to today's fish (FISH_RINGS, FISH_TIP_MASS, FISH_K)."""
    lat = Lattice()
    stiff = stiff or FISH_K
    masses = ring_masses or [r[2] for r in FISH_RINGS]
    rings_xhm = [(x, h, m) for (x, h, _), m in zip(FISH_RINGS, masses, strict=True)]

    def place(x, y, z):
        p = np.array([x, y, z]) * FISH_L
        if rotate_on_side:  # left (z > 0) becomes up (y > 0): the tail flaps up and down
            p = np.array([p[0], p[2], -p[1]])
        return p

    nose = lat.node("nose", place(0, 0, 0), 1.1 * FISH_M)
    rings = []
    pattern = [(1, 1), (1, -1), (-1, -1), (-1, 1)]  # (y, z) signs
    for r, (x, h, m) in enumerate(rings_xhm):
        rings.append(
            [
                lat.node(f"r{r + 1}_{k}", place(x, h * sy, h * sz), m * FISH_M)
                for k, (sy, sz) in enumerate(pattern)
            ]
        )
    tips = [
        lat.node("tail_top", place(-26, 3, 0), tip_mass * FISH_M),
        lat.node("tail_bottom", place(-26, -3, 0), tip_mass * FISH_M),
    ]
    for i in rings[0]:
        lat.spring(nose, i, stiff["structural"], "structural")
    for ring in rings:
        for k in range(4):
            lat.spring(ring[k], ring[(k + 1) % 4], stiff["structural"], "structural")
        lat.spring(ring[0], ring[2], stiff["cross"], "cross")
        lat.spring(ring[1], ring[3], stiff["cross"], "cross")
    segments = {0: "front", 1: "middle", 2: "back"}
    for r in range(4):
        for k in range(4):
            a, b = rings[r][k], rings[r + 1][k]
            if r in segments:
                left = pattern[k][1] > 0
                side = "left" if left else "right"
                act = f"{segments[r]}_{side}"
                lat.spring(
                    a,
                    b,
                    stiff["muscle"],
                    "muscle",
                    actuator=act,
                    max_shortening=0.1 if r == 2 else 0.2,
                )
            else:
                lat.spring(a, b, stiff["structural"], "structural")
        for k in range(4):
            for nb in ((k + 1) % 4, (k + 3) % 4):
                lat.spring(rings[r][k], rings[r + 1][nb], stiff["cross"], "cross")
    for t in tips:
        for i in rings[4]:
            lat.spring(i, t, stiff["fin"], "fin")
    lat.spring(tips[0], tips[1], stiff["fin"], "fin")
    assert len(lat.springs) == 91, len(lat.springs)
    # faces: nose triangles, quads between rings, the caudal fin
    x = lat.pos()
    centre = lambda ids: np.array([x[ids].mean(axis=0)[0], 0, 0])  # noqa: E731
    for k in range(4):
        ids = [nose, rings[0][k], rings[0][(k + 1) % 4]]
        lat.face(ids, centre(rings[0]) + np.array([FISH_L * 5, 0, 0]))
    for r in range(4):
        for k in range(4):
            ids = [rings[r][k], rings[r][(k + 1) % 4], rings[r + 1][(k + 1) % 4], rings[r + 1][k]]
            lat.face(ids, centre(ids))
    last = rings[4]
    tail_quads = [[last[0], last[3], tips[1], tips[0]], [last[1], last[2], tips[1], tips[0]]]
    for q in tail_quads:
        lat.face(q, centre(q) * np.array([1, 0, 0]) + x[last].mean(axis=0) * [0, 1, 1])
    lat.face([last[0], last[1], tips[0]], x[last].mean(axis=0))
    lat.face([last[2], last[3], tips[1]], x[last].mean(axis=0))
    return lat, rings


def fish_actuators(sides: dict[str, str] | None = None) -> list[dict]:
    out = []
    for seg in ("front", "middle", "back"):
        for side, other in (("left", "right"), ("right", "left")):
            out.append(
                {
                    "name": f"{seg}_{side}",
                    "kind": "muscle",
                    "side": (sides or {}).get(side, side),
                    "mirror": f"{seg}_{other}",
                }
            )
    return out


SHARK_FIN_AREA = 0.015  # m^2 per pectoral fin: about 15 cm x 10 cm on a 1 m leopard shark


def shark_fins(lat: Lattice, rings: list[list[int]]) -> tuple[list[dict], list[dict]]:
    """Two pectoral fins on the sides of the first ring (the dolphin's, on an upright fish).

    Each fin's forward axis runs along its own side (ring 1 to ring 3, parallel to the body
    axis), so the two are mirror images; the span axis (right to left) is shared.
    """
    names = [n["name"] for n in lat.nodes]
    r1, r3 = rings[0], rings[2]
    # ring corners k = 0..3 are (y, z) signs (+,+), (+,-), (-,-), (-,+): left is k = 0, 3
    sides = {"left": ([r1[0], r1[3]], [r1[0], r3[0]]), "right": ([r1[1], r1[2]], [r1[1], r3[1]])}
    acts, fins = [], []
    for side, other in (("left", "right"), ("right", "left")):
        nodes, fwd = sides[side]
        acts.append({"name": f"fin_{side}", "kind": "fin", "side": side, "mirror": f"fin_{other}"})
        fins.append(
            {
                "name": f"pectoral_{side}",
                "actuator": f"fin_{side}",
                "nodes": [names[i] for i in nodes],
                "forward": [names[i] for i in fwd],
                "span": [names[r1[0]], names[r1[1]]],
                "area": SHARK_FIN_AREA,
                "angle_range": [-0.5, 0.5],
            }
        )
    return acts, fins


def fish_doc(lat: Lattice, wave_hz: float, wave_lag: float, **top) -> dict:
    """Return the animal document of a fish lattice swimming in water, nose first along +x:
    its built-in wave travels ``wave_lag`` cycles per segment tailward, left and right in
    antiphase; ``top`` gives the rest (name, description, dt, defaults, actuators, fins)."""
    phases = {}
    for i, seg in enumerate(("front", "middle", "back")):
        phases[f"{seg}_left"] = round(wave_lag * i, 3)
        phases[f"{seg}_right"] = round(wave_lag * i + 0.5, 3)
    return lat.doc(
        medium="water",
        head="nose",
        forward=[1.0, 0.0, 0.0],
        wave={"frequency": wave_hz, "amplitude": 1.0, "offset": 0.0, "phases": phases},
        eyes=FISH_EYES,
        **top,
    )


def shark() -> dict:
    lat, rings = fish_lattice(rotate_on_side=False)
    fin_acts, fins = shark_fins(lat, rings)
    lat.damp_springs(10.0)
    print(f"shark   omega_max = {lat.omega_max():7.1f} rad/s")
    return fish_doc(
        lat,
        FISH_WAVE_HZ,
        FISH_WAVE_LAG,
        name="shark",
        description=(
            "Leopard shark: the 23-node, 91-spring fish lattice; 12 muscles, 6 muscle "
            "actuators and two pectoral fins."
        ),
        dt=0.005,
        defaults={"node_damping": 0.05, "spring_damping": 0.0},
        actuators=fish_actuators() + fin_acts,
        fins=fins,
    )


# The shark of the 1995 paper (docs/animals.md, "The papers' animals"): the MODEL-FACTS fish
# as it stands, in the same length and mass units as today's fish (0.04 m, 0.1 kg) and a time
# unit of our choosing (T = 0.0522 s, so that its "other springs" are the first zoo fish's
# 1100 N/m): stiffness 38/28/30 units (cross, muscle, other; the caudal fin's springs are
# "other"), spring damping 0.1 and nodal damping 0.05 units, masses 1.1/6.6/11/6.6/1.1/1.1 and
# tips 0.165. Six muscle actuators and no pectoral fins (the paper's Fig. 10).
FISH_1995_T = float(np.sqrt(FISH_M * 30.0 / 1100.0))  # s per time unit
FISH_1995_K_UNIT = FISH_M / FISH_1995_T**2  # N/m per stiffness unit
FISH_1995_C_UNIT = FISH_M / FISH_1995_T  # N s/m per damping unit
SHARK_1995 = {
    "rings": [6.6, 11.0, 6.6, 1.1, 1.1],
    "tip_mass": 0.165,
    "k": {"cross": 38.0, "muscle": 28.0, "structural": 30.0, "fin": 30.0},
    "spring_damping": 0.1,
    "node_damping": 0.05,
    "wave_hz": 5.0,
    "wave_lag": 0.1,
    "dt": 0.005,
}


def shark_1995(**over) -> dict:
    par = {**SHARK_1995, **over}
    stiff = {kind: units * FISH_1995_K_UNIT for kind, units in par["k"].items()}
    lat, _ = fish_lattice(False, par["rings"], par["tip_mass"], stiff)
    c = round(par["spring_damping"] * FISH_1995_C_UNIT, 5)
    for s in lat.springs:
        s["damping"] = c
    print(f"shark-1995 omega_max = {lat.omega_max():7.1f} rad/s")
    return fish_doc(
        lat,
        par["wave_hz"],
        par["wave_lag"],
        name="shark-1995",
        description=(
            "The 1995 paper's leopard shark: the 23-node, 91-spring fish with the constants of "
            "its references (MODEL-FACTS), 6 muscle actuators, no pectoral fins."
        ),
        dt=par["dt"],
        defaults={
            "node_damping": round(par["node_damping"] * FISH_1995_C_UNIT, 5),
            "spring_damping": 0.0,
        },
        actuators=fish_actuators(),
    )


def dolphin_1995(**over) -> dict:
    """The 1995 paper's dolphin: "the shark spring-mass system turned on its side" with
    pectoral fins, so shark-1995's constants at its size (no scaling, no drag coefficients);
    the fins' size is not given: today's dolphin's 0.02 m^2 before its scaling."""
    par = {**SHARK_1995, **over}
    return dolphin(
        rings=par["rings"],
        tip_mass=par["tip_mass"],
        k={kind: units * FISH_1995_K_UNIT for kind, units in par["k"].items()},
        spring_damping=round(par["spring_damping"] * FISH_1995_C_UNIT, 5),
        node_damping=round(par["node_damping"] * FISH_1995_C_UNIT, 5),
        drag={g: 1.0 for g in DOLPHIN["drag"]},
        wave_hz=par["wave_hz"],
        dt=par["dt"],
        scale=1.0,
        name="dolphin-1995",
        description=(
            "The 1995 paper's dolphin: shark-1995 turned on its side (muscles flap the tail "
            "up and down) with two pectoral fins; lives below a free surface."
        ),
    )


# The dolphin (issue 10): the fish lattice on its side, re-massed, re-strengthened and with a
# drag coefficient per face group (docs/animals.md, "The dolphin"): mass units of each ring and
# of each fluke tip; a factor on each spring kind's stiffness; the face law's coefficient
# (a factor on the medium's) per group of faces; the built-in stroke frequency.
DOLPHIN = {
    "rings": [6.6, 9.0, 6.6, 3.3, 3.3],
    "tip_mass": 1.5,
    "k_scale": {"cross": 3.0, "muscle": 3.0, "structural": 3.0, "fin": 9.0},
    "drag": {"head": 0.12, "trunk": 1.0, "peduncle": 0.3, "flukes": 2.0, "edges": 0.12},
    "wave_hz": 4.0,
    "dt": 0.0025,
    "scale": 1.635,
    "dorsal": None,  # no dorsal fin (DORSAL_FIN below was tried: it did not fix the drift)
    "k": None,  # N/m per spring kind before scaling (None: FISH_K x k_scale)
    "spring_damping": None,  # N s/m for every spring (None: 10 s^-1 x the lighter end's mass)
    "node_damping": 0.05,  # N s/m
    "fin_area": 0.02,  # m^2 per pectoral fin before scaling
    "name": "dolphin",
    "description": (
        "Heaviside's dolphin (1.70 m, 52 kg): the fish lattice scaled up and turned on its "
        "side (muscles flap the tail up and down), streamlined head, hydrofoil flukes and "
        "two pectoral fins; lives below a free surface and flies above it."
    ),
}


# A dorsal fin, tried and not adopted (docs/animals.md, "The dorsal fin (tried, not kept)"):
# build it with dolphin(dorsal=DORSAL_FIN), as experiments/dolphin_yaw.py does. A thin
# triangular plate on the back's midline from ring 2 back to ring 3, its tip swept back;
# positions (x, height) in fish length units before scaling; mass (kg, taken off ring 2);
# its springs' stiffness (N/m, after scaling); the plate's face coefficient.
DORSAL_FIN = {
    "front": (-10.0, 3.0),  # on the back at ring 2 (0.65 m behind the nose, 38 % of L)
    "back": (-15.0, 2.0),  # on the back at ring 3 (0.98 m, 58 % of L)
    "tip": (-14.2, 5.4),  # 0.93 m back, 0.21 m above the back: 0.035 m^2 per side
    "mass": 0.6,  # kg: 0.035 m^2 x 1.7 cm mean thickness x 1000 kg/m^3
    "k": 20000.0,  # N/m: omega_max stays at the body's 847 rad/s (30000 and 0.8 kg: 888)
    "drag": 2.5,  # lift slope of a wing of aspect ratio 1.3: 2 pi AR / (AR + 2) per rad
}


def dorsal_fin(lat: Lattice, rings: list[list[int]], par: dict, sc: float) -> None:
    """Add the dolphin's dorsal fin: two nodes on the back's midline (at rings 2 and 3) and a
    tip above them, each held by stiff springs to the top and bottom nodes of rings 2 and 3,
    and the plate as two one-sided triangles (one facing each side, so that sideways motion
    either way meets it; the face law only pushes on a face moving outward)."""
    fin = par["dorsal"]
    m = fin["mass"] / 3
    for i in rings[1]:  # the fin's mass comes off ring 2: the total stays the same
        lat.nodes[i]["mass"] = round(lat.nodes[i]["mass"] - fin["mass"] / 4, 6)
    ids = []
    for name in ("front", "back", "tip"):
        x, y = fin[name][0] * FISH_L * sc, fin[name][1] * FISH_L * sc
        ids.append(lat.node(f"dorsal_{name}", [x, y, 0.0], m))
    for a in ids:  # each to all 8 nodes of rings 2 and 3: held in every direction
        for b in rings[1] + rings[2]:
            lat.spring(a, b, fin["k"], "fin")
    for a, b in ((0, 1), (0, 2), (1, 2)):
        lat.spring(ids[a], ids[b], fin["k"], "fin")
    names = [lat.nodes[i]["name"] for i in ids]
    lat.faces.append(names)
    lat.faces.append(list(reversed(names)))


def dolphin(**params) -> dict:
    par = {**DOLPHIN, **params}
    lat, rings = fish_lattice(rotate_on_side=True)
    for ring, units in zip(rings, par["rings"], strict=True):
        for i in ring:
            lat.nodes[i]["mass"] = round(units * FISH_M, 6)
    for nd in lat.nodes[-2:]:
        nd["mass"] = round(par["tip_mass"] * FISH_M, 6)
    sc = par["scale"]  # geometric similarity: lengths x sc, masses and stiffnesses x sc^3
    for nd in lat.nodes:
        nd["pos"] = [round(p * sc, 6) for p in nd["pos"]]
        nd["mass"] = round(nd["mass"] * sc**3, 6)
    for s in lat.springs:
        k = par["k"][s["kind"]] if par["k"] else s["stiffness"] * par["k_scale"][s["kind"]]
        s["stiffness"] = round(k * sc**3, 4)
    if par["dorsal"]:
        dorsal_fin(lat, rings, par, sc)
    doc_acts = []
    for seg in ("front", "middle", "back"):  # left muscles now lie on the back (dorsal)
        doc_acts.append({"name": f"{seg}_dorsal", "kind": "muscle", "side": "center"})
        doc_acts.append({"name": f"{seg}_ventral", "kind": "muscle", "side": "center"})
    for s in lat.springs:
        if "actuator" in s:
            s["actuator"] = s["actuator"].replace("_left", "_dorsal").replace("_right", "_ventral")
    x = lat.pos()
    r1 = rings[0]
    left = [i for i in r1 if x[i][2] > 0]
    right = [i for i in r1 if x[i][2] < 0]
    names = [n["name"] for n in lat.nodes]
    tail_of = [rings[4][0], rings[4][2]]
    fins = []
    for side, ids, other in (("left", left, "right"), ("right", right, "left")):
        doc_acts.append(
            {"name": f"fin_{side}", "kind": "fin", "side": side, "mirror": f"fin_{other}"}
        )
        # the body's right-to-left axis (x[0] - x[1]), level, and the same for both fins
        span = [max(left, key=lambda i: x[i][1]), max(right, key=lambda i: x[i][1])]
        fins.append(
            {
                "name": f"pectoral_{side}",
                "actuator": f"fin_{side}",
                "nodes": [names[i] for i in ids],
                "forward": ["nose", names[tail_of[0]]],
                "span": [names[span[0]], names[span[1]]],
                "area": round(par["fin_area"] * sc**2, 6),
                "angle_range": [-0.5, 0.5],
            }
        )
    phases = {}
    for i, seg in enumerate(("front", "middle", "back")):
        phases[f"{seg}_dorsal"] = round(FISH_WAVE_LAG * i, 3)
        phases[f"{seg}_ventral"] = round(FISH_WAVE_LAG * i + 0.5, 3)
    lat.damp_springs(10.0)
    if par["spring_damping"] is not None:
        for s in lat.springs:
            s["damping"] = par["spring_damping"]
    print(f"{par['name']} omega_max = {lat.omega_max():7.1f} rad/s")
    doc = lat.doc(
        name=par["name"],
        description=par["description"],
        medium="sea",
        dt=par["dt"],
        start_offset=[0.0, -1.0, 0.0],
        head="nose",
        forward=[1.0, 0.0, 0.0],
        defaults={"node_damping": par["node_damping"], "spring_damping": 0.0},
        actuators=doc_acts,
        fins=fins,
        wave={"frequency": par["wave_hz"], "amplitude": 1.0, "offset": 0.0, "phases": phases},
        eyes=FISH_EYES,
    )
    # faces in fish_lattice's order: 4 nose triangles and 4 quads ring 1 -> 2 face forward
    # (the head), 4 quads ring 2 -> 3 (the trunk) and 8 quads ring 3 -> 5 (the tail stock)
    # face backward: they meet the water only moving sideways; then the flukes' two sides and
    # their two leading edges (the triangles from the tail stock out to the fluke tips)
    groups = ["head"] * 8 + ["trunk"] * 4 + ["peduncle"] * 8 + ["flukes"] * 2 + ["edges"] * 2
    groups += ["dorsal"] * (2 if par["dorsal"] else 0)  # the dorsal fin's two sides
    assert len(groups) == len(doc["faces"])
    for face, group in zip(doc["faces"], groups, strict=True):
        coef = par["dorsal"]["drag"] if group == "dorsal" else par["drag"][group]
        if coef != 1.0:
            face["drag"] = coef
    return doc


# ----------------------------------------------------------------------------- snake
def snake() -> dict:
    seg_len, half_w, height, total_mass = 0.1, 0.02, 0.04, 0.5
    n_rings = 11
    n_nodes = 4 * n_rings + 1
    m = total_mass / n_nodes
    k_struct, k_cross, k_muscle = 130.0, 130.0, 75.0
    lat = Lattice()
    nose = lat.node("nose", [0.05, height / 2, 0.0], m)
    rings = []
    pattern = [(height, half_w), (height, -half_w), (0.0, -half_w), (0.0, half_w)]
    for r in range(n_rings):
        x = -r * seg_len
        rings.append([lat.node(f"r{r}_{k}", [x, y, z], m) for k, (y, z) in enumerate(pattern)])
    for i in rings[0]:
        lat.spring(nose, i, k_struct, "structural")
    for ring in rings:
        for k in range(4):
            lat.spring(ring[k], ring[(k + 1) % 4], k_struct, "structural")
        lat.spring(ring[0], ring[2], k_cross, "cross")
        lat.spring(ring[1], ring[3], k_cross, "cross")
    acts = []
    for r in range(n_rings - 1):
        for side, other in (("left", "right"), ("right", "left")):
            acts.append(
                {
                    "name": f"seg{r}_{side}",
                    "kind": "muscle",
                    "side": side,
                    "mirror": f"seg{r}_{other}",
                }
            )
        for k in range(4):
            side = "left" if k in (0, 3) else "right"
            lat.spring(
                rings[r][k],
                rings[r + 1][k],
                k_muscle,
                "muscle",
                actuator=f"seg{r}_{side}",
                max_shortening=0.3,
            )
        for k in range(4):
            for nb in ((k + 1) % 4, (k + 3) % 4):
                lat.spring(rings[r][k], rings[r + 1][nb], k_cross, "cross")
    x = lat.pos()
    for k in range(4):
        lat.face(
            [nose, rings[0][k], rings[0][(k + 1) % 4]], x[rings[0]].mean(axis=0) - [0.05, 0, 0]
        )
    for r in range(n_rings - 1):
        for k in range(4):
            ids = [rings[r][k], rings[r][(k + 1) % 4], rings[r + 1][(k + 1) % 4], rings[r + 1][k]]
            lat.face(ids, x[rings[r] + rings[r + 1]].mean(axis=0))
    lat.face(rings[-1], x[rings[-2]].mean(axis=0))
    phases = {}
    for r in range(n_rings - 1):
        phases[f"seg{r}_left"] = round(0.15 * r, 4)
        phases[f"seg{r}_right"] = round(0.15 * r + 0.5, 4)
    lat.damp_springs(10.0)
    print(f"snake   omega_max = {lat.omega_max():7.1f} rad/s")
    return lat.doc(
        name="snake",
        description=(
            "Coral snake: 10 segments of 4 longitudinal muscles (a pair each side, one "
            "actuator per pair): 40 muscles, 20 actuators; crawls by directional friction."
        ),
        medium="ground",
        dt=0.005,
        head="nose",
        forward=[1.0, 0.0, 0.0],
        defaults={"node_damping": 0.002, "spring_damping": 0.0},
        actuators=acts,
        wave={"frequency": 3.0, "amplitude": 1.0, "offset": 0.0, "phases": phases},
    )


# ----------------------------------------------------------------------------- ray
# The ray's numbers (docs/animals.md, "Strength of the ray", gives each one's reason and the
# measurements behind it); ray(**changes) builds a variant, as experiments/ray_strength.py does.
RAY = {
    "k_s": 250.0,  # N/m, structural and cross springs
    "k_m": 800.0,  # N/m, muscles
    "k_body": None,  # per-group passive stiffness (None: k_s): body box, nose, tail
    "k_root": None,  # the wing root's cross springs (box node to mid-wing)
    "k_thick": 500.0,  # the wing's thickness at mid-span (upper to lower mid-wing node)
    "k_wing": None,  # the rest of the wing
    "rear": 0.5,  # stiffness factor of the passive springs of the wings' rear half
    "rear_groups": ("wing",),  # the groups the rear factor applies to
    "mass": 1.5,  # kg in all
    "wing_mass": None,  # fraction of the mass in the 24 wing nodes (None: even)
    "tip_share": 1.0,  # a wing tip node's mass relative to a mid-wing node's
    "node_damping": 0.005,  # N s/m per node: skin friction, which the face law lacks
    "zeta": 10.0,  # spring damping per kg of the lighter end (s^-1)
    "thick": 0.025,  # half-thickness of the body box (m)
    "mid_thick": 0.012,  # half-thickness of the wing at mid-span (m)
    "frequency": 2.0,  # the built-in flap (Hz)
    "lag": 0.5,  # cycles between the elevators and the depressors of the built-in flap
    "dt": 0.005,
}


def ray(**over) -> dict:
    par = {**RAY, **over}
    xs = [-0.08, -0.16, -0.24, -0.32]
    spans = [0.16, 0.26, 0.26, 0.16]
    body_half, thick, mid_thick = 0.04, par["thick"], par["mid_thick"]
    k_s, k_m = par["k_s"], par["k_m"]
    lat = Lattice()
    names = ["tipR", "midTR", "TR", "TL", "midTL", "tipL"]
    rows_top, rows_bot, stations = [], [], []
    n_nodes = 2 + 10 * len(xs)
    m = par["mass"] / n_nodes
    if par["wing_mass"] is not None:
        mw = par["mass"] * par["wing_mass"]
        m = (par["mass"] - mw) / 18
        m_mid = mw / (16 + 8 * par["tip_share"])
        m_tip = m_mid * par["tip_share"]
    else:
        m_mid = m_tip = m
    nose = lat.node("nose", [0.0, 0.0, 0.0], m)
    for k, (x, s) in enumerate(zip(xs, spans, strict=True)):
        st = {
            "TL": lat.node(f"s{k}_TL", [x, thick, body_half], m),
            "TR": lat.node(f"s{k}_TR", [x, thick, -body_half], m),
            "BL": lat.node(f"s{k}_BL", [x, -thick, body_half], m),
            "BR": lat.node(f"s{k}_BR", [x, -thick, -body_half], m),
            "midTL": lat.node(f"s{k}_midTL", [x, mid_thick, s / 2], m_mid),
            "midTR": lat.node(f"s{k}_midTR", [x, mid_thick, -s / 2], m_mid),
            "midBL": lat.node(f"s{k}_midBL", [x, -mid_thick, s / 2], m_mid),
            "midBR": lat.node(f"s{k}_midBR", [x, -mid_thick, -s / 2], m_mid),
            "tipL": lat.node(f"s{k}_tipL", [x, 0.0, s], m_tip),
            "tipR": lat.node(f"s{k}_tipR", [x, 0.0, -s], m_tip),
        }
        stations.append(st)
        rows_top.append([st[n] for n in names])
        rows_bot.append(
            [st[n.replace("T", "B") if n.startswith(("T", "midT")) else n] for n in names]
        )
    tail = lat.node("tail", [-0.45, 0.0, 0.0], m)
    acts = []
    for side, other in (("left", "right"), ("right", "left")):
        for role in ("elevator", "depressor"):
            acts.append(
                {
                    "name": f"{role}_{side}",
                    "kind": "muscle",
                    "side": side,
                    "mirror": f"{role}_{other}",
                }
            )
    for st in stations:
        box = [st["TL"], st["TR"], st["BR"], st["BL"]]
        for k in range(4):
            lat.spring(box[k], box[(k + 1) % 4], k_s, "structural")
        lat.spring(box[0], box[2], k_s, "cross")
        lat.spring(box[1], box[3], k_s, "cross")
        for S, side in (("L", "left"), ("R", "right")):
            T, B, mT, mB, tip = (
                st["T" + S],
                st["B" + S],
                st["midT" + S],
                st["midB" + S],
                st["tip" + S],
            )
            lat.spring(T, mT, k_m, "muscle", actuator=f"elevator_{side}", max_shortening=0.2)
            lat.spring(B, mB, k_m, "muscle", actuator=f"depressor_{side}", max_shortening=0.2)
            lat.spring(mT, mB, k_s, "structural")
            lat.spring(T, mB, k_s, "cross")
            lat.spring(B, mT, k_s, "cross")
            lat.spring(mT, tip, k_s, "structural")
            lat.spring(mB, tip, k_s, "structural")
    for k in range(len(xs) - 1):
        for row in (rows_top, rows_bot):
            a, b = row[k], row[k + 1]
            for p in range(6):
                lat.spring(a[p], b[p], k_s, "structural")
                for q in (p - 1, p + 1):
                    if 0 <= q < 6:
                        lat.spring(a[p], b[q], k_s, "cross")
        for p in range(1, 5):
            lat.spring(rows_top[k][p], rows_bot[k + 1][p], k_s, "cross")
            lat.spring(rows_bot[k][p], rows_top[k + 1][p], k_s, "cross")
    for p in range(6):
        lat.spring(nose, rows_top[0][p], k_s, "structural")
        lat.spring(nose, rows_bot[0][p], k_s, "structural")
    for n in ("TL", "TR", "BL", "BR"):
        lat.spring(tail, stations[-1][n], k_s, "structural")

    # passive stiffness by group
    def group(a: str, b: str) -> str:
        wing = [("mid" in v or "tip" in v) for v in (a, b)]
        if not any(wing):
            return "body"
        if all("mid" in v for v in (a, b)) and a[:2] == b[:2]:
            return "thick"
        if not all(wing) and a[:2] == b[:2] and "tip" not in a + b:
            return "root"
        return "wing"

    for s in lat.springs:
        if "actuator" not in s:
            k = par["k_" + group(*s["nodes"])]
            if k is not None:
                s["stiffness"] = round(k, 4)
    # the rear half of each wing is softer, so a flapping wing twists and pushes water back
    wing_rear = {
        lat.nodes[i]["name"]
        for st in stations[2:]
        for key, i in st.items()
        if key.startswith(("mid", "tip"))
    }
    for s in lat.springs:
        if "actuator" not in s and any(v in wing_rear for v in s["nodes"]):
            if all(v in wing_rear or v.startswith(("s2_", "s3_")) for v in s["nodes"]):
                if group(*s["nodes"]) in par["rear_groups"]:
                    s["stiffness"] = round(s["stiffness"] * par["rear"], 4)
    # faces: top (normal up) and bottom (normal down) sheets, nose and tail fans
    up, down = np.array([0, -1.0, 0]), np.array([0, 1.0, 0])
    x = lat.pos()

    def sheet_face(ids, top: bool):
        c = x[ids].mean(axis=0) + (up if top else down)
        lat.face(ids, c)

    for k in range(len(xs) - 1):
        for row, top in ((rows_top, True), (rows_bot, False)):
            for p in range(5):
                sheet_face([row[k][p], row[k][p + 1], row[k + 1][p + 1], row[k + 1][p]], top)
    for row, top in ((rows_top, True), (rows_bot, False)):
        for p in range(5):
            sheet_face([nose, row[0][p], row[0][p + 1]], top)
        for p in range(1, 4):
            sheet_face([tail, row[-1][p], row[-1][p + 1]], top)
    lat.damp_springs(par["zeta"])
    print(f"ray     omega_max = {lat.omega_max():7.1f} rad/s")
    return lat.doc(
        name="ray",
        description=(
            "Kuhl's stingray: a flat body with flexible wings; 4 elevator and 4 depressor "
            "muscles per side, 4 actuators."
        ),
        medium="water",
        dt=par["dt"],
        head="nose",
        forward=[1.0, 0.0, 0.0],
        defaults={"node_damping": par["node_damping"], "spring_damping": 0.0},
        actuators=acts,
        wave={
            "frequency": par["frequency"],
            "amplitude": 1.0,
            "offset": 0.0,
            "phases": {
                "elevator_left": 0.0,
                "elevator_right": 0.0,
                "depressor_left": par["lag"],
                "depressor_right": par["lag"],
            },
        },
    )


HEADER = (
    "# Built-in zoetic animal (see docs/animals.md for the format).\n"
    "# Generated by scripts/make_zoo.py; units are SI (m, kg, s, N).\n"
)


def main() -> None:
    ZOO.mkdir(parents=True, exist_ok=True)
    for make in (snake, shark, ray, dolphin, shark_1995, dolphin_1995):
        doc = make()
        order = [
            "name",
            "description",
            "medium",
            "dt",
            "start_offset",
            "head",
            "forward",
            "defaults",
            "wave",
            "eyes",
            "actuators",
            "fins",
            "nodes",
            "springs",
            "faces",
        ]
        doc = {k: doc[k] for k in order if k in doc}
        (ZOO / f"{doc['name']}.toml").write_text(HEADER + tomli_w.dumps(doc))


if __name__ == "__main__":
    main()
