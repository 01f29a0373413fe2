"""What the web viewer's page reads of a run: its glTF in base64, the centre-of-mass paths,
activations, events and figures, built from a Scene (``zoetic.viz.scene``), and, taken from
the record itself, the time plots of its per-period scalars, a search's E history, the
animals' minds (drives and intentions) and what each kind of run draws beside the bodies:
a predator's gaze rays, a stunt's spray."""

from __future__ import annotations

import base64

import numpy as np

from zoetic.record import Record
from zoetic.viz.gltf import scene_glb, to_gltf_axes
from zoetic.viz.scene import Scene

MAX_EVENTS = 2000  # events listed in the page (a long aquarium run has many)
MAX_POINTS = 2000  # samples per plotted scalar: more than a strip chart's pixels
# the motion every record carries (``control.measure``), plotted before the other scalars
FIRST = ("speed", "depth", "height", "heading", "pitch", "roll")
# per-period places in the world (drawn in the scene, not plotted): a predator's eyes and
# their directions, where a stunt's body crossed the surface
PLACES = ("eye_pos", "eye_dirs", "splash_at")
DRIVES = ("hunger", "libido", "fear")  # an aquarium fish's drives, drawn with its intention


def _round(a: np.ndarray, digits: int) -> list:
    return np.round(np.asarray(a, np.float64), digits).ravel().tolist()


def _series(values: np.ndarray) -> list:
    """Return plotted values as a JSON list: rounded, with null where not finite."""
    v = np.round(np.asarray(values, np.float64), 4).ravel()
    return [float(x) if np.isfinite(x) else None for x in v]


def plots_data(rec: Record) -> dict:
    """Return the record's numeric per-period scalars for the page's time plots: the period
    times (s from the record's start), each quantity's unit, and per animal its series (one
    per column of a quantity with several); integer-coded ones (an intention) are left to
    the labelled states."""
    periods = np.asarray(rec.period_times, float)
    if not len(periods) or not rec.scalars:
        return {}
    keep = np.arange(0, len(periods), int(np.ceil(len(periods) / MAX_POINTS)))
    order = {q: i for i, q in enumerate(FIRST)}
    animals: dict = {}
    for who, quantities in rec.scalars.items():
        series: dict = {}
        for what in sorted(quantities, key=lambda q: (order.get(q, len(FIRST)), q)):
            values = np.asarray(quantities[what])
            if what in rec.labels or what in PLACES or values.ndim > 2:
                continue
            if values.ndim == 1:
                series[what] = _series(values[keep])
            else:
                for j in range(values.shape[1]):
                    series[f"{what} {j + 1}"] = _series(values[keep, j])
        if series:
            animals[who] = series
    if not animals:
        return {}
    return {
        "times": _round(periods[keep] - float(rec.times[0]), 4),
        "units": {k: str(v) for k, v in rec.units.items()},
        "animals": animals,
    }


def history_data(rec: Record) -> dict:
    """Return a search's progress for the page's E plot: per evaluation (thinned to at most
    MAX_POINTS, the last kept) each recorded quantity (E, best_E), null where not finite."""
    if not rec.history:
        return {}
    n = max(len(v) for v in rec.history.values())
    keep = np.unique(np.r_[np.arange(0, n, int(np.ceil(n / MAX_POINTS))), n - 1])
    return {
        "evaluations": (keep + 1).tolist(),
        "series": {what: _series(np.asarray(v)[keep]) for what, v in rec.history.items()},
    }


def mind_data(rec: Record, plots: dict) -> dict:
    """Return each animal's mind over the run at the time plots' periods: its labelled state
    (an intention's index into ``labels``) and its drives (0..1), for the page's mind chart."""
    periods = np.asarray(rec.period_times, float)
    if not plots or "intention" not in rec.labels:
        return {}
    keep = np.arange(0, len(periods), int(np.ceil(len(periods) / MAX_POINTS)))
    animals = {}
    for who, q in rec.scalars.items():
        if "intention" not in q:
            continue
        codes = np.nan_to_num(np.asarray(q["intention"])[keep], nan=-1).astype(int)
        drives = {d: _series(np.asarray(q[d])[keep]) for d in DRIVES if d in q}
        animals[who] = {"intention": codes.tolist(), "drives": drives}
    return {"labels": list(rec.labels["intention"]), "animals": animals} if animals else {}


def gaze_data(rec: Record, scene: Scene) -> list:
    """Return each animal's gaze rays per frame of the scene, in glTF axes: per animal with
    eyes (a predator's ``eye_pos`` and ``eye_dirs``) its name and, flat per frame, both
    eyes' start and end points (R x 2 x 2 x 3 m; null where not finite)."""
    from zoetic.viz.gaze import gaze_ends
    from zoetic.viz.scene import period_index

    out = []
    k = period_index(rec, scene.times + float(rec.times[0]))
    for who, q in rec.scalars.items():
        if "eye_pos" not in q or "eye_dirs" not in q or not len(k):
            continue
        pos = np.asarray(q["eye_pos"], float)[k]
        far = np.full(len(pos), np.inf) if "range" not in q else np.asarray(q["range"])[k]
        rays = np.stack([pos, gaze_ends(pos, np.asarray(q["eye_dirs"])[k], far)], axis=2)
        out.append({"name": who, "rays": _series(to_gltf_axes(rays))})
    return out


def splash_data(rec: Record, scene: Scene) -> dict:
    """Return a stunt's spray for the page: each drop's launch time (s from the record's
    start), point and velocity (glTF axes), thrown by the spray model of the stunt videos
    (``viz.spray``) from the surface crossings recorded (``splash``, ``splash_at``)."""
    from zoetic.viz.spray import Splash, spray_launches

    times, points, flux = [], [], []
    periods = np.asarray(rec.period_times, float)
    step = np.diff(periods, append=periods[-1:])  # to the next instant: the crossings' midst
    for q in rec.scalars.values():
        if "splash" not in q or "splash_at" not in q:
            continue
        f = np.nan_to_num(np.asarray(q["splash"], float))
        rows = np.nonzero(f > 0)[0]
        times.append(periods[rows] + 0.5 * step[rows] - rec.times[0])
        points.append(np.asarray(q["splash_at"], float)[rows])
        flux.append(f[rows])
    if not times or not sum(len(t) for t in times):
        return {}
    t0, p0, v0 = spray_launches(
        Splash(np.concatenate(times), np.concatenate(points), np.concatenate(flux))
    )
    return {
        "t0": _round(t0, 4),
        "p0": _round(to_gltf_axes(p0), 4),
        "v0": _round(to_gltf_axes(v0), 4),
        "gravity": float(scene.medium.gravity),
        "level": float(scene.medium.water_level),
    }


def viewer_data(scene: Scene, rec: Record | None = None) -> dict:
    """Return what the page's script reads: the .glb in base64, the run's figures, events,
    and (given the record the scene came from) the time plots of its scalars, its search
    history, its animals' minds, gaze rays and spray (``_record_data``)."""
    if scene.animals:
        first = scene.animals[0].positions[0]
    else:  # rigid links: their frames' origins and far ends
        first = np.concatenate(
            [
                [ln.translations[0], ln.translations[0] + ln.vertices.max(0)]
                for ln in scene.creatures[0].links
            ]
        )
    first = first[np.isfinite(first).all(axis=1)]
    extent = float(np.linalg.norm(first - first.mean(0), axis=1).max()) if len(first) else 1.0
    sea = abs(scene.medium.water_level) < 1e8
    side_view = any(ln.axis == "z" for c in scene.creatures for ln in c.links)  # planar SANs
    events = sorted(scene.events, key=lambda e: e.t)[:MAX_EVENTS]
    numbers = {k: v for k, v in scene.numbers.items() if k != "distance_m"}
    if "distance_m" in scene.numbers:
        numbers["final distance (m)"] = scene.numbers["distance_m"]
    return {
        "title": scene.title,
        "kind": scene.kind,
        "medium": scene.medium.name,
        "fps": scene.fps,
        "frames": len(scene.times),
        "duration": scene.duration,
        "extent": max(extent, 0.05),
        "elevation": 12.0 if sea else 25.0,
        "numbers": numbers,
        "azimuth": 80.0 if side_view else 40.0,
        "animals": [
            {
                "name": a.name,
                "com": _round(to_gltf_axes(np.nan_to_num(a.com)), 4),
                "actuators": list(a.actuators),
                "activations": None if a.activations is None else _round(a.activations, 3),
            }
            for a in scene.movers
        ],
        "objects": [{"kind": o.kind, "name": o.name} for o in scene.objects],
        "states": scene.states,
        "events": [[round(e.t, 3), e.who, e.what, e.detail] for e in events],
        **({} if rec is None else _record_data(rec, scene)),
        "glb": base64.b64encode(scene_glb(scene)).decode("ascii"),
    }


def _record_data(rec: Record, scene: Scene) -> dict:
    """Return what the page draws from the record itself beside the scene."""
    plots = plots_data(rec)
    return {
        "plots": plots,
        "history": history_data(rec),
        "mind": mind_data(rec, plots),
        "gaze": gaze_data(rec, scene),
        "splash": splash_data(rec, scene),
    }
