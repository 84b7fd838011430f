"""One registry mechanism for every named, pluggable thing in realm-ms.

Tasks, skills (rubrics and expert skills), sysid effects, perturbations, policies, scenes and
object builders are each a ``Registry``: ``register`` (a call or a decorator) adds an entry under
a name (and optional aliases, e.g. a perturbation's numeric id); ``get`` looks one up and, for an
unknown name, raises ``UnknownNameError`` listing the known ones, so a typo never surfaces as a
bare ``KeyError``. Names are matched exactly first, then case-insensitively.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

from realm_ms.errors import InputError

T = TypeVar("T")


class UnknownNameError(InputError):
    """A name that no entry of a registry carries; the message lists the known names. Names come
    from the user (flags, config files), so it is a user error (and a ``ValueError``)."""


class Registry(Generic[T]):
    """Named entries of one kind (``kind`` appears in error messages, e.g. ``"perturbation"``)."""

    def __init__(self, kind: str):
        self.kind = kind
        self._entries: dict[str, T] = {}
        self._aliases: dict[str, str] = {}

    def register(self, name: str, entry: T | None = None, *, aliases: tuple[str, ...] = ()) -> T | Callable[[T], T]:
        """``reg.register("x", obj)`` or ``@reg.register("x")``; a duplicate name is an error.
        Names are stored as ``str(name)`` (so a ``str`` enum member registers under its value)."""
        name = str(name)
        aliases = tuple(str(a) for a in aliases)

        def add(obj: T) -> T:
            for key in (name, *aliases):
                if key in self._entries or key in self._aliases:
                    raise ValueError(f"{self.kind} {key!r} registered twice")
            self._entries[name] = obj
            for a in aliases:
                self._aliases[str(a)] = name
            return obj

        return add(entry) if entry is not None else add

    def canonical(self, name: str | int) -> str:
        """The registered name for ``name`` or one of its aliases (exact, then case-insensitive)."""
        key = str(name)
        if key in self._entries:
            return key
        if key in self._aliases:
            return self._aliases[key]
        folded = {k.lower(): k for k in self._entries} | {a.lower(): n for a, n in self._aliases.items()}
        if key.lower() in folded:
            return folded[key.lower()]
        raise UnknownNameError(f"unknown {self.kind} {key!r}; known: {', '.join(self._entries) or '(none registered)'}")

    def get(self, name: str | int) -> T:
        return self._entries[self.canonical(name)]

    def names(self) -> list[str]:
        return list(self._entries)

    def items(self):
        return self._entries.items()

    def values(self):
        return self._entries.values()

    def __contains__(self, name: object) -> bool:
        try:
            self.canonical(name)  # type: ignore[arg-type]
            return True
        except UnknownNameError:
            return False

    def __getitem__(self, name: str | int) -> T:
        return self.get(name)

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {self.names()})"
