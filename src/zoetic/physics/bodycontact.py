"""Contact between animals: a node of one body against the skin (the closed triangle surface,
``Body.faces``) of another.

A node's signed distance to a body is its distance to the nearest triangle of the body's
surface, negative inside (the winding number of the surface about the node says which). A node
touches when its signed distance is under the skin radius r (the world's node radius) and is
pushed out along the distance's gradient (away from the nearest surface point) by a penalty
force; the triangle's three nodes take the opposite force, shared by the closest point's
barycentric weights, so momentum is conserved. The force is a spring-damper on the depth r - s
with the pair's reduced mass m: k = m w^2, damping 2 zeta m w with w = pi / (``CONTACT_STEPS``
dt) (a contact lasts about 8 steps; w dt = 0.39 keeps the explicit step stable even with a
dozen contacts loading one node), never pulling (clamped at 0) and without friction, so contact
can only take energy away (``tests/test_bodycontact.py`` checks it).

How deep one animal went into another (``deepest``) is the largest -s over its nodes: 0 unless a
node crossed the other's skin. ``close`` is the broad phase: two animals can touch within a
horizon only if some pair of their nodes is within reach (the longest surface edge, the skin
radius and how far both can travel).

Layouts follow the animal kernel: node arrays (N, 3, B) float32 (a World's state views).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zoetic.bodies import Body
from zoetic.jitcache import fresh_numba_cache
from zoetic.physics.shapes import node_box

fresh_numba_cache()

CONTACT_STEPS = 8  # steps a contact lasts: w = pi / (CONTACT_STEPS dt)
STRETCH = 1.5  # how much longer than at rest a surface edge may get (the broad phase's reach)


def surface_reach(body: Body) -> float:
    """Return how far a point of the body's surface may lie from the nearest of its nodes: the
    longest edge of its triangles at rest, stretched by ``STRETCH``, over sqrt(3) (no point of
    a triangle lies farther than that from all three corners). A point within r of the surface
    lies within r + this of one of its nodes."""
    f = np.asarray(body.faces, dtype=np.int64)
    if not len(f):
        return 0.0
    p = body.rest_pos
    edges = np.concatenate(
        [p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 1]], p[f[:, 0]] - p[f[:, 2]]]
    )
    return float(np.sqrt((edges**2).sum(1)).max() * STRETCH / np.sqrt(3.0))


@njit(cache=True, inline="always")
def _closest(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz):
    """Return the point of triangle abc closest to p and its barycentric weights (u, v, w) on
    a, b, c (Ericson, Real-Time Collision Detection, 5.1.5)."""
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az, 1.0, 0.0, 0.0
    bpx, bpy, bpz = px - bx, py - by, pz - bz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz, 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return ax + v * abx, ay + v * aby, az + v * abz, 1.0 - v, v, 0.0
    cpx, cpy, cpz = px - cx, py - cy, pz - cz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz, 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return ax + w * acx, ay + w * acy, az + w * acz, 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + w * (cx - bx), by + w * (cy - by), bz + w * (cz - bz), 0.0, 1.0 - w, w
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    return (
        ax + abx * v + acx * w,
        ay + aby * v + acy * w,
        az + abz * v + acz * w,
        1.0 - v - w,
        v,
        w,
    )


@njit(cache=True, inline="always")
def _signed(pos, faces, b, px, py, pz):
    """Return (s, k, u, v, w, nx, ny, nz): the signed distance of p to the closed surface of
    the body at ``pos`` (lane b; negative inside), the nearest triangle k, the closest point's
    weights on it and the unit direction that takes p out of the body fastest (the distance's
    gradient: from the closest point to p outside, from p to it inside).

    Inside or out is the winding number (the triangles' solid angles seen from p, Van
    Oosterom and Strackee), which holds near edges and corners where the nearest triangle's
    own normal can mislead.
    """
    best = np.inf
    bk, bu, bv, bw = -1, 0.0, 0.0, 0.0
    bqx, bqy, bqz = 0.0, 0.0, 0.0
    fnx, fny, fnz = 0.0, 0.0, 0.0
    solid = 0.0
    for k in range(faces.shape[0]):
        i, j, m = faces[k, 0], faces[k, 1], faces[k, 2]
        ax, ay, az = pos[i, 0, b], pos[i, 1, b], pos[i, 2, b]
        bx, by, bz = pos[j, 0, b], pos[j, 1, b], pos[j, 2, b]
        cx, cy, cz = pos[m, 0, b], pos[m, 1, b], pos[m, 2, b]
        # solid angle of the triangle seen from p
        x1, y1, z1 = ax - px, ay - py, az - pz
        x2, y2, z2 = bx - px, by - py, bz - pz
        x3, y3, z3 = cx - px, cy - py, cz - pz
        l1 = math.sqrt(x1 * x1 + y1 * y1 + z1 * z1)
        l2 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
        l3 = math.sqrt(x3 * x3 + y3 * y3 + z3 * z3)
        det = x1 * (y2 * z3 - z2 * y3) - y1 * (x2 * z3 - z2 * x3) + z1 * (x2 * y3 - y2 * x3)
        den = (
            l1 * l2 * l3
            + (x1 * x2 + y1 * y2 + z1 * z2) * l3
            + (x1 * x3 + y1 * y3 + z1 * z3) * l2
            + (x2 * x3 + y2 * y3 + z2 * z3) * l1
        )
        solid += 2.0 * math.atan2(det, den)
        qx, qy, qz, u, v, w = _closest(px, py, pz, ax, ay, az, bx, by, bz, cx, cy, cz)
        dx, dy, dz = px - qx, py - qy, pz - qz
        d = math.sqrt(dx * dx + dy * dy + dz * dz)
        if d < best:
            best = d
            bk, bu, bv, bw = k, u, v, w
            bqx, bqy, bqz = qx, qy, qz
            fnx = (by - ay) * (cz - az) - (bz - az) * (cy - ay)
            fny = (bz - az) * (cx - ax) - (bx - ax) * (cz - az)
            fnz = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    inside = solid > 2.0 * math.pi  # winding number 1 (4 pi) inside, 0 outside
    if best > 1e-9:
        sgn = -1.0 if inside else 1.0
        nx, ny, nz = sgn * (px - bqx) / best, sgn * (py - bqy) / best, sgn * (pz - bqz) / best
    else:  # on the surface: the triangle's own normal
        nn = math.sqrt(fnx * fnx + fny * fny + fnz * fnz) + 1e-30
        nx, ny, nz = fnx / nn, fny / nn, fnz / nn
    return (-best if inside else best), bk, bu, bv, bw, nx, ny, nz


@njit(cache=True, inline="always")
def _any_in_box(p, q, b, pad) -> bool:
    """Return True if some node of p lies in the bounding box of q's nodes padded by pad."""
    lx, ly, lz, hx, hy, hz = node_box(q, b, pad)
    for i in range(p.shape[0]):
        x, y, z = p[i, 0, b], p[i, 1, b], p[i, 2, b]
        if lx <= x <= hx and ly <= y <= hy and lz <= z <= hz:
            return True
    return False


@njit(cache=True)
def close(pa, va, pb, vb, reach, skin, horizon) -> bool:
    """Return True if, in some lane, the animals at pa and pb (velocities va, vb) may touch
    within ``horizon`` s at their present speeds. They close at most (max |va - u| +
    max |vb - u|) m/s for any u, here the nodes' mean velocity (two fishes swimming side by
    side close only as fast as they wag). Both must hold: a node of one within ``skin`` (plus
    that travel) of the other's bounding box, which holds its surface; and two nodes within
    ``reach`` (plus the travel)."""
    na, nb = pa.shape[0], pb.shape[0]
    for b in range(pa.shape[2]):
        ux = uy = uz = 0.0
        for i in range(na):
            ux, uy, uz = ux + va[i, 0, b], uy + va[i, 1, b], uz + va[i, 2, b]
        for j in range(nb):
            ux, uy, uz = ux + vb[j, 0, b], uy + vb[j, 1, b], uz + vb[j, 2, b]
        ux, uy, uz = ux / (na + nb), uy / (na + nb), uz / (na + nb)
        sa = 0.0
        for i in range(na):
            sa = max(
                sa, (va[i, 0, b] - ux) ** 2 + (va[i, 1, b] - uy) ** 2 + (va[i, 2, b] - uz) ** 2
            )
        sb = 0.0
        for j in range(nb):
            sb = max(
                sb, (vb[j, 0, b] - ux) ** 2 + (vb[j, 1, b] - uy) ** 2 + (vb[j, 2, b] - uz) ** 2
            )
        travel = (math.sqrt(sa) + math.sqrt(sb)) * horizon
        if not (_any_in_box(pa, pb, b, skin + travel) or _any_in_box(pb, pa, b, skin + travel)):
            continue
        r = reach + travel
        r2 = r * r
        for i in range(na):
            x, y, z = pa[i, 0, b], pa[i, 1, b], pa[i, 2, b]
            for j in range(nb):
                dx, dy, dz = x - pb[j, 0, b], y - pb[j, 1, b], z - pb[j, 2, b]
                if dx * dx + dy * dy + dz * dz < r2:
                    return True
    return False


@njit(cache=True)
def _extents(pos, vel, off):
    """Return each animal's bounding box over all lanes, lo (n, 3) and hi (n, 3), and the
    fastest of its nodes' speeds (n,) m/s: nodes of all animals stacked in pos, vel (N, 3, B)."""
    n = off.shape[0] - 1
    lo, hi, speed = np.full((n, 3), np.inf), np.full((n, 3), -np.inf), np.zeros(n)
    for a in range(n):
        for i in range(off[a], off[a + 1]):
            for b in range(pos.shape[2]):
                s = 0.0
                for c in range(3):
                    lo[a, c] = min(lo[a, c], pos[i, c, b])
                    hi[a, c] = max(hi[a, c], pos[i, c, b])
                    s += vel[i, c, b] * vel[i, c, b]
                speed[a] = max(speed[a], s)
        speed[a] = math.sqrt(speed[a])
    return lo, hi, speed


@njit(cache=True)
def close_pairs(pos, vel, off, reach, skin, horizon) -> np.ndarray:
    """Return the pairs (P, 2) of animals that may touch within ``horizon`` s (``close`` for
    every pair in one call), in order (a < c, by a then c): nodes of all animals stacked in
    pos, vel (N, 3, B), animal a's rows off[a]:off[a + 1], its surface reach (m) reach[a].

    Sweep and prune first: ``close`` needs a node of one within its skin plus the travel of
    the other's bounding box, and the travel is at most 4 max |v| horizon (each node's speed
    against the pair's mean velocity at most twice the fastest node's), so only pairs whose
    boxes padded by that overlap are tested (found along the boxes sorted by their low x)."""
    n = off.shape[0] - 1
    lo, hi, speed = _extents(pos, vel, off)
    reach_all = 4.0 * horizon * (speed.max() if n else 0.0) + skin + 1e-6
    order = np.argsort(lo[:, 0])
    keys = [np.int64(0) for _ in range(0)]
    for ia in range(n):
        a = order[ia]
        for ic in range(ia + 1, n):
            c = order[ic]
            if lo[c, 0] > hi[a, 0] + reach_all:
                break
            pad = 4.0 * horizon * max(speed[a], speed[c]) + skin + 1e-6
            if (
                lo[c, 1] > hi[a, 1] + pad
                or lo[a, 1] > hi[c, 1] + pad
                or lo[c, 2] > hi[a, 2] + pad
                or lo[a, 2] > hi[c, 2] + pad
                or lo[c, 0] > hi[a, 0] + pad
                or lo[a, 0] > hi[c, 0] + pad
            ):
                continue
            i, j = min(a, c), max(a, c)
            r = max(reach[i], reach[j]) + skin
            pi, vi = pos[off[i] : off[i + 1]], vel[off[i] : off[i + 1]]
            if close(pi, vi, pos[off[j] : off[j + 1]], vel[off[j] : off[j + 1]], r, skin, horizon):
                keys.append(i * n + j)
    found = np.sort(np.array(keys, np.int64)) if len(keys) > 0 else np.empty(0, np.int64)
    out = np.empty((found.shape[0], 2), np.int64)
    out[:, 0] = found // n
    out[:, 1] = found % n
    return out


@njit(cache=True)
def _push(pa, va, ma, pb, vb, mb, fb, radius, w, zeta, fa_out, fb_out, load, b):
    """Add to fa_out / fb_out (N, 3) the forces between the nodes of a and the skin of b in
    lane b; return the normal force's sum (N)."""
    lx, ly, lz, hx, hy, hz = node_box(pb, b, radius)
    total = 0.0
    for i in range(pa.shape[0]):
        px, py, pz = pa[i, 0, b], pa[i, 1, b], pa[i, 2, b]
        if px < lx or px > hx or py < ly or py > hy or pz < lz or pz > hz:
            continue
        s, k, u, v, ww, nx, ny, nz = _signed(pb, fb, b, px, py, pz)
        pen = radius - s
        if k < 0 or pen <= 0.0:
            continue
        i0, i1, i2 = fb[k, 0], fb[k, 1], fb[k, 2]
        # the face side's effective mass at the closest point, and the pair's reduced mass
        inv_face = u * u / mb[i0] + v * v / mb[i1] + ww * ww / mb[i2]
        m = 1.0 / (1.0 / ma[i] + inv_face)
        # relative normal velocity of the node against the surface point (>0: separating)
        qvx = u * vb[i0, 0, b] + v * vb[i1, 0, b] + ww * vb[i2, 0, b]
        qvy = u * vb[i0, 1, b] + v * vb[i1, 1, b] + ww * vb[i2, 1, b]
        qvz = u * vb[i0, 2, b] + v * vb[i1, 2, b] + ww * vb[i2, 2, b]
        vn = (va[i, 0, b] - qvx) * nx + (va[i, 1, b] - qvy) * ny + (va[i, 2, b] - qvz) * nz
        fn = m * w * w * pen - 2.0 * zeta * m * w * vn
        if fn <= 0.0:
            continue
        load[i] = 1.0
        total += fn
        fa_out[i, 0] += fn * nx
        fa_out[i, 1] += fn * ny
        fa_out[i, 2] += fn * nz
        fb_out[i0, 0] -= u * fn * nx
        fb_out[i0, 1] -= u * fn * ny
        fb_out[i0, 2] -= u * fn * nz
        fb_out[i1, 0] -= v * fn * nx
        fb_out[i1, 1] -= v * fn * ny
        fb_out[i1, 2] -= v * fn * nz
        fb_out[i2, 0] -= ww * fn * nx
        fb_out[i2, 1] -= ww * fn * ny
        fb_out[i2, 2] -= ww * fn * nz
    return total


@njit(cache=True)
def pair_contacts(pa, va, ma, fa, pb, vb, mb, fb, radius, dt, w, zeta, between):
    """Apply one step's contact impulses between two animals (each node of one against the
    other's skin, both ways), all forces from the state at the step's start. Velocities change
    in place (v += dt F / m); ``between`` (2, B) accumulates the normal impulse (N s) that a got
    from b (row 0) and b from a (row 1)."""
    na, nb = pa.shape[0], pb.shape[0]
    for b in range(pa.shape[2]):
        f_a = np.zeros((na, 3))
        f_b = np.zeros((nb, 3))
        load_a = np.zeros(na)
        load_b = np.zeros(nb)
        ja = _push(pa, va, ma, pb, vb, mb, fb, radius, w, zeta, f_a, f_b, load_a, b)
        jb = _push(pb, vb, mb, pa, va, ma, fa, radius, w, zeta, f_b, f_a, load_b, b)
        if ja == 0.0 and jb == 0.0:
            continue
        between[0, b] += ja * dt
        between[1, b] += jb * dt
        for i in range(na):
            for c in range(3):
                va[i, c, b] += dt * f_a[i, c] / ma[i]
        for j in range(nb):
            for c in range(3):
                vb[j, c, b] += dt * f_b[j, c] / mb[j]


@njit(cache=True)
def pairs_contacts(pos, vel, off, mass, faces, face_off, pairs, radius, dt, w, zeta, between):
    """``pair_contacts`` for each pair (P, 2) in order, in one call: nodes of all animals
    stacked in pos, vel (N, 3, B) float32 (animal a's rows off[a]:off[a + 1]), their masses
    stacked in ``mass`` (N,), animal a's triangles faces[face_off[a]:face_off[a + 1]] (indices
    into its own nodes). ``between`` (B, n, n) accumulates the normal impulse (N s) that a got
    from c at [:, a, c] (and c from a at [:, c, a]), a pair's step added once as a whole."""
    buf = np.zeros((2, pos.shape[2]))
    for p in range(pairs.shape[0]):
        a, c = pairs[p, 0], pairs[p, 1]
        a0, a1, c0, c1 = off[a], off[a + 1], off[c], off[c + 1]
        buf[:] = 0.0
        pair_contacts(
            pos[a0:a1],
            vel[a0:a1],
            mass[a0:a1],
            faces[face_off[a] : face_off[a + 1]],
            pos[c0:c1],
            vel[c0:c1],
            mass[c0:c1],
            faces[face_off[c] : face_off[c + 1]],
            radius,
            dt,
            w,
            zeta,
            buf,
        )
        for b in range(pos.shape[2]):
            between[b, a, c] += buf[0, b]
            between[b, c, a] += buf[1, b]


@njit(cache=True)
def close_among(pos, vel, off, pairs, reach, skin, horizon) -> np.ndarray:
    """Return (P,) bools: whether each pair (P, 2) of animals may touch within ``horizon`` s
    (``close`` with the larger of the two surface reaches ``reach`` plus ``skin``), in one
    call: nodes of all animals stacked in pos, vel (N, 3, B), animal a's rows off[a]:off[a + 1]."""
    out = np.zeros(pairs.shape[0], np.bool_)
    for p in range(pairs.shape[0]):
        a, c = pairs[p, 0], pairs[p, 1]
        r = max(reach[a], reach[c]) + skin
        a0, a1, c0, c1 = off[a], off[a + 1], off[c], off[c + 1]
        out[p] = close(pos[a0:a1], vel[a0:a1], pos[c0:c1], vel[c0:c1], r, skin, horizon)
    return out


@njit(cache=True)
def _deepest(pa, pb, fb, b) -> float:
    lx, ly, lz, hx, hy, hz = node_box(pb, b, 0.0)
    out = 0.0
    for i in range(pa.shape[0]):
        px, py, pz = pa[i, 0, b], pa[i, 1, b], pa[i, 2, b]
        if px < lx or px > hx or py < ly or py > hy or pz < lz or pz > hz:
            continue
        s = _signed(pb, fb, b, px, py, pz)[0]
        out = max(out, -s)
    return out


def deepest(pos_a: np.ndarray, pos_b: np.ndarray, faces_b: np.ndarray) -> float:
    """Return how deep (m) the deepest node of animal a (positions (N, 3)) lies inside the
    closed surface of animal b (positions (M, 3), triangles ``faces_b``): 0 if none is."""
    pa = np.ascontiguousarray(np.asarray(pos_a, np.float64)[:, :, None])
    pb = np.ascontiguousarray(np.asarray(pos_b, np.float64)[:, :, None])
    return float(_deepest(pa, pb, np.asarray(faces_b, np.int64), 0))


@njit(cache=True)
def skin_distances(points, which, pos, faces, face_off):
    """Return, for each point (P, 3) against the closed surface of body which[p] (triangles
    faces[face_off[a]:face_off[a + 1]], indices into the nodes pos (N, 3)): its signed
    distance (P,) m (negative inside), the nearest triangle's row in ``faces`` (P,; -1 if the
    body has none), the closest point's weights on its corners (P, 3) and the unit direction
    that takes the point out fastest (P, 3)."""
    n = points.shape[0]
    dist = np.full(n, np.inf)
    face = np.full(n, -1, np.int64)
    bary = np.zeros((n, 3))
    normal = np.zeros((n, 3))
    lanes = pos.reshape(pos.shape[0], 3, 1)
    for p in range(n):
        a = which[p]
        f0, f1 = face_off[a], face_off[a + 1]
        if f1 <= f0:
            continue
        s, k, u, v, w, nx, ny, nz = _signed(
            lanes, faces[f0:f1], 0, points[p, 0], points[p, 1], points[p, 2]
        )
        dist[p], face[p] = s, f0 + k
        bary[p, 0], bary[p, 1], bary[p, 2] = u, v, w
        normal[p, 0], normal[p, 1], normal[p, 2] = nx, ny, nz
    return dist, face, bary, normal
