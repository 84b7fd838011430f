"""Atomic file writes: a reader (or a resumed run) sees the old file or the new one, never half
of one, whatever kills the writer.

Each writes ``NAME.<pid>.tmp`` beside the target and renames it over the target (``os.replace``
is atomic on one file system); the pid keeps processes that write the same file (a cache shared
by workers) off each other's temporary file. Missing parent directories are created.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any


def _write(path: str | os.PathLike, mode: str, fill: Callable[[IO], Any]) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, mode) as f:
            fill(f)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_text(path: str | os.PathLike, text: str) -> Path:
    return _write(path, "w", lambda f: f.write(text))


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    return _write(path, "wb", lambda f: f.write(data))


def write_json(path: str | os.PathLike, obj: Any, **dumps: Any) -> Path:
    """``obj`` as JSON; ``dumps``: ``json.dumps`` options (``indent=2``, ``default=float``)."""
    return write_text(path, json.dumps(obj, **dumps))


def write_npz(path: str | os.PathLike, **arrays: Any) -> Path:
    """``numpy.savez`` (written through a file object, so no ``.npz`` is appended to the name)."""
    import numpy as np

    return _write(path, "wb", lambda f: np.savez(f, **arrays))
