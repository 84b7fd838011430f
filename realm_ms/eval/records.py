"""Append-only episode records (``RUN/records.jsonl``, one JSON object per line) and resume.

Each finished episode is one ``write`` of one line on an ``O_APPEND`` descriptor followed by
``fsync``, so a run killed at any moment keeps every finished episode; a line cut by the kill is the
only possible damage and is dropped (that episode simply runs again) when the file is reopened.
A rerun skips keys whose record has ``status`` "ok" or "unsupported"; an "error" record (e.g. the
policy server stayed down) is kept for the report but its episode is retried.

A line that is not a record (not JSON, not UTF-8, not an object, a key field missing or of the
wrong type, a status or a progression out of range) never counts: ``read_records`` skips it and,
given a ``problems`` list, says which line and why, so the caller can report it.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from realm_ms.eval.protocol import EpisodeKey
from realm_ms.validate import InputError

FINISHED = ("ok", "unsupported")
STATUSES = ("ok", "unsupported", "error")


def key_of(rec: dict) -> EpisodeKey:
    return EpisodeKey(rec["task"], rec["perturbation"], int(rec["seed"]))


def robot_model_of(rec: dict) -> str | dict | None:
    """The robot model a record's episode ran: its env config's ``robot_model`` (a named model, a
    MODEL.yaml path as given, or an inline dict; None = the nominal robot). Records written before
    ``realm eval --robot-model`` existed name none (or carry no config): they ran the nominal robot, None."""
    return (rec.get("config") or {}).get("robot_model")


def _complete(raw: bytes) -> bool:
    """``raw`` is one whole JSON value (a last line written without its newline, not a cut one)."""
    try:
        json.loads(raw.decode("utf-8"))
    except ValueError:  # JSONDecodeError and UnicodeDecodeError
        return False
    return True


def _repair(path: Path) -> None:
    """Drop a trailing partial line (a kill during the write): truncate after the last newline. A
    whole last line that only lacks its newline (written by hand) gets one instead."""
    if not path.exists() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        f.seek(0, os.SEEK_END)
        size = f.tell()
        f.seek(max(0, size - 1))
        if f.read(1) == b"\n":
            return
        data = path.read_bytes()
        cut = data.rfind(b"\n") + 1
        if _complete(data[cut:]):
            f.seek(0, os.SEEK_END)
            f.write(b"\n")
        else:
            f.truncate(cut)


def check_record(rec) -> str | None:
    """Why ``rec`` is not a usable episode record, or None. Only what keying, resume and the
    metrics read is checked; further fields are free."""
    if not isinstance(rec, dict):
        return f"not a JSON object (a {type(rec).__name__})"
    for k in ("task", "perturbation"):
        if not isinstance(rec.get(k), str) or not rec[k]:
            return f"`{k}` is {'missing' if k not in rec else repr(rec[k])}; expected a name"
    seed = rec.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        return f"`seed` is {'missing' if 'seed' not in rec else repr(seed)}; expected an integer in [0, 2**32)"
    status = rec.get("status", "ok")
    if status not in STATUSES:
        return f"`status` is {status!r}; expected one of {', '.join(STATUSES)}"
    if status != "ok":
        return None
    if not isinstance(rec.get("success"), bool):
        return f"`success` is {'missing' if 'success' not in rec else repr(rec['success'])}; expected true or false"
    prog = rec.get("progression")
    if isinstance(prog, bool) or not isinstance(prog, (int, float)) or not (math.isfinite(prog) and 0.0 <= prog <= 1.0):
        return f"`progression` is {'missing' if 'progression' not in rec else repr(prog)}; expected a number in [0, 1]"
    steps = rec.get("steps", 0)
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0:
        return f"`steps` is {steps!r}; expected an integer >= 0"
    if not isinstance(rec.get("stages", {}) or {}, dict):
        return f"`stages` is {rec['stages']!r}; expected an object"
    return None


def read_records(path: Path | str, problems: list[str] | None = None) -> list[dict]:
    """All complete, valid records in file order. A line that is not one is skipped and, when
    ``problems`` is given, described there as ``FILE:LINE: why`` (a last line cut by a kill too:
    its episode runs again). A path that is a directory, or unreadable, is an ``InputError``."""
    return [rec for _, rec in numbered_records(path, problems)]


def numbered_records(path: Path | str, problems: list[str] | None = None) -> list[tuple[int, dict]]:
    """``(line number, record)`` of the valid records (see ``read_records``)."""
    path = Path(path)
    if not path.exists():
        return []
    if path.is_dir():
        raise InputError(f"{path} is a directory; the records file must be a file (move it away, or use another --out)")
    try:
        data = path.read_bytes()
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror})") from None
    out = []
    lines = data.split(b"\n")
    cut = lines.pop() if lines else b""  # text after the last newline: a cut write, or a last line without newline
    if cut.strip() and _complete(cut):
        lines.append(cut)
        cut = b""
    for n, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        why = None
        try:
            rec = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError:
            why = "not UTF-8 text"
        except json.JSONDecodeError as e:
            why = f"not valid JSON ({e.msg} at column {e.colno})"
        else:
            why = check_record(rec)
        if why is None:
            out.append((n, rec))
        elif problems is not None:
            problems.append(f"{path}:{n}: {why}")
    if cut.strip() and problems is not None:
        problems.append(f"{path}:{len(lines) + 1}: no newline at the end (a write cut short); the episode runs again")
    return out


def format_problems(problems: list[str], limit: int = 20) -> str:
    """``problems`` for a warning: the first ``limit`` lines, then how many more."""
    shown = problems[:limit]
    more = f"\n  ... and {len(problems) - limit} more unreadable line(s)" if len(problems) > limit else ""
    return "\n".join(f"  {p}" for p in shown) + more


def latest_by_key(records: list[dict]) -> dict[EpisodeKey, dict]:
    """One record per key: the last finished one, else the last error."""
    best: dict[EpisodeKey, dict] = {}
    for r in records:
        k = key_of(r)
        if k not in best or r.get("status", "ok") in FINISHED or best[k].get("status") not in FINISHED:
            best[k] = r
    return best


class RecordWriter:
    def __init__(self, path: Path | str):
        self.path = Path(path)
        if self.path.is_dir():
            raise InputError(f"{self.path} is a directory; the records file must be a file (move it away, or use another --out)")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        _repair(self.path)
        self.fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def finished_keys(self) -> set[EpisodeKey]:
        return {key_of(r) for r in read_records(self.path) if r.get("status", "ok") in FINISHED}

    def append(self, record: dict) -> None:
        line = (json.dumps(record, separators=(",", ":"), default=_default) + "\n").encode()
        written = os.write(self.fd, line)
        while written < len(line):  # short writes are possible on some filesystems
            written += os.write(self.fd, line[written:])
        os.fsync(self.fd)

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def _default(o):
    import numpy as np

    if isinstance(o, np.generic):
        return o.item()
    if hasattr(o, "tolist"):  # arrays, tensors
        return o.tolist()
    return str(o)
