"""Reusable checks of user input: every rejection is one line naming the flag, field or file.

Two forms of each check, so the command line, the Python API and config files reject the same
things with the same words (``docs/validation.md`` lists what is rejected):

* value checks (``check_positive(x, "--segment", "s")``) raise :class:`InputError` (a
  ``UserError`` and a ``ValueError``); ``realm`` prints it as ``realm VERB: error: ...`` and exits
  with code 2;
* argparse types (``type=positive("s")``) reject a flag while parsing (argparse: exit code 2).

Numbers: NaN and infinities are always rejected; ``positive`` means > 0, ``non-negative`` >= 0.
Output paths are checked *before* long work starts (an existing directory where a file is wanted,
a parent that is a file, an unwritable directory).
"""

from __future__ import annotations

import argparse
import math
import os
import re
from pathlib import Path
from typing import Any, Callable

from realm_ms.errors import InputError  # noqa: F401  (the checks' error; importers take it from here)


def _units(unit: str) -> str:
    return f" {unit}" if unit else ""


def check_number(value: Any, where: str, unit: str = "", *, minimum: float | None = None,
                 inclusive: bool = True, maximum: float | None = None) -> float:
    """A finite real number (not bool, not an array), optionally bounded below/above."""
    if isinstance(value, bool):
        raise InputError(f"{where}: expected a number{_units(unit)}, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        shape = getattr(value, "shape", None)
        got = f"an array of shape {tuple(shape)}" if shape is not None else repr(value)
        raise InputError(f"{where}: expected a single number{_units(unit)}, got {got}") from None
    if not math.isfinite(x):
        raise InputError(f"{where}: must be a finite number{_units(unit)}, got {value!r}")
    if minimum is not None and (x < minimum or (not inclusive and x == minimum)):
        rel = ">=" if inclusive else ">"
        raise InputError(f"{where}: must be {rel} {minimum:g}{_units(unit)}, got {x:g}")
    if maximum is not None and x > maximum:
        raise InputError(f"{where}: must be <= {maximum:g}{_units(unit)}, got {x:g}")
    return x


def check_positive(value: Any, where: str, unit: str = "") -> float:
    """A finite number > 0."""
    return check_number(value, where, unit, minimum=0.0, inclusive=False)


def check_non_negative(value: Any, where: str, unit: str = "") -> float:
    """A finite number >= 0."""
    return check_number(value, where, unit, minimum=0.0)


def check_int(value: Any, where: str, minimum: int = 1, maximum: int | None = None) -> int:
    """An integer >= ``minimum`` (a float is accepted only when it is whole)."""
    if isinstance(value, bool):
        raise InputError(f"{where}: expected an integer, got {value!r}")
    try:
        x = float(value)
        ok = math.isfinite(x) and x == int(x)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise InputError(f"{where}: expected an integer, got {value!r}")
    n = int(x)
    if n < minimum:
        raise InputError(f"{where}: must be >= {minimum}, got {n}")
    if maximum is not None and n > maximum:
        raise InputError(f"{where}: must be <= {maximum}, got {n}")
    return n


SEED_LIMIT = 2**32  # numpy / torch / SAPIEN seeds: integers in [0, 2**32)


def check_seed(value: Any, where: str, count: int = 1) -> int:
    """A seed in [0, 2**32); with ``count`` > 1, the seeds ``value .. value + count - 1`` must all be."""
    if isinstance(value, str):
        value = value.strip()
    try:
        n = check_int(value, where, 0, SEED_LIMIT - 1)
    except InputError as e:
        raise InputError(f"{e} (a seed is an integer in [0, 2**32))") from None
    if count > 1 and n + count - 1 >= SEED_LIMIT:
        raise InputError(f"{where}: seeds {n}..{n + count - 1} go past 2**32 - 1; use a smaller seed")
    return n


def check_port(value: Any, where: str) -> int:
    """A TCP port, 1..65535."""
    try:
        return check_int(value, where, 1, 65535)
    except InputError as e:
        raise InputError(f"{e} (a TCP port is 1..65535)") from None


def output_arg(parser, path: str | os.PathLike, flag: str = "--out", example: str | None = None) -> Path:
    """``check_output_path`` for a command-line file argument, before the run: a bad path ends the
    command with argparse's usage line and the reason (exit status 2), not a traceback hours later."""
    try:
        return check_output_path(path, flag, "file", example=example)
    except InputError as e:
        parser.error(str(e))


def check_output_path(path: str | os.PathLike, where: str, kind: str = "file", example: str | None = None) -> Path:
    """An output path that can be written, checked before any work: ``kind="file"`` (not an
    existing directory) or ``kind="dir"`` (not an existing file); a path below a file, or in a
    directory that cannot be written into, is rejected too. One line naming ``where``; ``example``
    is a file name suggested when a directory is given for a file."""
    if kind not in ("file", "dir"):
        raise ValueError(f"check_output_path: kind must be 'file' or 'dir', got {kind!r}")
    p = Path(path)
    if str(path) == "" or (kind == "file" and p.name in ("", ".", "..")):
        raise InputError(f"{where}: {str(path)!r} is not a {'file' if kind == 'file' else 'directory'} name")
    if kind == "file":
        if p.is_dir():
            hint = f" (e.g. {p / example})" if example else ""
            raise InputError(f"{where}: {p} is a directory; give a file path{hint}")
        if p.exists() and not p.is_file():
            raise InputError(f"{where}: {p} exists and is not a regular file")
        if p.exists() and not os.access(p, os.W_OK):
            raise InputError(f"{where}: {p} exists and is not writable")
        _check_parent(p, where)
        return p
    if p.exists() and not p.is_dir():
        raise InputError(f"{where}: {p} exists and is a file; give a directory")
    if p.is_dir():
        _check_writable_dir(p, p, where)
        return p
    _check_parent(p, where)
    return p


def check_output_file(path: str | os.PathLike, where: str) -> Path:
    """A file path that can be written: not an existing directory, and its parent is (or can be
    made) a writable directory. Checked before long work, so a run never fails at its end."""
    return check_output_path(path, where, "file")


def check_output_dir(path: str | os.PathLike, where: str) -> Path:
    """A directory that can be created or written into (not an existing file)."""
    return check_output_path(path, where, "dir")


def _check_parent(p: Path, where: str) -> None:
    parent = p.absolute().parent
    while not parent.exists() and not parent.is_symlink():  # the nearest existing ancestor decides
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"{where}: cannot create {p}: {parent} is {'a file' if parent.is_file() else 'not a directory'}")
    _check_writable_dir(parent, p, where)


def _check_writable_dir(d: Path, p: Path, where: str) -> None:
    """``d`` accepts new files: the permission bits, then a real probe (root passes ``os.access``
    even on read-only or virtual file systems such as /sys)."""
    what = f"directory {d} is not writable" if d == p else f"cannot write {p}: directory {d} is not writable"
    if not os.access(d, os.W_OK | os.X_OK):
        raise InputError(f"{where}: {what}")
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".realm-write-probe-", dir=d)
    except OSError as e:
        raise InputError(f"{where}: {what} ({e.strerror})") from None
    os.close(fd)
    os.unlink(probe)


# ---------------------------------------------------------------------------- argparse types
def _argtype(check: Callable[[str], Any], name: str) -> Callable[[str], Any]:
    def parse(text: str):
        try:
            return check(text)
        except InputError as e:  # argparse prefixes "argument --flag: "
            raise argparse.ArgumentTypeError(str(e).split(": ", 1)[1]) from None

    parse.__name__ = name  # argparse uses it in "invalid <name> value"
    return parse


def check_device(device: str, where: str = "device (--device)") -> str:
    """A torch device a command can use: ``cpu``, or ``cuda``/``cuda:N`` where a CUDA GPU exists
    (checked up front: otherwise a run fails in its driver's traceback after hours of work)."""
    text = str(device)
    if text != "cpu" and not re.fullmatch(r"cuda(:\d+)?", text):
        raise InputError(f"{where}: unknown device {device!r}; use cpu or cuda")
    if text.startswith("cuda"):
        import torch

        if not torch.cuda.is_available():
            raise InputError(f"--device {text}: no CUDA GPU is available here (torch.cuda.is_available() is False); "
                             "use --device cpu or leave --device out")
    return text


def positive(unit: str = "") -> Callable[[str], float]:
    """argparse type: a finite number > 0 (in ``unit``)."""
    return _argtype(lambda s: check_positive(s, "value", unit), "positive number")


def non_negative(unit: str = "") -> Callable[[str], float]:
    """argparse type: a finite number >= 0 (in ``unit``)."""
    return _argtype(lambda s: check_non_negative(s, "value", unit), "non-negative number")


def integer(minimum: int = 1, maximum: int | None = None) -> Callable[[str], int]:
    """argparse type: an integer >= ``minimum``."""
    return _argtype(lambda s: check_int(s, "value", minimum, maximum), "integer")


def seed() -> Callable[[str], int]:
    """argparse type: a seed, an integer in [0, 2**32)."""
    return _argtype(lambda s: check_seed(s, "value"), "seed")


def finite(unit: str = "") -> Callable[[str], float]:
    """argparse type: any finite number."""
    return _argtype(lambda s: check_number(s, "value", unit), "number")


# ---------------------------------------------------------------------------- repeated flags
class _StoreOnce(argparse._StoreAction):
    """A single-valued flag given twice is an error (not the last one silently)."""

    def __call__(self, parser, namespace, values, option_string=None):
        seen = namespace.__dict__.setdefault("_flags_given", {})
        if self.dest in seen:
            old, new = (repr(os.fspath(v)) if isinstance(v, os.PathLike) else repr(v) for v in (seen[self.dest], values))
            parser.error(f"argument {'/'.join(self.option_strings)}: given twice ({old}, then {new}); give it once")
        seen[self.dest] = values
        super().__call__(parser, namespace, values, option_string)


class _StoreList(argparse._StoreAction):
    """A list flag (``nargs="+"``) given twice accumulates: ``--tasks A --tasks B`` is ``[A, B]``."""

    def __call__(self, parser, namespace, values, option_string=None):
        seen = namespace.__dict__.setdefault("_flags_given", {})
        values = (list(seen[self.dest]) if self.dest in seen else []) + list(values)
        seen[self.dest] = values
        super().__call__(parser, namespace, values, option_string)


def forbid_repeats(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Make every single-valued option of ``parser`` (and of its sub-parsers) an error when given
    twice; list options (``nargs="+"``/``"*"``) accumulate, as ``append`` options do."""
    for action in parser._actions:
        if type(action) is argparse._StoreAction and action.option_strings:
            action.__class__ = _StoreOnce if action.nargs in (None, "?") else _StoreList
        elif isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                forbid_repeats(sub)
    return parser
