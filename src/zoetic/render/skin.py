"""An animal's display surface: a smooth, coloured skin driven by its spring-mass lattice, as
the papers' display models were (a surface bound to the simulated nodes, not the nodes'
triangles themselves).

A ``Skin`` is one fixed linear map from the N node positions to V surface vertices: each
vertex is a weighted sum of a few nodes (``index`` (V, K), ``weight`` (V, K), each row summing
to 1, so the skin moves rigidly with the lattice). ``skin_vertices`` applies it to any batch
of frames in one product. The surface is the lattice's triangles after Loop subdivision
(weights >= 0), plus display-only fins whose corners are affine combinations of named nodes
(weights may be negative: a fin tip stands out beyond the nodes). Per-vertex colours come
from the species' look file (``render/looks/<name>.toml``): a back colour shaded to a belly
colour, then markings (spots, stripes, bands, eyes) placed in body coordinates at rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from zoetic.errors import ZoeticError
from zoetic.io import Table, load_toml

LOOKS = Path(__file__).parent / "looks"
LEVELS = 2  # Loop subdivisions of the lattice: 16 display triangles per lattice triangle
MARKINGS = ("spots", "stripe", "bands", "eyes", "patch")
_PALETTE = [(200, 120, 80), (110, 160, 200), (150, 110, 180), (90, 160, 120), (200, 170, 80)]


class LookError(ZoeticError):
    """A look file that cannot be read."""


@dataclass(frozen=True)
class Marking:
    """A coloured pattern in body coordinates at rest: u from the nose (0) to the tail tip (1),
    v from the belly (-1) to the back (+1) at that u, w from the right (-1) to the left (+1).

    kind: spots (``count`` round spots of ``size`` m, placed at random with ``seed``), stripe
    (the band of v in ``v`` along u in ``u``), bands (rings across u in ``u``, ``count`` of
    them, each ``size`` of its period), eyes (a round spot of ``size`` m each side at u[0],
    v[0]), patch (where u, v and w all lie in their ranges)."""

    kind: str
    color: tuple[float, float, float]
    u: tuple[float, float] = (0.0, 1.0)
    v: tuple[float, float] = (-1.0, 1.0)
    w: tuple[float, float] = (-1.0, 1.0)
    size: float = 0.05
    count: int = 10
    seed: int = 0


@dataclass(frozen=True)
class Fin:
    """A display-only fin: a flat polygon whose corners are affine combinations of named nodes
    (each a {node: weight} table, the weights summing to 1)."""

    name: str
    points: tuple[tuple[tuple[str, float], ...], ...]
    color: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Look:
    """How a species looks: back and belly colours (RGB in [0, 1]), where the back's colour
    gives way to the belly's (``shade``: v of the boundary, ``soft``: its width), markings
    and fins."""

    name: str
    back: tuple[float, float, float]
    belly: tuple[float, float, float]
    shade: float = 0.0
    soft: float = 0.4
    markings: tuple[Marking, ...] = ()
    fins: tuple[Fin, ...] = ()


@dataclass(frozen=True)
class Skin:
    """A display surface bound to N nodes: vertex v = sum_k weight[v, k] * node[index[v, k]].

    index (V, K) int32; weight (V, K) float32 (rows sum to 1); triangles (T, 3) int32,
    counter-clockwise seen from outside; colors (V, 3) float32 RGB in [0, 1]; closed (T,)
    bool: the triangle belongs to the closed body (False: a fin, seen from both sides)."""

    index: np.ndarray
    weight: np.ndarray
    triangles: np.ndarray
    colors: np.ndarray
    closed: np.ndarray
    n_nodes: int

    @property
    def face_colors(self) -> np.ndarray:
        """Return (T, 3) RGB in [0, 1]: each triangle's mean vertex colour (flat shading)."""
        return self.colors[self.triangles].mean(axis=1)

    def dense(self) -> np.ndarray:
        """Return the map as a dense (V, N) matrix."""
        m = np.zeros((len(self.index), self.n_nodes))
        np.add.at(m, (np.arange(len(self.index))[:, None], self.index), self.weight)
        return m


def skin_vertices(skin: Skin, positions) -> np.ndarray:
    """Return the skin's vertices (..., V, 3) m for node positions (..., N, 3) m."""
    p = np.asarray(positions, float)
    return np.einsum("...vkc,vk->...vc", p[..., skin.index, :], skin.weight)


def subdivision(faces: np.ndarray, n_nodes: int, levels: int = LEVELS):
    """Return (S, faces') of ``levels`` Loop subdivisions of a triangle mesh: the smooth
    surface's vertices are S @ nodes (S (V, N), rows >= 0 summing to 1) and its triangles
    faces'. Vertices on an open edge keep their place."""
    s = np.eye(n_nodes)
    f = np.asarray(faces, int)
    for _ in range(levels):
        n = s.shape[0]
        e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        opp = np.concatenate([f[:, 2], f[:, 0], f[:, 1]])
        edges, inv = np.unique(e, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        m = np.zeros((n + len(edges), n))
        nbr: list[set[int]] = [set() for _ in range(n)]
        boundary = np.zeros(n, bool)
        for k, (a, b) in enumerate(edges):
            nbr[a].add(b)
            nbr[b].add(a)
            others = opp[inv == k]
            if len(others) == 2:
                m[n + k, [a, b]] = 3 / 8
                m[n + k, others] += 1 / 8
            else:
                m[n + k, [a, b]] = 1 / 2
                boundary[[a, b]] = True
        for v in range(n):
            k = len(nbr[v])
            if boundary[v] or k == 0:
                m[v, v] = 1.0
                continue
            beta = 3 / (8 * k) if k > 3 else 3 / 16
            m[v, v] = 1 - k * beta
            m[v, list(nbr[v])] = beta
        mid = n + inv.reshape(3, -1).T  # (F, 3): edge points of (01, 12, 20)
        a, b, c = f.T
        ab, bc, ca = mid.T
        f = np.concatenate(
            [np.stack(x, 1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        )
        s = m @ s
    return s, f


# ---------------------------------------------------------------- look files


def _rgb(t: Table, key: str, default=...) -> tuple[float, float, float]:
    c = t.numbers(key, default, size=3)
    if c is default:
        return c
    if not all(0 <= x <= 255 for x in c):
        raise t.fail(f"{key!r} must be 3 numbers in [0, 255] (RGB), got {c}")
    return tuple(float(x) / 255.0 for x in c)  # type: ignore[return-value]


def _pair(t: Table, key: str, default) -> tuple[float, float]:
    lo, hi = t.numbers(key, list(default), size=2)
    if lo > hi:
        raise t.fail(f"{key!r} must be [low, high], got [{lo}, {hi}]")
    return (lo, hi)


def _marking(data, where: str) -> Marking:
    t = Table(data, where, LookError)
    m = Marking(
        t.string("kind", choices=MARKINGS),
        _rgb(t, "color"),
        _pair(t, "u", (0.0, 1.0)),
        _pair(t, "v", (-1.0, 1.0)),
        _pair(t, "w", (-1.0, 1.0)),
        t.number("size", 0.05, positive=True),
        t.integer("count", 10, lo=1, hi=500),
        t.integer("seed", 0, lo=0),
    )
    t.finish()
    return m


def _fin(data, where: str) -> Fin:
    t = Table(data, where, LookError)
    pts = t.raw("points")
    if not isinstance(pts, list) or not 3 <= len(pts) <= 8:
        raise t.fail("'points' must list 3 to 8 corners, each a {node = weight} table")
    corners = []
    for k, p in enumerate(pts):
        if not isinstance(p, dict) or not p:
            raise t.fail(f"corner {k + 1} must be a {{node = weight}} table, got {p!r}")
        w = {str(n): float(Table(p, f"{where}: corner {k + 1}", LookError).number(n)) for n in p}
        if abs(sum(w.values()) - 1.0) > 1e-6:
            raise t.fail(f"corner {k + 1}: weights sum to {sum(w.values()):g}, not 1")
        corners.append(tuple(w.items()))
    fin = Fin(t.string("name"), tuple(corners), _rgb(t, "color", None))
    t.finish()
    return fin


def read_look(path: str | Path) -> Look:
    """Return the Look in a look file (TOML: name, color, belly, shade, soft, [[marking]],
    [[fin]]); a bad entry is a LookError naming the file and entry."""
    path = Path(path)
    t = Table(load_toml(path, "look file", LookError), str(path), LookError)
    look = Look(
        t.string("name"),
        _rgb(t, "color"),
        _rgb(t, "belly"),
        t.number("shade", 0.0, lo=-1.0, hi=1.0),
        t.number("soft", 0.4, positive=True),
        tuple(
            _marking(m, f"{path}: marking {k + 1}") for k, m in enumerate(t.tables("marking", 50))
        ),
        tuple(_fin(f, f"{path}: fin {k + 1}") for k, f in enumerate(t.tables("fin", 20))),
    )
    t.finish()
    return look


@lru_cache(maxsize=32)
def look_of(name: str) -> Look:
    """Return the look of a species by name (``render/looks/<name>.toml``), or a plain one in
    a colour picked by the name when there is no such file."""
    path = LOOKS / f"{name}.toml"
    if path.is_file():
        return read_look(path)
    c = np.array(_PALETTE[sum(map(ord, name)) % len(_PALETTE)], float) / 255.0
    return Look(name, tuple(c), tuple(0.55 * c + 0.45))


def look_name(name: str, species: str) -> str:
    """Return the look of an animal named ``name`` (e.g. ``minnow_3``, a fish of the minnow
    species on the shark's lattice) of body ``species``: the name's stem if a look file has
    it, else the species."""
    stem = name.rsplit("_", 1)[0] if name.rsplit("_", 1)[-1].isdigit() else name
    return stem if (LOOKS / f"{stem}.toml").is_file() else species


def name_color(name: str) -> tuple[int, int, int]:
    """Return the display colour (RGB 0-255) of a species by name: its look's back colour."""
    return tuple(int(round(255 * c)) for c in look_of(name).back)  # type: ignore[return-value]


# ---------------------------------------------------------------- building a skin


def body_coordinates(rest: np.ndarray, forward=(1.0, 0.0, 0.0), bins: int = 16) -> np.ndarray:
    """Return (V, 3) body coordinates (u, v, w) of rest points (V, 3): u from the foremost
    (0) to the hindmost (1) along ``forward``, v from the lowest (-1) to the highest (+1)
    and w from the rightmost (-1) to the leftmost (+1) among the points at about that u."""
    f = np.asarray(forward, float) / np.linalg.norm(forward)
    x = rest @ f
    u = (x.max() - x) / max(float(np.ptp(x)), 1e-9)
    k = np.minimum((u * bins).astype(int), bins - 1)
    out = [u]
    for axis in (1, 2):
        y = rest[:, axis]
        lo = np.full(bins, np.inf)
        hi = np.full(bins, -np.inf)
        np.minimum.at(lo, k, y)
        np.maximum.at(hi, k, y)
        lo, hi = np.where(np.isfinite(lo), lo, 0.0), np.where(np.isfinite(hi), hi, 0.0)
        mid, half = 0.5 * (lo + hi)[k], np.maximum(0.5 * (hi - lo)[k], 1e-6)
        out.append(np.clip((y - mid) / half, -1.0, 1.0))
    return np.stack(out, axis=1)


def _inside(m: Marking, uvw: np.ndarray) -> np.ndarray:
    ok = np.ones(len(uvw), bool)
    for k, (lo, hi) in enumerate((m.u, m.v, m.w)):
        ok &= (uvw[:, k] >= lo) & (uvw[:, k] <= hi)
    return ok


def _marked(m: Marking, rest: np.ndarray, uvw: np.ndarray) -> np.ndarray:
    """Return (V,) bool: the vertices a marking colours."""
    region = _inside(m, uvw)
    if m.kind in ("stripe", "patch"):
        return region
    if m.kind == "bands":
        phase = (uvw[:, 0] - m.u[0]) / max(m.u[1] - m.u[0], 1e-9) * m.count
        return region & (phase % 1.0 < m.size)
    if m.kind == "spots":
        cand = np.flatnonzero(region)
        if not len(cand):
            return region
        rng = np.random.default_rng(m.seed)
        centres = rest[rng.choice(cand, size=min(m.count, len(cand)), replace=False)]
    else:  # eyes: the point at (u, v) farthest out on each side
        centres = []
        for side in (-1.0, 1.0):
            near = np.abs(uvw[:, 0] - m.u[0]) + 0.3 * np.abs(uvw[:, 1] - m.v[0])
            near -= 0.3 * side * uvw[:, 2]
            centres.append(rest[int(np.argmin(near))])
    d = np.linalg.norm(rest[:, None] - np.asarray(centres)[None], axis=-1).min(axis=1)
    return d <= m.size


def skin_colors(look: Look, rest: np.ndarray, uvw: np.ndarray) -> np.ndarray:
    """Return (V, 3) RGB in [0, 1] of vertices at rest (V, 3) with body coordinates ``uvw``:
    the back's colour over the belly's, then each marking in order."""
    t = np.clip(0.5 - (uvw[:, 1] - look.shade) / look.soft, 0.0, 1.0)[:, None]
    col = np.asarray(look.back) * (1 - t) + np.asarray(look.belly) * t
    for m in look.markings:
        col[_marked(m, rest, uvw)] = m.color
    return col


def _fin_rows(look: Look, node_names, n_nodes: int):
    """Return the fins' weight rows (P, N), triangles (into those rows) and colours (P, 3)."""
    rows, tris, cols = [], [], []
    index = {n: i for i, n in enumerate(node_names or ())}
    for fin in look.fins:
        base = len(rows)
        for corner in fin.points:
            r = np.zeros(n_nodes)
            for node, w in corner:
                if node not in index:
                    raise LookError(f"look {look.name!r}: fin {fin.name!r}: no node {node!r}")
                r[index[node]] += w
            rows.append(r)
        k = len(fin.points)
        tris += [(base, base + j, base + j + 1) for j in range(1, k - 1)]
        cols += [fin.color or look.back] * k
    return rows, tris, cols


def _sparse(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (index, weight) (V, K) of a (V, N) matrix's non-zero entries, zero-padded."""
    nz = np.abs(m) > 1e-12
    k = max(int(nz.sum(axis=1).max()), 1)
    order = np.argsort(~nz, axis=1, kind="stable")[:, :k]
    w = np.take_along_axis(m, order, axis=1)
    return order.astype(np.int32), np.where(np.abs(w) > 1e-12, w, 0.0).astype(np.float32)


def make_skin(
    faces,
    rest,
    look: Look,
    node_names=None,
    forward=(1.0, 0.0, 0.0),
    levels: int = LEVELS,
) -> Skin:
    """Return the skin of a lattice with surface triangles ``faces`` (F, 3) and rest node
    positions ``rest`` (N, 3) m, coloured by ``look``; its fins need the ``node_names``
    (without them the look's fins are left out)."""
    rest = np.asarray(rest, float)
    n = len(rest)
    s, tris = subdivision(faces, n, levels)
    fin_rows, fin_tris, fin_cols = _fin_rows(look, node_names, n) if node_names else ([], [], [])
    body_rest = s @ rest
    uvw = body_coordinates(body_rest, forward)
    colors = skin_colors(look, body_rest, uvw)
    if fin_rows:
        s = np.concatenate([s, np.asarray(fin_rows)])
        tris = np.concatenate([tris, np.asarray(fin_tris) + len(body_rest)])
        colors = np.concatenate([colors, np.asarray(fin_cols)])
    closed = np.arange(len(tris)) < len(tris) - len(fin_tris)
    index, weight = _sparse(s)
    return Skin(index, weight, tris.astype(np.int32), colors.astype(np.float32), closed, n)


@lru_cache(maxsize=32)
def _body_skin(body, look: str, levels: int) -> Skin:
    return make_skin(
        body.faces, body.rest_pos, look_of(look), body.node_names, body.forward, levels
    )


def body_skin(body, look: str | None = None, levels: int = LEVELS) -> Skin:
    """Return the skin of a Body in the look named ``look`` (default: the body's own name)."""
    return _body_skin(body, look or body.name, levels)


def record_skin(name: str, species: str, faces, rest) -> Skin:
    """Return the skin of a recorded animal: its zoo body's (with fins) when ``species`` is a
    built-in animal with these faces, else one made on ``rest`` (N, 3) (a pose of the
    animal, e.g. its first recorded frame) without fins; in the look ``look_name`` picks."""
    look = look_name(name, species)
    body = _zoo_body(species)
    if body is not None and np.array_equal(np.asarray(body.faces), np.asarray(faces)):
        return body_skin(body, look)
    rest = np.nan_to_num(np.asarray(rest, float))
    return make_skin(faces, rest, look_of(look), None)


@lru_cache(maxsize=16)
def _zoo_body(species: str):
    """Return the built-in animal of that name, or None."""
    from zoetic.bodies import load_animal

    try:
        return load_animal(species)
    except ZoeticError:
        return None
