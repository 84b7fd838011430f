"""Batched backend (ManiSkill GPU simulation): each sub-env of a ManiSkill env with ``num_envs = N`` is an episode slot.

``BatchedBackend`` holds G groups, each a ``slots.CellSlots``: one env of N sub-envs stepped
together on the episode engine (``tasks.episode``), the same code that runs ``EpisodeRunner`` (its
one-slot case). With ``sim_backend="physx_cuda"`` one group of N (GPU simulation, batched cameras);
on CPU physics (``physx_cpu``, where ManiSkill allows only ``num_envs = 1``) G groups of one sub-env
each, stepped in turn in this process (the tests cover the path there; records equal the in-process
runner's).

This module schedules: sub-envs of one env share the task class and the perturbation, so a group
holds one (task, perturbation) cell at a time and switches cell (a new env) only when all its slots
are free. A slot starts a new episode with a ManiSkill partial reset while the other sub-envs run on
(the engine keeps every row's episode seed in the seed list); a cell whose perturbation rebuilds the
scene every reset (``needs_reconfigure``) starts its episodes in waves of whole groups. A finished
slot's sub-env holds its last action until the slot starts again. ``policy_input`` hands a group's
observation batch to the policy without a copy when every row asks for actions from it.
"""

from __future__ import annotations

import dataclasses

from realm_ms.eval.backends.base import Backend
from realm_ms.eval.policies.policy import PolicyInput
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig, build_cell_env
from realm_ms.eval.slots import CellSlots


class BatchedBackend(Backend):
    """``groups`` envs of ``num_envs`` sub-envs each, on ``sim_backend`` (see the module docstring)."""

    def __init__(self, cfg: RunConfig, num_envs: int, groups: int = 1, sim_backend: str = "physx_cuda", env_factory=build_cell_env):
        if num_envs > 1 and sim_backend in ("cpu", "physx_cpu"):
            raise ValueError("ManiSkill's CPU simulation runs one sub-env per env: use num_envs=1 (and groups=N) with physx_cpu")
        self.cfg = dataclasses.replace(cfg, env_kwargs=cfg.env_kwargs | dict(num_envs=num_envs, sim_backend=sim_backend))
        self.groups = [CellSlots(self.cfg, num_envs, g * num_envs, env_factory) for g in range(groups)]
        self.n_slots = groups * num_envs

    def _by_group(self, per_slot: dict) -> dict[int, dict]:
        out: dict[int, dict] = {}
        for s, v in per_slot.items():
            out.setdefault(s // self.groups[0].num_envs, {})[s] = v
        return out

    def cell(self, slot: int):
        return self.groups[slot // self.groups[0].num_envs].cell

    # ------------------------------------------------------------------ scheduling
    def assign(self, free: list[int], queue: list[EpisodeKey]) -> dict[int, EpisodeKey]:
        """Free rows take keys of their group's cell (all rows at once where resets are whole-batch);
        a group with every row free and none of its cell's keys left takes the next cell."""
        free_set, starts = set(free), {}
        for g in self.groups:
            rows = [s for s in g.slots() if s in free_set]
            if not rows or not queue:
                continue
            idle = len(rows) == g.num_envs
            cell = g.cell if any(k.cell() == g.cell for k in queue) else (queue[0].cell() if idle else None)
            if cell is None or (cell == g.cell and g.whole_batch_resets and not idle):
                continue
            for s in rows:
                j = next((i for i, k in enumerate(queue) if k.cell() == cell), None)
                if j is None:
                    break
                starts[s] = queue.pop(j)
        return starts

    # ------------------------------------------------------------------ episodes
    def start(self, starts: dict[int, EpisodeKey]) -> dict[int, dict]:
        out = {}
        for gi, keys in self._by_group(starts).items():
            out.update(self.groups[gi].start(keys))
        return out

    def step(self, commands: dict, delays: dict | None = None) -> dict:
        out = {}
        for gi, cmds in self._by_group(commands).items():
            out.update(self.groups[gi].step(cmds, delays=delays))
        return out

    def abort(self, aborts: dict[int, str]) -> dict:
        out = {}
        for gi, msgs in self._by_group(aborts).items():
            out.update(self.groups[gi].abort(msgs))
        return out

    def close(self) -> None:
        for g in self.groups:
            g.close()

    def policy_input(self, ready: list[int], pending: dict[int, dict]) -> PolicyInput:
        """The group's batch itself when every row asks from the same batch, in row order; else stacked rows."""
        first = pending[ready[0]]
        batch = first.get("batch")
        if batch is not None and len(ready) == len(batch.state) and all(pending[s].get("batch") is batch and pending[s]["row"] == i for i, s in enumerate(ready)):
            return PolicyInput(state=batch.state, images=batch.images, instructions=[pending[s]["instruction"] for s in ready], slots=list(ready))
        return super().policy_input(ready, pending)


__all__ = ["BatchedBackend"]
