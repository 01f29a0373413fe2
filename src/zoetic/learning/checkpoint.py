"""A learning run's checkpoint file (``checkpoint.npz``): the log of every evaluation and the
optimizer's whole state (``state_dict``), with a SHA-256 checksum over both; the run writes it
atomically and keeps the previous one as ``checkpoint.prev.npz`` (``learning.run``)."""

from __future__ import annotations

import hashlib
import io
import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zoetic.errors import RunDirError


@dataclass
class Log:
    """Every evaluation in order: parameters, E and its parts, wall time; and batch sizes."""

    X: list = field(default_factory=list)
    E: list = field(default_factory=list)
    E_u: list = field(default_factory=list)
    E_v: list = field(default_factory=list)
    wall: list = field(default_factory=list)
    batches: list = field(default_factory=list)
    _lines: list = field(default_factory=list, repr=False, compare=False)  # history.csv's

    def add(self, X, ev, wall: float) -> None:
        """Append a batch: its candidates X (k, n), E, E_u, E_v and the run's wall time (s)."""
        self.X.extend(np.asarray(X))
        self.E.extend(ev.E)
        self.E_u.extend(ev.E_u)
        self.E_v.extend(ev.E_v)
        self.wall.extend([wall] * len(ev.E))
        self.batches.append(len(ev.E))

    def history_csv(self) -> bytes:
        """Return history.csv bytes: per evaluation E, E_u, E_v, best E so far, wall (s).

        Each evaluation's line is formatted once and kept (a run checkpoints every few
        seconds, and formatting the whole history each time grew with its square)."""
        lines = self._lines
        del lines[len(self.E) :]  # a step undone on interruption
        best = min(self.E[: len(lines)], default=np.inf)
        rows = zip(self.E, self.E_u, self.E_v, self.wall, strict=True)
        for i, (e, eu, ev, w) in enumerate(rows):
            if i < len(lines):
                continue
            best = min(best, e)
            lines.append(f"{i + 1},{e:.6g},{eu:.6g},{ev:.6g},{best:.6g},{w:.3f}\n")
        return ("evaluation,E,E_u,E_v,best_E,wall_time\n" + "".join(lines)).encode()


CHECKPOINT = "checkpoint.npz"
PREVIOUS = "checkpoint.prev.npz"
LOG_KEYS = ("X", "E", "E_u", "E_v", "wall", "batches")


def _digest(arrays: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def checkpoint_bytes(log: Log, state: dict, config: dict | None = None) -> bytes:
    """Return the checkpoint file's bytes: the log, the optimizer state, the run's settings
    (to tell an edited config.toml on resume) and their checksum."""
    arrays = {k: np.array(getattr(log, k)) for k in LOG_KEYS}
    if config is not None:
        text = json.dumps(config, sort_keys=True, default=str)
        arrays["config_json"] = np.frombuffer(text.encode(), dtype=np.uint8)
    plain = {}
    for key, value in state.items():
        if isinstance(value, np.ndarray):
            arrays[f"opt.{key}"] = value
        else:
            plain[key] = value
    arrays["opt_json"] = np.frombuffer(json.dumps(plain).encode(), dtype=np.uint8)
    arrays["sha256"] = np.frombuffer(_digest(arrays).encode(), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def saved_config(path: Path) -> dict | None:
    """Return the run settings a (verified) checkpoint was written with, if it holds them."""
    with np.load(path, allow_pickle=False) as z:
        if "config_json" not in z.files:
            return None
        return json.loads(z["config_json"].tobytes().decode())


def edited_keys(saved: dict, now: dict) -> list[str]:
    """Return the settings that differ between a checkpoint's and config.toml's."""
    norm = json.loads(json.dumps(now, sort_keys=True, default=str))
    return sorted(k for k in saved.keys() | norm.keys() if saved.get(k) != norm.get(k))


def keep_previous(path: Path, previous: Path) -> None:
    """Make ``previous`` a copy of ``path`` (if any) while ``path`` stays in place."""
    if not path.exists():
        return
    tmp = previous.with_name(previous.name + ".tmp")
    tmp.unlink(missing_ok=True)
    try:
        os.link(path, tmp)  # a second name for the same bytes: nothing is copied
    except OSError:
        shutil.copyfile(path, tmp)
    os.replace(tmp, previous)


def read_checkpoint(path: Path) -> tuple[Log, dict]:
    """Return the log and optimizer state of a checkpoint; RunDirError if it is damaged."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        if "sha256" not in arrays and "X" in arrays:
            raise RunDirError(
                f"{path}: written by an older zoetic that saved no optimizer state, so it "
                f"cannot be resumed; start afresh with another --out (or delete {path.parent})"
            )
        digest = arrays.pop("sha256").tobytes().decode()
        if digest != _digest(arrays):
            raise ValueError("checksum mismatch")
        arrays.pop("config_json", None)  # read by saved_config
        state = json.loads(arrays.pop("opt_json").tobytes().decode())
        state |= {k[4:]: v for k, v in arrays.items() if k.startswith("opt.")}
        columns = (list(arrays[k]) for k in LOG_KEYS[:-1])
        log = Log(*columns, batches=[int(b) for b in arrays["batches"]])
    except RunDirError:
        raise
    except Exception as exc:  # noqa: BLE001 - any damage reads the same to the user
        prev = path.parent / PREVIOUS
        offer = ""
        if path.name != PREVIOUS and prev.exists():
            offer = f"the previous good checkpoint is {prev}: move it over {path} to resume from "
            offer += "there, "
        raise RunDirError(
            f"{path}: damaged checkpoint ({type(exc).__name__}: {exc}); {offer}or start afresh "
            f"with another --out (or delete {path.parent})"
        ) from None
    return log, state
