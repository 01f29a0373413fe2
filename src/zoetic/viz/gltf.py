"""A Scene as an animated glTF 2.0 binary (.glb) that Blender, three.js and other tools load.

Each animal is its display skin (``render.skin``) as a skinned mesh with one joint per node:
a joint's translation is its node's position, keyframed at the scene's frame rate (LINEAR),
and each vertex is its skin's weighted sum of joints (JOINTS_n/WEIGHTS_n in sets of four;
a fin tip, an affine extension of the nodes, is a joint of its own keyframed where it is),
coloured per vertex (COLOR_0). The file grows as frames x joints x 12 bytes, like morph
targets would, without the frames^2 weights table and the per-shader limits on morph target
counts. A rigid-link
creature's links are meshes posed per frame. Objects are meshes of their shapes (spheres,
boxes, cylinders; a target a small octahedron), moved where they move and scaled to nothing
once gone (food eaten). Ground, sea floor and sea surface are static quads (checkered by a
2 x 2 texture).

zoetic's axes are x forward, y up, z LEFT; glTF's are right-handed, so z is mirrored (and
triangles reversed to stay counter-clockwise from outside): left stays on the animal's left.
"""

from __future__ import annotations

import io
import json
import os
import struct
from pathlib import Path

import numpy as np

from zoetic.io import atomic_write_bytes
from zoetic.render.scene import solid, strand_tube
from zoetic.render.skin import Skin, look_of, make_skin, skin_vertices
from zoetic.viz.scene import Animal, Creature, Scene, Thing

MIRROR = np.array([1.0, 1.0, -1.0], np.float32)  # zoetic (x, y, z left) -> glTF (z right)
_FLOAT, _UINT, _USHORT, _UBYTE = 5126, 5125, 5123, 5121
_ARRAY, _ELEMENTS = 34962, 34963
_TILE = 0.5  # m, side of a checker square (as in the videos)
OBJECT_COLORS = {  # kind: (sRGB 0-255, opacity)
    "ball": ((235, 235, 220), 1.0),
    "food": ((240, 170, 50), 1.0),
    "rock": ((115, 107, 97), 1.0),
    "seaweed": ((40, 140, 50), 1.0),
    "hurdle": ((230, 90, 40), 1.0),
    "bar": ((230, 90, 40), 1.0),  # a hurdle's bar (the hurdle trick)
    "post": ((150, 110, 70), 1.0),  # a ball trick's post
    "target": ((220, 40, 30), 1.0),
    "goal": ((220, 40, 30), 1.0),
    "obstacle": ((240, 200, 40), 0.35),
    "wall": ((150, 180, 210), 0.12),
}


def to_gltf_axes(points: np.ndarray) -> np.ndarray:
    """Return points (..., 3) in glTF axes as float32 (z mirrored)."""
    return (np.asarray(points, np.float32) * MIRROR).astype(np.float32)


def _fill_frames(pos: np.ndarray) -> np.ndarray:
    """Return positions (R, N, 3) with non-finite frames replaced by the last finite one."""
    good = np.isfinite(pos).all(axis=(1, 2))
    if good.all():
        return pos
    if not good.any():
        return np.zeros_like(pos)
    idx = np.maximum.accumulate(np.where(good, np.arange(len(pos)), np.argmax(good)))
    return pos[idx]


def _linear(rgb) -> list[float]:
    """Return an sRGB 0-255 colour as glTF's linear RGBA factors."""
    c = (np.asarray(rgb[:3], float) / 255.0) ** 2.2
    return [round(float(v), 5) for v in c] + [1.0]


def _checker_png(a, b) -> bytes:
    from PIL import Image

    img = Image.new("RGB", (2, 2))
    img.putdata([tuple(map(int, a)), tuple(map(int, b)), tuple(map(int, b)), tuple(map(int, a))])
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue()


class _Builder:
    """Accumulates the JSON document and the binary chunk of a GLB."""

    def __init__(self) -> None:
        self.doc: dict = {
            "asset": {"version": "2.0", "generator": "zoetic"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }
        self.blob = bytearray()

    def view(self, data: bytes, target: int | None = None) -> int:
        while len(self.blob) % 4:
            self.blob.append(0)
        v = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if target is not None:
            v["target"] = target
        self.blob.extend(data)
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(
        self,
        arr: np.ndarray,
        kind: str,
        target: int | None = None,
        view: int | None = None,
        offset: int = 0,
        bounds: bool = False,
    ) -> int:
        comp = {
            np.dtype(np.float32): _FLOAT,
            np.dtype(np.uint32): _UINT,
            np.dtype(np.uint16): _USHORT,
            np.dtype(np.uint8): _UBYTE,
        }[arr.dtype]
        if view is None:
            view = self.view(np.ascontiguousarray(arr).tobytes(), target)
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        flat = arr.reshape(-1, width)
        acc = {
            "bufferView": view,
            "byteOffset": offset,
            "componentType": comp,
            "count": len(flat),
            "type": kind,
        }
        if bounds:
            acc["min"] = [float(v) for v in flat.min(axis=0)]
            acc["max"] = [float(v) for v in flat.max(axis=0)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def add(self, key: str, item: dict) -> int:
        self.doc.setdefault(key, []).append(item)
        return len(self.doc[key]) - 1

    def node(self, item: dict, root: bool = True) -> int:
        k = self.add("nodes", item)
        if root:
            self.doc["scenes"][0]["nodes"].append(k)
        return k

    def glb(self) -> bytes:
        while len(self.blob) % 4:
            self.blob.append(0)
        self.doc["buffers"] = [{"byteLength": len(self.blob)}]
        doc = {k: v for k, v in self.doc.items() if v != []}
        js = json.dumps(doc, separators=(",", ":")).encode()
        js += b" " * (-len(js) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.blob)
        return b"".join(
            [
                struct.pack("<III", 0x46546C67, 2, total),
                struct.pack("<II", len(js), 0x4E4F534A),
                js,
                struct.pack("<II", len(self.blob), 0x004E4942),
                bytes(self.blob),
            ]
        )


def _material(
    b: _Builder,
    name: str,
    rgba: list[float],
    texture: bytes | None = None,
    blend: bool = False,
    roughness: float = 0.8,
) -> int:
    pbr: dict = {"baseColorFactor": rgba, "metallicFactor": 0.0, "roughnessFactor": roughness}
    if texture is not None:
        image = b.add("images", {"bufferView": b.view(texture), "mimeType": "image/png"})
        sampler = b.add(
            "samplers", {"magFilter": 9728, "minFilter": 9984, "wrapS": 10497, "wrapT": 10497}
        )
        pbr["baseColorTexture"] = {
            "index": b.add("textures", {"source": image, "sampler": sampler})
        }
    mat = {"name": name, "pbrMetallicRoughness": pbr, "doubleSided": True}
    if blend:
        mat["alphaMode"] = "BLEND"
    return b.add("materials", mat)


def _quad(b: _Builder, name: str, y: float, lo, hi, material: int, textured: bool) -> None:
    """Add a horizontal rectangle at height ``y`` over x in [lo0, hi0], z in [lo1, hi1]."""
    (x0, z0), (x1, z1) = lo, hi
    pos = np.array([[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]], np.float32)
    attrs = {
        "POSITION": b.accessor(pos, "VEC3", _ARRAY, bounds=True),
        "NORMAL": b.accessor(np.tile(np.float32([0, 1, 0]), (4, 1)), "VEC3", _ARRAY),
    }
    if textured:
        uv = np.ascontiguousarray(pos[:, [0, 2]] / np.float32(2 * _TILE))
        attrs["TEXCOORD_0"] = b.accessor(uv, "VEC2", _ARRAY)
    idx = b.accessor(np.array([0, 2, 1, 0, 3, 2], np.uint16), "SCALAR", _ELEMENTS)
    mesh = b.add(
        "meshes",
        {"name": name, "primitives": [{"attributes": attrs, "indices": idx, "material": material}]},
    )
    b.node({"name": name, "mesh": mesh})


def _quaternions(angles: np.ndarray, axis: str) -> np.ndarray:
    """Return glTF rotations (R, 4) xyzw of planar angles (R,) in zoetic axes.

    About z (a vertical plane) mirroring z leaves the rotation as it is; about y (a top view,
    the angle turning x toward zoetic's +z, which is glTF's -z) it is a rotation by +angle.
    """
    half = np.asarray(angles, np.float64) / 2
    q = np.zeros((len(half), 4), np.float32)
    q[:, 2 if axis == "z" else 1] = np.sin(half)
    q[:, 3] = np.cos(half)
    return q


def environment_levels(scene: Scene) -> dict:
    """Return the heights (glTF y) of the ground, sea floor and sea surface a scene shows.

    Keys present: ``ground`` (a floor at y = 0), ``seabed`` (under water), ``surface`` (a sea's
    water level). The sea floor lies 3 m under the surface, or under the animals' lowest point.
    """
    med = scene.medium
    if med.floor:
        return {"ground": 0.0}
    if med.water_level < -1e8:  # vacuum: nothing to stand on
        return {}
    low = min([float(np.nanmin(m.com[:, 1])) - 0.5 for m in scene.movers] + [0.0])
    for a in scene.animals:
        low = min(low, float(np.nanmin(a.positions[..., 1])))
    base = med.water_level if abs(med.water_level) < 1e8 else 0.0
    levels = {"seabed": round(min(base - 3.0, low - 1.0), 3)}
    if abs(med.water_level) < 1e8:
        levels["surface"] = float(med.water_level)
    return levels


def scene_bounds(scene: Scene, margin: float = 8.0) -> tuple[np.ndarray, np.ndarray]:
    """Return the (x, z) rectangle in glTF axes that the ground covers: the paths, the objects
    and a margin."""
    pts = [to_gltf_axes(m.com)[:, [0, 2]] for m in scene.movers]
    pts += [to_gltf_axes(o.positions).reshape(-1, 3)[:, [0, 2]] for o in scene.objects]
    allp = np.concatenate(pts) if pts else np.zeros((0, 2), np.float32)
    allp = allp[np.isfinite(allp).all(axis=1)]
    if not len(allp):
        allp = np.zeros((1, 2), np.float32)
    lo = np.floor((allp.min(axis=0) - margin) / (2 * _TILE)) * 2 * _TILE
    hi = np.ceil((allp.max(axis=0) + margin) / (2 * _TILE)) * 2 * _TILE
    return lo, hi


class _Tracks:
    """The animation's channels and samplers, all keyed on one time accessor."""

    def __init__(self, b: _Builder, times: np.ndarray) -> None:
        self.b, self.channels, self.samplers = b, [], []
        self.times = b.accessor(times, "SCALAR", bounds=True)

    def add(self, node: int, path: str, output: int, interpolation: str = "LINEAR") -> None:
        self.samplers.append(
            {"input": self.times, "output": output, "interpolation": interpolation}
        )
        self.channels.append(
            {"sampler": len(self.samplers) - 1, "target": {"node": node, "path": path}}
        )


def skin_joints(skin: Skin) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return a skin as glTF skinning: per vertex joint ids and weights (V, 4 s) in s sets of
    four (weights >= 0, summing to 1), the joints being the N nodes followed by one joint per
    vertex the nodes cannot carry with weights >= 0 (a fin's tip, keyframed where it is);
    and the indices (E,) of those vertices."""
    v, k = skin.index.shape
    sets = -(-k // 4)
    extra = np.flatnonzero((skin.weight < 0).any(axis=1))
    ids = np.zeros((v, 4 * sets), np.int64)
    w = np.zeros((v, 4 * sets), np.float64)
    ids[:, :k], w[:, :k] = skin.index, skin.weight
    ids[extra], w[extra] = 0, 0.0
    ids[extra, 0], w[extra, 0] = skin.n_nodes + np.arange(len(extra)), 1.0
    w[w < 0] = 0.0
    ids[w == 0] = 0  # glTF: an unused slot names joint 0
    return ids, (w / w.sum(axis=1, keepdims=True)).astype(np.float32), extra


def _add_animal(b: _Builder, tracks: _Tracks, k: int, animal: Animal) -> None:
    """Add an animal as its display skin (``render.skin``): a skinned mesh whose joints are
    its nodes (and its fins' tips), keyframed at their positions, with vertex colours."""
    nodes = _fill_frames(animal.positions)  # (R, N, 3)
    skin = animal.skin or make_skin(animal.faces, np.nan_to_num(nodes[0]), look_of(animal.name))
    ids, weights, extra = skin_joints(skin)
    pos = to_gltf_axes(np.concatenate([nodes, skin_vertices(skin, nodes)[:, extra]], axis=1))
    n = pos.shape[1]
    rest = pos[0]
    verts = to_gltf_axes(skin_vertices(skin, nodes[0])).astype(np.float32)
    faces = np.asarray(skin.triangles)[:, ::-1]
    itype = np.uint16 if len(verts) < 65535 else np.uint32
    jtype = np.uint8 if n <= 256 else np.uint16
    mat = _material(b, animal.name, [1.0, 1.0, 1.0, 1.0], roughness=0.6)
    colors = np.asarray(skin.colors, np.float32) ** 2.2  # linear, as glTF's colours are
    attrs = {
        "POSITION": b.accessor(verts, "VEC3", _ARRAY, bounds=True),
        "COLOR_0": b.accessor(np.ascontiguousarray(colors), "VEC3", _ARRAY),
    }
    for s in range(ids.shape[1] // 4):
        part = slice(4 * s, 4 * s + 4)
        attrs[f"JOINTS_{s}"] = b.accessor(ids[:, part].astype(jtype), "VEC4", _ARRAY)
        w = np.ascontiguousarray(weights[:, part])
        attrs[f"WEIGHTS_{s}"] = b.accessor(w, "VEC4", _ARRAY)
    idx = b.accessor(faces.astype(itype).ravel(), "SCALAR", _ELEMENTS)
    prim = {"attributes": attrs, "material": mat, "indices": idx}
    mesh = b.add("meshes", {"name": f"{animal.name}-surface", "primitives": [prim]})
    joints = [
        b.node(
            {"name": f"{animal.name}-{k}-node-{i}", "translation": [float(c) for c in rest[i]]},
            root=False,
        )
        for i in range(n)
    ]
    ibm = np.tile(np.eye(4, dtype=np.float32), (n, 1, 1))
    ibm[:, 3, :3] = -rest  # column-major: the translation is the last column
    gskin = b.add(
        "skins",
        {"name": animal.name, "joints": joints, "inverseBindMatrices": b.accessor(ibm, "MAT4")},
    )
    b.node({"name": f"{animal.name}-{k}", "children": joints})
    b.node({"name": f"{animal.name}-{k}-surface", "mesh": mesh, "skin": gskin})
    track = np.ascontiguousarray(pos.transpose(1, 0, 2))  # (J, R, 3): joint-major
    view = b.view(track.tobytes())
    for i, joint in enumerate(joints):
        out = b.accessor(track[i], "VEC3", view=view, offset=i * track[i].nbytes)
        tracks.add(joint, "translation", out)


def _add_creature(b: _Builder, tracks: _Tracks, k: int, creature: Creature) -> None:
    """Add a rigid-link creature: one mesh per link, posed per frame."""
    parent = b.node({"name": f"{creature.name}-{k}"})
    kids = []
    for link in creature.links:
        mat = _material(b, link.name, _linear(link.color), roughness=0.6)
        verts = to_gltf_axes(link.vertices)
        faces = np.asarray(link.faces)[:, ::-1].astype(np.uint16).ravel()
        prim = {
            "attributes": {"POSITION": b.accessor(verts, "VEC3", _ARRAY, bounds=True)},
            "indices": b.accessor(faces, "SCALAR", _ELEMENTS),
            "material": mat,
        }
        mesh = b.add("meshes", {"name": link.name, "primitives": [prim]})
        tr = to_gltf_axes(np.nan_to_num(link.translations))
        rot = _quaternions(np.nan_to_num(link.angles), link.axis)
        node = b.node(
            {
                "name": f"{creature.name}-{k}-{link.name}",
                "mesh": mesh,
                "translation": tr[0].tolist(),
                "rotation": rot[0].tolist(),
            },
            root=False,
        )
        kids.append(node)
        tracks.add(node, "translation", b.accessor(np.ascontiguousarray(tr), "VEC3"))
        tracks.add(node, "rotation", b.accessor(np.ascontiguousarray(rot), "VEC4"))
    b.doc["nodes"][parent]["children"] = kids


def _solid(thing: Thing, marker: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the vertices (V, 3) about the object's centre and triangles of its shape."""
    v, f = solid(thing.shape, thing.size, thing.axis, marker)
    return to_gltf_axes(v), np.asarray(f)[:, ::-1].astype(np.uint16)


def _add_objects(b: _Builder, tracks: _Tracks, scene: Scene) -> None:
    """Add every object: a mesh of its shape, moved where it moves, hidden once gone."""
    sizes = [
        float(np.ptp(a.positions[0][np.isfinite(a.positions[0]).all(1)], axis=0).max())
        for a in scene.animals
        if np.isfinite(a.positions[0]).any()
    ]
    marker = 0.08 * max(max(sizes + [0.5]), 0.1)
    materials: dict[str, int] = {}
    for i, thing in enumerate(scene.objects):
        if thing.kind not in materials:
            rgb, alpha = OBJECT_COLORS.get(thing.kind, ((160, 160, 160), 1.0))
            rgba = _linear(rgb)[:3] + [alpha]
            materials[thing.kind] = _material(b, thing.kind, rgba, blend=alpha < 1)
        if thing.shape == "strand":
            _add_strand(b, tracks, f"{thing.kind}-{i + 1}-{thing.name}", thing, materials)
            continue
        verts, faces = _solid(thing, marker)
        prim = {
            "attributes": {"POSITION": b.accessor(verts, "VEC3", _ARRAY, bounds=True)},
            "indices": b.accessor(faces.ravel(), "SCALAR", _ELEMENTS),
            "material": materials[thing.kind],
        }
        mesh = b.add("meshes", {"name": thing.name, "primitives": [prim]})
        pos = to_gltf_axes(_fill_frames(thing.positions[:, None])[:, 0])
        node = b.node(
            {
                "name": f"{thing.kind}-{i + 1}-{thing.name}",
                "mesh": mesh,
                "translation": [float(c) for c in pos[0]],
            }
        )
        if len(pos) > 1 and len(scene.times) > 1:
            tracks.add(node, "translation", b.accessor(np.ascontiguousarray(pos), "VEC3"))
        if thing.visible is not None and len(scene.times) > 1:
            scale = np.repeat(np.asarray(thing.visible, np.float32)[:, None], 3, axis=1)
            tracks.add(node, "scale", b.accessor(scale, "VEC3"), "STEP")


def _add_strand(b: _Builder, tracks: _Tracks, name: str, thing: Thing, materials: dict) -> None:
    """Add a dynamic plant's strand: a tube of its radius whose rings are skinned, one to a
    joint, to its nodes, keyframed where they were."""
    nodes = to_gltf_axes(_fill_frames(np.asarray(thing.positions, np.float32)))  # (R, M, 3)
    rest, m = nodes[0], nodes.shape[1]
    verts, faces, ring_of = strand_tube(rest, thing.size[0])
    ids = np.zeros((len(verts), 4), np.uint16)
    ids[:, 0] = ring_of
    weights = np.zeros((len(verts), 4), np.float32)
    weights[:, 0] = 1.0
    attrs = {
        "POSITION": b.accessor(verts, "VEC3", _ARRAY, bounds=True),
        "JOINTS_0": b.accessor(ids, "VEC4", _ARRAY),
        "WEIGHTS_0": b.accessor(weights, "VEC4", _ARRAY),
    }
    idx = b.accessor(faces.astype(np.uint32).ravel(), "SCALAR", _ELEMENTS)
    prim = {"attributes": attrs, "material": materials[thing.kind], "indices": idx}
    mesh = b.add("meshes", {"name": thing.name, "primitives": [prim]})
    joints = [
        b.node({"name": f"{name}-node-{n}", "translation": rest[n].tolist()}, root=False)
        for n in range(m)
    ]
    ibm = np.tile(np.eye(4, dtype=np.float32), (m, 1, 1))
    ibm[:, 3, :3] = -rest  # column-major: the translation is the last column
    skin = b.add("skins", {"joints": joints, "inverseBindMatrices": b.accessor(ibm, "MAT4")})
    b.node({"name": f"{name}-nodes", "children": joints})
    b.node({"name": name, "mesh": mesh, "skin": skin})  # the viewer's objects layer
    if len(nodes) > 1:
        for n, joint in enumerate(joints):
            track = np.ascontiguousarray(nodes[:, n])
            tracks.add(joint, "translation", b.accessor(track, "VEC3"))


def _add_environment(b: _Builder, scene: Scene) -> None:
    """Add the ground, the sea floor and the sea surface as quads under the scene."""
    from zoetic.viz import render3d as r3

    levels = environment_levels(scene)
    lo, hi = scene_bounds(scene)
    if "ground" in levels:
        mat = _material(b, "ground", [1, 1, 1, 1], _checker_png(*r3._GROUND))
        _quad(b, "ground", levels["ground"], lo, hi, mat, True)
    if "seabed" in levels:
        mat = _material(b, "sea floor", [1, 1, 1, 1], _checker_png(*r3._SEABED))
        _quad(b, "sea floor", levels["seabed"], lo, hi, mat, True)
    if "surface" in levels:
        rgba = _linear(r3._SURFACE)[:3] + [0.35]
        mat = _material(b, "sea surface", rgba, blend=True, roughness=0.2)
        _quad(b, "sea surface", levels["surface"], lo, hi, mat, False)


def scene_glb(scene: Scene) -> bytes:
    """Return the scene as GLB bytes: skinned animals, rigid creatures and objects animated at
    the scene's frame rate, over the ground or sea floor."""
    b = _Builder()
    tracks = _Tracks(b, np.asarray(scene.times - scene.times[0], np.float32))
    for k, animal in enumerate(scene.animals):
        _add_animal(b, tracks, k, animal)
    for k, creature in enumerate(scene.creatures):
        _add_creature(b, tracks, k, creature)
    _add_objects(b, tracks, scene)
    if len(scene.times) > 1 and tracks.channels:
        b.add(
            "animations", {"name": "run", "channels": tracks.channels, "samplers": tracks.samplers}
        )
    _add_environment(b, scene)
    b.doc["scenes"][0]["name"] = scene.title
    b.doc["scenes"][0]["extras"] = {
        "fps": scene.fps,
        "duration_s": scene.duration,
        "medium": scene.medium.name,
        "kind": scene.kind,
    }
    return b.glb()


def write_glb(scene: Scene, path: str | os.PathLike) -> Path:
    """Write the scene to ``path`` as a .glb (atomically); returns the path."""
    return atomic_write_bytes(path, scene_glb(scene))
