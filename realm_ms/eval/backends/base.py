"""The protocol every execution backend implements for ``runner.run_plan``, and the control signals
a backend hands back in place of an observation.

A backend holds ``n_slots`` episode slots (envs or sub-envs) and answers, per round of the driver:
``assign(free, queue)`` which keys the free slots start, ``start({slot: key})`` each slot's first
observation (or a signal: ``Unsupported``, ``Failed``), ``policy_input(ready, pending)`` the
policy's batch, ``step({slot: chunk | None}, {slot: delay})`` each slot's next observation or its
finished record, ``abort({slot: message})`` the records of episodes the policy side failed, and
``close()``. Observations are dicts of data (``state``, ``images``, ``instruction``, ``steps``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from realm_ms.eval.policies.policy import PolicyInput
from realm_ms.eval.protocol import EpisodeKey


@dataclass(frozen=True)
class Unsupported:
    """The slot's perturbation does not apply to its task (REALM: 9 of 160 cells): no observation;
    the next ``step`` returns the cell's "unsupported" record without acting."""

    reason: str


@dataclass(frozen=True)
class Failed:
    """The slot could not even start its episode (its worker died or raised during the reset):
    ``record`` is that episode's error record."""

    record: dict


class Backend(ABC):
    """Where the episode slots of ``run_plan`` live and step (module docstring)."""

    n_slots: int

    @abstractmethod
    def cell(self, slot: int) -> tuple[str, str] | None:
        """The (task, perturbation) whose env the slot holds now (None: none yet)."""

    @abstractmethod
    def start(self, starts: dict[int, EpisodeKey]) -> dict[int, dict | Unsupported | Failed]:
        """Start each slot's episode; its first observation, or a control signal."""

    @abstractmethod
    def step(self, commands: dict[int, np.ndarray | None], delays: dict[int, int] | None = None) -> dict[int, tuple[dict | None, dict | None]]:
        """Execute each slot's chunk (``None``: the env-side policy acts) after holding its previous
        target for ``delays[slot]`` steps; (observation, None) per slot, or (None, record) when it ended."""

    @abstractmethod
    def abort(self, aborts: dict[int, str]) -> dict[int, dict]:
        """End these slots' episodes as failed by the policy side; their error records."""

    def close(self) -> None:
        """Release the slots' envs (and processes)."""

    def assign(self, free: list[int], queue: list[EpisodeKey]) -> dict[int, EpisodeKey]:
        """Pop the next key from ``queue`` for each free slot, preferring the slot's current
        (task, perturbation) cell so its env is reused."""
        starts = {}
        for slot in free:
            if not queue:
                break
            cell = self.cell(slot)
            starts[slot] = queue.pop(next((i for i, k in enumerate(queue) if k.cell() == cell), 0))
        return starts

    def policy_input(self, ready: list[int], pending: dict[int, dict]) -> PolicyInput:
        """The policy's batch from the latest observation of each ``ready`` slot."""
        return PolicyInput(
            state=np.stack([pending[s]["state"] for s in ready]),
            instructions=[pending[s]["instruction"] for s in ready],
            images={c: np.stack([pending[s]["images"][c] for s in ready]) for c in pending[ready[0]]["images"]},
            slots=list(ready),
        )


__all__ = ["Backend", "Unsupported", "Failed"]
