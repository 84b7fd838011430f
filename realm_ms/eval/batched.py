"""Batched simulation backend: each sub-env of a ManiSkill env with ``num_envs = N`` is an episode slot.

``BatchedBackend`` holds G groups, each one env of N sub-envs stepped together: with
``sim_backend="physx_cuda"`` one group of N (GPU simulation, batched cameras); on CPU physics
(``physx_cpu``, where ManiSkill allows only ``num_envs = 1``) G groups of one sub-env each, stepped in
turn in this process, which runs the same code path as the GPU one (the tests cover it there).

- Sub-envs of one env share the task class and the perturbation, so a group holds one
  (task, perturbation) cell at a time; it switches cell (a new env) only when all its slots are free.
- A slot starts a new episode with a ManiSkill partial reset (``reset(seed=[...],
  options={"env_idx": rows})``) while the other sub-envs run on. ManiSkill sets the episode seeds
  of *all* sub-envs from the ``seed`` list, so the list carries every row's current episode seed and
  the new rows' seeds: each sub-env's placement and perturbation draws come from its own episode
  seed (``_batched_episode_rng[i]``, ``_episode_seed[i]``). When every row resets together it is a
  full reset (with one sub-env: ``reset(seed=s)``, as ``EpisodeRunner`` does, so records equal).
- ManiSkill cannot reconfigure (rebuild the scene) on a partial reset: a cell whose perturbation
  rebuilds the scene every reset (``needs_reconfigure``) starts its episodes in waves of whole groups.
- Each slot keeps its own bookkeeping (``SlotEpisode``: stage latches, progression, steps, success,
  early stop ``success_tail`` steps after success, ``max_steps``, trajectory quality, video frames);
  a finished slot's record is taken at its last step and its sub-env then holds its last action until
  the slot starts again. Records have the schema of ``EpisodeRunner``'s.
- Observations come back once per round as one host copy of the batched tensors; each slot's
  observation is a row view of it, and ``policy_input`` hands the whole batch to the policy
  without a copy when every row of a group asks for actions from the same batch.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from realm_ms.eval.policies.policy import PolicyInput
from realm_ms.eval.protocol import DEFAULT, EpisodeKey
from realm_ms.eval.runner import VIDEO_CAMERAS, RunConfig, advance_episode, build_cell_env, episode_record, unsupported_record
from realm_ms.eval.backend import Backend
from realm_ms.jsonable import jsonable

# keys of ``info["perturbation"]`` that hold one entry per sub-env (a slot's record keeps its row)
PER_ENV_PERTURBATION_KEYS = ("episode_seed", "instruction", "skill", "params")


@dataclass
class ObsBatch:
    """One host copy of a group's observation: ``state`` (N, 8) float32, ``images[cam]`` (N, H, W, 3) uint8."""

    state: np.ndarray
    images: dict[str, np.ndarray]


@dataclass
class SlotEpisode:
    """One slot's episode: what ``EpisodeRunner`` tracks for its single env, for one sub-env row."""

    key: EpisodeKey
    row: int
    t0: float = field(default_factory=time.perf_counter)
    unsupported: str | None = None
    instruction: str = ""
    perturbation_info: dict = field(default_factory=dict)
    stages: list[str] = field(default_factory=list)
    latched: dict[str, int | None] = field(default_factory=dict)
    best: float = 0.0
    rises: list[int] = field(default_factory=list)
    steps: int = 0
    success: bool = False  # as of the last step
    quality: object = None
    frames: list[np.ndarray] = field(default_factory=list)
    record: dict | None = None  # set at the step the episode ends


class RowQuality:
    """Trajectory quality of one sub-env row of a batched env (joint and TCP paths; contact counts
    are ``None``, as ``TrajectoryQuality`` reports them under GPU simulation)."""

    contacts = False

    def __init__(self):
        self.q: list[np.ndarray] = []
        self.tcp: list[np.ndarray] = []

    def add(self, q: np.ndarray, tcp: np.ndarray) -> None:
        self.q.append(q.astype(np.float64))
        self.tcp.append(tcp.astype(np.float64))

    def summary(self) -> dict:
        from realm_ms.eval.quality import TrajectoryQuality

        return TrajectoryQuality.summary(self)  # the same definitions; it reads only q, tcp, contacts


@dataclass
class Group:
    """One env of ``num_envs`` sub-envs; slot ``first + row`` is sub-env ``row``."""

    first: int
    num_envs: int
    env: object = None
    cell: tuple[str, str] | None = None
    unsupported: str | None = None  # the cell's perturbation does not support its task
    reset_once: bool = False
    seeds: list[int] = field(default_factory=list)  # current episode seed per row
    hold: object = None  # (N, 8) last applied action; idle rows keep holding it
    env_policy: object = None
    obs: object = None  # the env's latest (batched) observation
    batch: ObsBatch | None = None

    def slots(self) -> range:
        return range(self.first, self.first + self.num_envs)

    @property
    def whole_batch_resets(self) -> bool:
        """Resets must include every row: one sub-env, or the perturbation rebuilds the scene each reset."""
        return self.num_envs == 1 or bool(self.env is not None and self.env.unwrapped.perturbations.needs_reconfigure)


class BatchedBackend(Backend):
    """``groups`` envs of ``num_envs`` sub-envs each, on ``sim_backend`` (see the module docstring)."""

    def __init__(self, cfg: RunConfig, num_envs: int, groups: int = 1, sim_backend: str = "physx_cuda", env_factory=build_cell_env):
        if num_envs > 1 and sim_backend in ("cpu", "physx_cpu"):
            raise ValueError("ManiSkill's CPU simulation runs one sub-env per env: use num_envs=1 (and groups=N) with physx_cpu")
        self.cfg = dataclasses.replace(cfg, env_kwargs=cfg.env_kwargs | dict(num_envs=num_envs, sim_backend=sim_backend))
        self.env_factory = env_factory
        self.groups = [Group(first=g * num_envs, num_envs=num_envs) for g in range(groups)]
        self.n_slots = groups * num_envs
        self.episodes: list[SlotEpisode | None] = [None] * self.n_slots

    def _group(self, slot: int) -> Group:
        return self.groups[slot // self.groups[0].num_envs]

    def cell(self, slot: int):
        return self._group(slot).cell

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
    def _build(self, g: Group, cell: tuple[str, str]) -> None:
        if g.env is not None:
            g.env.close()
        g.env, g.cell, g.unsupported, g.reset_once, g.env_policy, g.obs, g.batch = None, cell, None, False, None, None, None
        g.seeds = [0] * g.num_envs
        try:
            g.env = self.env_factory(cell[0], cell[1], self.cfg)
        except NotImplementedError as e:  # a cell the perturbation does not support (REALM: 9 of 160)
            g.unsupported = str(e) or "unsupported"

    def start(self, starts: dict[int, EpisodeKey]) -> dict[int, dict]:
        by_group: dict[int, dict[int, EpisodeKey]] = {}
        for s, k in starts.items():
            by_group.setdefault(s // self.groups[0].num_envs, {})[s] = k
        out = {}
        for gi, keys in by_group.items():
            out.update(self._start_group(self.groups[gi], keys))
        return out

    def _start_group(self, g: Group, keys: dict[int, EpisodeKey]) -> dict[int, dict]:
        import torch

        cell = next(iter(keys.values())).cell()
        if g.cell != cell or (g.env is None and g.unsupported is None):
            self._build(g, cell)
        if g.unsupported:
            for s, k in keys.items():
                self.episodes[s] = SlotEpisode(k, s - g.first, unsupported=g.unsupported)
            return {s: {"unsupported": g.unsupported} for s in keys}
        rows = [s - g.first for s in keys]
        t0 = time.perf_counter()
        whole = len(rows) == g.num_envs or not g.reset_once or g.whole_batch_resets
        if whole:  # every row resets (``assign`` starts such a group only when all its rows are free)
            first_seed = next(iter(keys.values())).seed  # rows left idle (fewer keys than rows) reuse it
            g.seeds = [first_seed] * g.num_envs
        for s, k in keys.items():
            g.seeds[s - g.first] = k.seed
        if whole:
            obs, info = g.env.reset(seed=g.seeds[0] if g.num_envs == 1 else list(g.seeds))
        else:
            idx = torch.as_tensor(rows, dtype=torch.long, device=g.env.unwrapped.device)
            obs, info = g.env.reset(seed=list(g.seeds), options={"env_idx": idx})
        g.reset_once, g.obs = True, obs
        from realm_ms.agents.droid_action_spaces import hold_action

        u = g.env.unwrapped
        if g.hold is None or whole:  # keep still, in the env's action space (velocity spaces: zeros)
            g.hold = hold_action(u)
        else:
            g.hold[idx] = hold_action(u)[idx]
        self._reset_env_policy(g, rows, whole)
        instructions = u.get_language_instruction()
        pert = info.get("perturbation")
        for s, k in keys.items():
            r = s - g.first
            ep = SlotEpisode(k, r, t0=t0, instruction=instructions[r], stages=[st.value for st in u.tracker.stages])
            ep.perturbation_info = jsonable(_row(pert, r, g.num_envs) if pert is not None else {"name": DEFAULT, "params": {}})
            ep.latched = {st: None for st in ep.stages}
            if self.cfg.quality:
                from realm_ms.eval.quality import TrajectoryQuality

                ep.quality = TrajectoryQuality(g.env) if g.num_envs == 1 else RowQuality()
            self.episodes[s] = ep
        self._frames(g, obs, list(keys))
        return self._observe(g, obs, list(keys))

    def _reset_env_policy(self, g: Group, rows: list[int], whole: bool) -> None:
        if not self.cfg.env_side:
            return
        if g.env_policy is None:
            from realm_ms.eval.policies import make_policy

            g.env_policy = make_policy(self.cfg.policy).bind_env_policy(g.env.unwrapped)
        elif whole:
            g.env_policy.reset()
        else:
            reset_policy_rows(g.env_policy, rows)

    # ------------------------------------------------------------------ observations
    def _observe(self, g: Group, obs, slots: list[int]) -> dict[int, dict]:
        """One host copy of the batch; each slot gets row views of it."""
        u = g.env.unwrapped
        images = {cam: _host(obs["sensor_data"][cam]["rgb"]) for cam in self.cfg.obs.cameras}
        g.batch = batch = ObsBatch(state=_host(u.agent.droid_state()).astype(np.float32, copy=False), images=images)
        out = {}
        for s in slots:
            r, ep = s - g.first, self.episodes[s]
            out[s] = {"state": batch.state[r], "images": {c: a[r] for c, a in images.items()}, "instruction": ep.instruction,
                      "steps": ep.steps, "batch": batch, "row": r}
        return out

    def policy_input(self, ready: list[int], pending: dict[int, dict]) -> PolicyInput:
        """The group's batch itself when every row asks from the same batch, in row order; else stacked rows."""
        first = pending[ready[0]]
        batch = first.get("batch")
        if batch is not None and len(ready) == len(batch.state) and all(pending[s].get("batch") is batch and pending[s]["row"] == i for i, s in enumerate(ready)):
            return PolicyInput(state=batch.state, images=batch.images, instructions=[pending[s]["instruction"] for s in ready], slots=list(ready))
        return super().policy_input(ready, pending)

    def _frames(self, g: Group, obs, slots: list[int]) -> None:
        if self.cfg.videos == "none":
            return
        cams = [_host(obs["sensor_data"][c]["rgb"]) for c in VIDEO_CAMERAS]
        h = min(c.shape[1] for c in cams)
        for s in slots:
            r = s - g.first
            self.episodes[s].frames.append(np.concatenate([c[r, :h] for c in cams], axis=1))

    # ------------------------------------------------------------------ stepping
    def step(self, commands: dict) -> dict:
        out = {}
        by_group: dict[int, dict] = {}
        for s, a in commands.items():
            ep = self.episodes[s]
            if ep is not None and ep.unsupported:
                out[s] = (None, self._finish(s, self._unsupported_record(ep)))
            else:
                by_group.setdefault(s // self.groups[0].num_envs, {})[s] = a
        for gi, cmds in by_group.items():
            out.update(self._step_group(self.groups[gi], cmds))
        return out

    def _step_group(self, g: Group, cmds: dict) -> dict:
        import torch

        env, u = g.env, g.env.unwrapped
        live = sorted(cmds)
        rows = {s: s - g.first for s in live}
        chunks = {s: a for s, a in cmds.items() if a is not None}
        n = min([self.cfg.replan_every] + [len(a) for a in chunks.values()])
        host_actions = {s: np.asarray(a[:n], dtype=np.float32) for s, a in chunks.items()}
        stage_keys = [f"stage_{st.lower()}" for st in self.episodes[live[0]].stages]
        obs = g.obs
        # as EpisodeRunner: a chunk's observation is read after its last step only, so the steps
        # before it skip camera capture (RealmEnv.capture_sensors) unless frames go into videos
        sparse = g.env_policy is None and self.cfg.videos == "none"
        for i in range(n):
            running = [s for s in live if self.episodes[s].record is None]  # rows without an episode hold
            if g.env_policy is not None:
                a = g.env_policy.act(obs)
                idle = torch.ones(g.num_envs, dtype=torch.bool, device=a.device)
                idle[[rows[s] for s in running]] = False
                if bool(idle.any()):
                    a = torch.where(idle[:, None], g.hold.to(a.device), a)
            else:
                a = g.hold.clone()
                fed = [s for s in running if s in host_actions]
                if fed:
                    a[torch.as_tensor([rows[s] for s in fed], device=a.device)] = torch.as_tensor(
                        np.stack([host_actions[s][i] for s in fed]), device=a.device)
            u.capture_sensors = not sparse or i == n - 1
            try:
                obs, _, term, trunc, info = env.step(a)
            finally:
                u.capture_sensors = True
            g.hold, g.obs = a, obs
            self._frames(g, obs, running)  # the finishing step's frame included
            flags = torch.stack([info["progression"].float(), info["success"].float(), term.float(), trunc.float().to(term.device),
                                 *[info[k].float() for k in stage_keys]]).cpu().numpy()
            qt = None
            if self.cfg.quality and g.num_envs > 1:
                qt = _host(u.agent.arm_qpos), _host(u.agent.tcp_pose.p)
            for s in live:
                ep = self.episodes[s]
                if ep.record is not None:
                    continue
                r = rows[s]
                ep.success = bool(flags[1, r] > 0.5)
                advance_episode(ep, float(flags[0, r]), flags[4:, r] > 0.5)
                if isinstance(ep.quality, RowQuality):
                    ep.quality.add(qt[0][r], qt[1][r])
                elif ep.quality is not None:
                    ep.quality.update()
                script_over = g.env_policy is not None and bool(getattr(g.env_policy, "done", [False] * g.num_envs)[r])
                if flags[2, r] > 0.5 or flags[3, r] > 0.5 or ep.steps >= self.cfg.max_steps or script_over:
                    ep.record = self._record(g, ep, "ok", stalled=u.stalled_stage()[r])
            if all(self.episodes[s].record is not None for s in live):
                break
        running = [s for s in live if self.episodes[s].record is None]
        views = self._observe(g, obs, running) if running else {}
        return {s: (views[s], None) if s in views else (None, self._finish(s, self.episodes[s].record)) for s in live}

    def abort(self, aborts: dict[int, str]) -> dict:
        out = {}
        for s, msg in aborts.items():
            g, ep = self._group(s), self.episodes[s]
            stalled = g.env.unwrapped.stalled_stage()[ep.row]
            out[s] = self._finish(s, self._record(g, ep, "error", stalled=stalled, error=msg))
        return out

    def _finish(self, slot: int, rec: dict) -> dict:
        self.episodes[slot] = None
        return rec

    # ------------------------------------------------------------------ records (EpisodeRunner's schema)
    def _unsupported_record(self, ep: SlotEpisode) -> dict:
        return unsupported_record(self.cfg, ep.key, ep.unsupported)

    def _record(self, g: Group, ep: SlotEpisode, status: str, stalled: str, error: str | None = None) -> dict:
        return episode_record(self.cfg, ep, status, skill=g.env.unwrapped.task_spec.skill, success=ep.success,
                              stalled=stalled, error=error)

    def close(self) -> None:
        for g in self.groups:
            if g.env is not None:
                g.env.close()
            g.env, g.cell, g.env_policy = None, None, None


def _host(t) -> np.ndarray:
    """A tensor as numpy: no copy for CPU tensors, one device-to-host transfer otherwise."""
    return t.detach().cpu().numpy() if hasattr(t, "detach") else np.asarray(t)


def _row(pert: dict, row: int, num_envs: int) -> dict:
    """A sub-env's part of ``info["perturbation"]`` in the shape a one-sub-env env reports it."""
    if num_envs == 1:
        return pert
    return {k: [v[row]] if k in PER_ENV_PERTURBATION_KEYS and isinstance(v, list) and len(v) == num_envs else v for k, v in pert.items()}


def reset_policy_rows(policy, rows: list[int]) -> None:
    """Restart an env-side policy (the scripted expert) for the sub-envs ``rows`` only.

    ``Expert.reset()`` restarts every row from the env's state; the other rows' per-row state
    (skill generators, contexts, commanded joints, base poses, done flags) is put back afterwards."""
    keep_lists = {a: list(getattr(policy, a)) for a in ("ctxs", "gens", "done")}
    keep_rows = {a: getattr(policy, a).clone() for a in ("q_cmd", "base_p")}
    policy.reset()
    reset = set(rows)
    for a, old in keep_lists.items():
        new = getattr(policy, a)
        for i in range(len(new)):
            if i not in reset:
                new[i] = old[i]
    for a, old in keep_rows.items():
        new = getattr(policy, a)
        mask = [i for i in range(len(new)) if i not in reset]
        new[mask] = old[mask]


__all__ = ["BatchedBackend", "SlotEpisode", "RowQuality", "reset_policy_rows", "PER_ENV_PERTURBATION_KEYS"]
