"""File I/O for every zoetic format: atomic writes, and the strict reader.

Writing: atomic (temporary file and rename), JSON and TOML.

Reading: every file format (animals, creatures, controllers, networks, repertoires, run
configurations) goes through the same reader. It reads a file safely (size limit, UTF-8 only
with a clear message for binary or UTF-16 files, a limit on nesting so a hostile file cannot
exhaust the stack), then offers typed access to its tables: unknown keys are refused with a
"did you mean" suggestion, numbers must be finite, counts and sizes are checked against
:data:`LIMITS` *before* anything is allocated, and every message names the file and the
entry, abbreviates long values, and says what to do. Errors are of the caller's
:class:`~zoetic.errors.ZoeticError` subclass.
"""

from __future__ import annotations

import difflib
import json
import math
import os
import re
import tempfile
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

from zoetic.errors import ZoeticError


def make_dir(path: str | os.PathLike) -> Path:
    """Create the directory ``path`` (and its parents); a ZoeticError if it cannot be made."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise ZoeticError(f"{path}: exists and is not a directory; choose another --out") from None
    except OSError as exc:
        raise ZoeticError(
            f"{path}: cannot create the directory ({exc.strerror or exc}); choose another --out"
        ) from None
    return path


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and a rename; returns the path."""
    path = Path(path)
    make_dir(path.parent)
    if path.is_dir():
        raise ZoeticError(f"{path}: is a directory, so it cannot be written as a file")
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    except OSError as exc:
        raise ZoeticError(f"{path}: cannot write ({exc.strerror or exc})") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Write ``obj`` as indented JSON, atomically; returns the path."""
    return atomic_write_bytes(path, (json.dumps(obj, indent=2) + "\n").encode())


def write_toml(path: str | os.PathLike, obj: dict[str, Any]) -> Path:
    """Write ``obj`` as TOML, atomically; returns the path."""
    return atomic_write_bytes(path, tomli_w.dumps(obj).encode())


def read_json(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> Any:
    """Return the parsed JSON in ``path``, read safely (:func:`load_json`)."""
    return load_json(path, what, error)


def read_toml(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> dict[str, Any]:
    """Return the parsed TOML in ``path``, read safely (:func:`load_toml`)."""
    return load_toml(path, what, error)


# ============================================================================ the strict reader


@dataclass(frozen=True)
class Limits:
    """What a file may ask of zoetic; each bound keeps memory under ~1 GB and time short."""

    file_bytes: int = 16 * 2**20  # a file larger than this is refused unread
    depth: int = 24  # nesting of tables, lists and controllers
    list_items: int = 200_000  # items in any one list of a file
    nodes: int = 10_000  # animal nodes
    springs: int = 100_000  # animal springs
    actuators: int = 1_000  # actuators (animals, creatures, controllers)
    links: int = 1_000  # creature links, joints and sensors each
    controller_nodes: int = 100_000  # values per actuator of a controller (M)
    seconds: float = 86_400.0  # any duration or horizon (s)
    min_dt: float = 1e-6  # smallest time step (s)
    steps: int = 20_000_000  # time steps of one simulation (seconds / dt)
    memory_bytes: int = 2**30  # what one command may allocate for its arrays


LIMITS = Limits()


def abbrev(value: Any, limit: int = 60) -> str:
    """Return repr(value) cut to about ``limit`` characters (long lists say how long they are)."""
    if isinstance(value, list | tuple) and len(value) > 6:
        head = ", ".join(abbrev(v, 16) for v in value[:3])
        text = f"[{head}, ... ({len(value)} items)]"
    elif isinstance(value, dict) and len(value) > 6:
        keys = ", ".join(repr(k)[:16] for k in list(value)[:3])
        text = "{" + keys + f", ... ({len(value)} keys)}}"
    else:
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 4] + " ..."


def suggest(key: str, allowed: Iterable[str]) -> str:
    """Return " (did you mean 'x'?)" for the closest allowed key, or ""."""
    close = difflib.get_close_matches(str(key), list(allowed), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


# ----------------------------------------------------------------------------- files


def is_path(text: str) -> bool:
    """True if ``text`` is written as a path (a slash, a suffix, or ``.``), not a zoo name.

    A bare name like ``shark`` always means the zoo entry, even when the working directory
    holds a folder or file of that name; ``./shark`` or ``shark.toml`` means the file.
    """
    return "/" in text or os.sep in text or Path(text).suffix != "" or text.startswith(".")


def read_text(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> str:
    """Return the UTF-8 text of ``path``; missing, huge, binary or UTF-16 files are ``error``."""
    path = Path(path)
    try:
        if path.is_dir():
            raise error(f"{path}: is a directory, not a {what}")
        size = path.stat().st_size
        if size > LIMITS.file_bytes:
            raise error(
                f"{path}: {size / 2**20:.1f} MB is too large for a {what} (at most "
                f"{LIMITS.file_bytes // 2**20} MB); is it the right file?"
            )
        data = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror or exc})") from None
    if data[:2] in (b"\xff\xfe", b"\xfe\xff") or data[:4] in (b"\x00\x00\xfe\xff",):
        raise error(f"{path}: the {what} is UTF-16/32 text; save it as UTF-8")
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]  # a UTF-8 byte-order mark is harmless
    if b"\x00" in data:
        raise error(f"{path}: the {what} is binary (it holds NUL bytes), not text")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(
            f"{path}: the {what} is not UTF-8 text (byte {exc.start}); save it as UTF-8"
        ) from None


def check_depth(obj: Any, where: str, error=ZoeticError, limit: int | None = None) -> None:
    """Raise ``error`` when lists and tables nest deeper than ``limit``, or a list is huge."""
    limit = LIMITS.depth if limit is None else limit
    stack = [(obj, 0)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            raise error(f"{where}: nested more than {limit} levels deep; is the file damaged?")
        if isinstance(item, dict):
            stack.extend((v, depth + 1) for v in item.values())
        elif isinstance(item, list):
            if len(item) > LIMITS.list_items:
                raise error(
                    f"{where}: a list of {len(item)} items (at most {LIMITS.list_items}): "
                    f"{abbrev(item)}"
                )
            stack.extend((v, depth + 1) for v in item if isinstance(v, list | dict))


# what a string or comment looks like, so that brackets inside one are not counted
_QUOTED = {
    "JSON": re.compile(r'"(?:[^"\\]|\\.)*"'),
    "TOML": re.compile(
        r'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*'
    ),
}
_BRACKETS = re.compile(r"[^\[\]{}]+")


def text_depth(text: str, fmt: str = "JSON") -> int:
    """Return how deep the brackets and braces of a JSON or TOML text nest (outside strings and
    comments), counted without parsing, so that a parser's recursion is never reached."""
    marks = _BRACKETS.sub("", _QUOTED[fmt].sub("", text)).encode()
    if not marks:
        return 0
    codes = np.frombuffer(marks, np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1)
    return int(np.cumsum(steps).max())


def _load(path, what: str, error, loads, invalid: type[Exception], fmt: str) -> Any:
    """Return ``loads`` of the text in ``path`` (read safely), nesting checked before and after
    parsing; errors name it."""
    text = read_text(path, what, error)
    if text_depth(text, fmt) > LIMITS.depth + 2:  # a TOML [[header]] adds two for a moment
        raise error(f"{path}: nested more than {LIMITS.depth} levels deep; is the {what} damaged?")
    try:
        doc = loads(text)
    except invalid as exc:
        raise error(f"{path}: not valid {fmt} ({exc}); fix the {what}") from None
    except (RecursionError, MemoryError):
        raise error(f"{path}: the {what} nests too deeply or is too large to read") from None
    check_depth(doc, str(path), error)
    return doc


def load_toml(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> dict[str, Any]:
    """Return the parsed TOML in ``path``, read safely (see :func:`read_text`)."""
    return _load(path, what, error, tomllib.loads, tomllib.TOMLDecodeError, "TOML")


def load_json(path: str | os.PathLike, what: str = "file", error=ZoeticError) -> Any:
    """Return the parsed JSON in ``path``, read safely (see :func:`read_text`)."""
    return _load(path, what, error, json.loads, json.JSONDecodeError, "JSON")


# ----------------------------------------------------------------------------- values


class Table:
    """Typed, strict access to one table of a file; errors name ``where`` (file: entry).

    Every key read is remembered; :meth:`finish` refuses the keys nobody read, suggesting the
    closest known one. ``known`` lists keys that are accepted without being read.
    """

    def __init__(self, data: Any, where: str, error=ZoeticError, known: Iterable[str] = ()):
        if not isinstance(data, dict):
            raise error(f"{where}: must be a table, got {abbrev(data)}")
        self.data, self.where, self.error = data, where, error
        self.used: set[str] = set(known)

    def fail(self, problem: str) -> ZoeticError:
        """Return (not raise) an ``error`` for ``problem``, prefixed with ``where``."""
        return self.error(f"{self.where}: {problem}")

    def __contains__(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = ...) -> Any:
        """Return ``key``'s value unchecked, marking it read; missing, no default: error."""
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                near = suggest(key, [k for k in self.data if k not in self.used])
                found = f" (found {near[15:-2]}: misspelled?)" if near else ""
                raise self.fail(f"missing {key!r}{found}; add it")
            return default
        return self.data[key]

    def number(
        self,
        key: str,
        default: Any = ...,
        lo: float | None = None,
        hi: float | None = None,
        positive: bool = False,
    ) -> float:
        """Return ``key`` as a finite float in [lo, hi]; a non-number default as is."""
        value = self.raw(key, default)
        if value is default and default is not ... and not isinstance(default, int | float):
            return value
        return number(value, f"{self.where}: {key}", self.error, lo, hi, positive)

    def integer(
        self, key: str, default: Any = ..., lo: int | None = None, hi: int | None = None
    ) -> int:
        """Return ``key`` as an int in [lo, hi]; a non-int default as is."""
        value = self.raw(key, default)
        if value is default and default is not ... and not isinstance(default, int):
            return value
        return integer(value, f"{self.where}: {key}", self.error, lo, hi)

    def string(self, key: str, default: Any = ..., choices: Iterable[str] | None = None) -> str:
        """Return ``key`` as a non-empty string (one of ``choices``); a non-str default as is."""
        value = self.raw(key, default)
        if value is default and default is not ... and not isinstance(default, str):
            return value
        return string(value, f"{self.where}: {key}", self.error, choices)

    def boolean(self, key: str, default: Any = ...) -> bool:
        """Return ``key`` as a bool: true or false only, else error."""
        value = self.raw(key, default)
        if not isinstance(value, bool):
            raise self.fail(f"{key!r} must be true or false, got {abbrev(value)}")
        return value

    def table(self, key: str, known: Iterable[str] = ()) -> Table:
        """Return the sub-table at ``key`` (empty if absent) as a Table naming it."""
        value = self.raw(key, {})
        return Table(value, f"{self.where}: [{key}]" if self.where else key, self.error, known)

    def tables(self, key: str, limit: int | None = None) -> list[dict]:
        """Return the [[key]] array of tables (empty if absent), at most ``limit``."""
        value = self.raw(key, [])
        if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
            raise self.fail(f"{key!r} must be an array of tables ([[{key}]]), got {abbrev(value)}")
        if limit is not None and len(value) > limit:
            raise self.fail(f"{len(value)} [[{key}]] entries is too many (at most {limit})")
        return value

    def numbers(
        self, key: str, default: Any = ..., size: int | None = None, limit: int | None = None
    ) -> list[float]:
        """Return ``key`` as finite floats (exactly ``size``, at most ``limit``)."""
        value = self.raw(key, default)
        if value is default and default is not ... and not isinstance(default, list):
            return value
        return numbers(value, f"{self.where}: {key}", self.error, size, limit)

    def finish(self) -> None:
        """Refuse keys that were never read (misspellings), with a suggestion."""
        check_keys(self.data, self.used, self.where, self.error)


def check_keys(data: dict, allowed: Iterable[str], where: str, error=ZoeticError) -> None:
    """Refuse keys of ``data`` not in ``allowed``, naming the closest allowed key."""
    allowed = set(allowed)
    extra = [k for k in data if k not in allowed]
    if extra:
        key = extra[0]
        more = f" (and {len(extra) - 1} more)" if len(extra) > 1 else ""
        raise error(
            f"{where}: unknown key {abbrev(key, 40)}{suggest(key, allowed)}{more}; "
            f"known keys: {', '.join(sorted(allowed))}"
        )


def number(
    value: Any,
    where: str,
    error=ZoeticError,
    lo: float | None = None,
    hi: float | None = None,
    positive: bool = False,
) -> float:
    """Return ``value`` as a finite float in [lo, hi] (> 0 if ``positive``), else ``error``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise error(f"{where} must be a number, got {abbrev(value)}")
    try:
        v = float(value)
    except OverflowError:
        raise error(f"{where} is too large ({abbrev(value)})") from None
    if not math.isfinite(v):
        raise error(f"{where} is a non-finite number ({v}); give a finite one")
    if positive and not v > 0:
        raise error(f"{where} must be positive, got {v:g}")
    if lo is not None and v < lo:
        raise error(f"{where} must be at least {lo:g}, got {v:g}")
    if hi is not None and v > hi:
        raise error(f"{where} must be at most {hi:g}, got {v:g}")
    return v


def integer(
    value: Any, where: str, error=ZoeticError, lo: int | None = None, hi: int | None = None
) -> int:
    """Return ``value`` as an int in [lo, hi] (a float with no fraction is accepted)."""
    if isinstance(value, float) and math.isfinite(value) and value == int(value):
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise error(f"{where} must be a whole number, got {abbrev(value)}")
    if lo is not None and value < lo:
        raise error(f"{where} must be at least {lo}, got {value}")
    if hi is not None and value > hi:
        raise error(f"{where} must be at most {hi}, got {abbrev(value)}")
    return value


def string(value: Any, where: str, error=ZoeticError, choices: Iterable[str] | None = None) -> str:
    """Return ``value`` if it is a non-empty string (one of ``choices`` when given)."""
    if not isinstance(value, str) or not value:
        raise error(f"{where} must be a non-empty string, got {abbrev(value)}")
    if choices is not None:
        choices = tuple(choices)
        if value not in choices:
            raise error(
                f"{where}: unknown value {abbrev(value, 40)}{suggest(value, choices)} "
                f"(choose from {', '.join(choices)})"
            )
    return value


def numbers(
    value: Any, where: str, error=ZoeticError, size: int | None = None, limit: int | None = None
) -> list[float]:
    """Return a list of finite floats (exactly ``size`` of them, at most ``limit``)."""
    if not isinstance(value, list | tuple):
        raise error(f"{where} must be a list of numbers, got {abbrev(value)}")
    limit = LIMITS.list_items if limit is None else limit
    if len(value) > limit:
        raise error(f"{where} holds {len(value)} values (at most {limit}): {abbrev(value)}")
    if size is not None and len(value) != size:
        raise error(f"{where} must hold {size} numbers, got {len(value)}: {abbrev(value)}")
    return [number(v, f"{where}[{i}]", error) for i, v in enumerate(value)]


def matrix(
    value: Any,
    where: str,
    error=ZoeticError,
    rows: int | None = None,
    cols: int | None = None,
    limit: int | None = None,
) -> list[list[float]]:
    """Return a rectangular list of lists of finite floats (with the given shape)."""
    if not isinstance(value, list) or not all(isinstance(r, list) for r in value):
        raise error(f"{where} must be a list of rows (lists of numbers), got {abbrev(value)}")
    if rows is not None and len(value) != rows:
        raise error(f"{where} must have {rows} rows (one per actuator), got {len(value)}")
    widths = {len(r) for r in value}
    if len(widths) > 1:
        raise error(f"{where}: rows differ in length ({sorted(widths)[:4]})")
    width = widths.pop() if widths else 0
    if cols is not None and width != cols:
        raise error(f"{where}: rows must hold {cols} numbers, got {width}")
    limit = LIMITS.list_items if limit is None else limit
    if len(value) * width > limit:
        raise error(f"{where} holds {len(value)} x {width} values (at most {limit})")
    return [numbers(r, f"{where}[{i}]", error) for i, r in enumerate(value)]


def check_steps(seconds: float, dt: float, where: str, error=ZoeticError) -> int:
    """Return the number of steps of ``seconds`` at ``dt``, refusing runs beyond the limits."""
    if not dt >= LIMITS.min_dt:
        raise error(f"{where}: time step {dt:g} s is below the smallest ({LIMITS.min_dt:g} s)")
    if not 0 < seconds <= LIMITS.seconds:
        raise error(f"{where}: duration {seconds:g} s must be in (0, {LIMITS.seconds:g}]")
    steps = int(math.ceil(seconds / dt - 1e-9))
    if steps > LIMITS.steps:
        raise error(
            f"{where}: {seconds:g} s at dt = {dt:g} s is {steps:,} steps (at most "
            f"{LIMITS.steps:,}); use a shorter time or a larger dt"
        )
    return steps


def check_memory(
    nbytes: float,
    what: str,
    error=ZoeticError,
    fix: str = "use a shorter time, a larger dt or fewer nodes",
) -> None:
    """Refuse work whose arrays would take more than ``LIMITS.memory_bytes``."""
    if nbytes > LIMITS.memory_bytes:
        raise error(
            f"{what} would need {nbytes / 2**30:.1f} GB of memory (at most "
            f"{LIMITS.memory_bytes / 2**30:.0f} GB); {fix}"
        )
