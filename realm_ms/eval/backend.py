"""The protocol every execution backend implements for ``run_plan`` (backends: ``workers.py``,
``batched.py``): ``n_slots``, ``cell(slot)``, ``assign``, ``start``, ``policy_input``, ``step``,
``abort``, ``close``."""

from __future__ import annotations

import numpy as np

from realm_ms.eval.policies.policy import PolicyInput
from realm_ms.eval.protocol import EpisodeKey


class Backend:
    """What ``run_plan`` drives; subclasses hold the slots' envs (the protocol: ``workers.py``'s docstring)."""

    n_slots: int

    def cell(self, slot: int):
        raise NotImplementedError

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

    def close(self) -> None:
        pass
