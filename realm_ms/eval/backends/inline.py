"""The in-process backend: each slot an ``EpisodeRunner`` in this process."""

from __future__ import annotations

from realm_ms.eval.backends.base import Backend
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig
from realm_ms.eval.slots import EpisodeRunner


class InlineBackend(Backend):
    def __init__(self, cfg: RunConfig, n_slots: int = 1):
        self.runners = [EpisodeRunner(cfg) for _ in range(n_slots)]
        self.n_slots = n_slots

    def cell(self, slot: int):
        return self.runners[slot].cell

    def start(self, starts: dict[int, EpisodeKey]) -> dict:
        return {s: self.runners[s].start(k) for s, k in starts.items()}

    def step(self, commands: dict, delays: dict | None = None) -> dict:
        return {s: self.runners[s].step(a, delay=(delays or {}).get(s, 0)) for s, a in commands.items()}

    def abort(self, aborts: dict[int, str]) -> dict:
        return {s: self.runners[s].abort(m) for s, m in aborts.items()}

    def close(self) -> None:
        for r in self.runners:
            r.close()


__all__ = ["InlineBackend"]
