"""Append-only episode records (``RUN/records.jsonl``, one JSON object per line) and resume.

Each finished episode is one ``write`` of one line on an ``O_APPEND`` descriptor followed by
``fsync``, so a run killed at any moment keeps every finished episode; a line cut by the kill is the
only possible damage and is dropped (that episode simply runs again) when the file is reopened.
A rerun skips keys whose record has ``status`` "ok" or "unsupported"; an "error" record (e.g. the
policy server stayed down) is kept for the report but its episode is retried.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from realm_ms.eval.protocol import EpisodeKey

FINISHED = ("ok", "unsupported")


def key_of(rec: dict) -> EpisodeKey:
    return EpisodeKey(rec["task"], rec["perturbation"], int(rec["seed"]))


def _repair(path: Path) -> None:
    """Drop a trailing partial line (a kill during the write): truncate after the last newline."""
    if not path.exists() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        f.seek(0, os.SEEK_END)
        size = f.tell()
        f.seek(max(0, size - 1))
        if f.read(1) == b"\n":
            return
        data = path.read_bytes()
        f.truncate(data.rfind(b"\n") + 1)


def read_records(path: Path | str) -> list[dict]:
    """All complete, parseable records in file order (a damaged line is skipped)."""
    path = Path(path)
    out = []
    if not path.exists():
        return out
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line:
            continue
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


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
    try:
        import numpy as np

        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
    except ImportError:
        pass
    if hasattr(o, "tolist"):
        return o.tolist()
    return str(o)
