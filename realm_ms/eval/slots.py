"""Episode slots of ``realm eval``: one env of a (task, perturbation) cell on the episode engine.

``CellSlots`` holds the env of one cell with ``num_envs`` sub-envs, each an episode slot, and runs
them through ``tasks.episode.EpisodeEngine`` (resets, chunks, per-slot stopping rules, sparse
capture). On top of the engine it adds what an eval record needs: the cell's env (built through
``build_cell_env``, rebuilt when the cell changes, the ``Unsupported`` signal when the perturbation
does not apply), the env-side policy (the scripted expert), trajectory quality and video frames per slot,
and the record of each finished episode. Observations come back as one host copy of the batched
tensors per call, each slot's observation a row view of it.

``EpisodeRunner`` is the one-slot case (the in-process backend and every worker process);
``batched.BatchedBackend`` holds G of them with N sub-envs each.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from realm_ms.eval.protocol import DEFAULT, EpisodeKey
from realm_ms.eval.runner import HOOKED, VIDEO_CAMERAS, RunConfig, build_cell_env, episode_record, unsupported_record
from realm_ms.tasks.episode import Episode, EpisodeEngine, Step


@dataclass(kw_only=True)
class SlotEpisode(Episode):
    """An engine episode with what its eval record adds: the key, trajectory quality, video frames,
    the frames of the run's ``EpisodeHook``."""

    key: EpisodeKey
    unsupported: str | None = None
    quality: object = None
    frames: list[np.ndarray] = field(default_factory=list)
    hooked: list = field(default_factory=list)

    @property
    def perturbation_info(self) -> dict:
        return self.perturbation if self.perturbation is not None else {"name": DEFAULT, "params": {}}


@dataclass
class ObsBatch:
    """One host copy of a cell env's observation: ``state`` (N, 8) float32, ``images[cam]`` (N, H, W, 3) uint8."""

    state: np.ndarray
    images: dict[str, np.ndarray]


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


class CellSlots:
    """Slots ``first`` .. ``first + num_envs - 1``: the sub-envs of one cell's env (module docstring).

    The protocol of a backend for its own slots: ``start({slot: key}) -> {slot: obs}``,
    ``step({slot: chunk | None}) -> {slot: (obs, record)}``, ``abort({slot: msg}) -> {slot: record}``."""

    def __init__(self, cfg: RunConfig, num_envs: int = 1, first: int = 0, env_factory=build_cell_env):
        self.cfg, self.num_envs, self.first, self.env_factory = cfg, num_envs, first, env_factory
        self.env, self.engine, self.cell, self.unsupported = None, None, None, None
        self.batch: ObsBatch | None = None
        self.eps: dict[int, SlotEpisode] = {}  # slot -> its episode, until its record is taken
        self.seen: dict[int, object] = {}  # slot -> the hook's part of the observation before the step

    def slots(self) -> range:
        return range(self.first, self.first + self.num_envs)

    @property
    def whole_batch_resets(self) -> bool:
        """Resets must include every row: one sub-env, or the perturbation rebuilds the scene each reset."""
        return self.num_envs == 1 or bool(self.engine is not None and self.engine.whole_batch_resets)

    # ------------------------------------------------------------------ episodes
    def _build(self, cell: tuple[str, str]) -> None:
        self.close()
        self.cell = cell
        try:
            self.env = self.env_factory(cell[0], cell[1], self.cfg)
        except NotImplementedError as e:  # a cell the perturbation does not support (REALM: 9 of 160)
            self.unsupported = str(e) or "unsupported"
            return
        self.engine = EpisodeEngine(self.env, every_frame=self.cfg.every_frame(), after_step=self._after_step,
                                    before_step=self._before_step if self.cfg.hook is not None else None)

    def start(self, keys: dict[int, EpisodeKey]) -> dict[int, dict]:
        """Start ``keys`` on their slots (all of one cell); returns each slot's first observation."""
        cell = next(iter(keys.values())).cell()
        if self.cell != cell or (self.env is None and self.unsupported is None):
            self._build(cell)
        max_steps = self.cfg.max_steps or (0 if self.unsupported else self._horizon())
        eps = {s: SlotEpisode(key=k, seed=k.seed, max_steps=max_steps, unsupported=self.unsupported) for s, k in keys.items()}
        self.eps.update(eps)
        if self.unsupported:
            from realm_ms.eval.backends.base import Unsupported

            return {s: Unsupported(self.unsupported) for s in keys}
        options = None
        if self.cfg.hook is not None and len(keys) == 1:  # replayed draws: one sub-env's episode at a time
            options = self.cfg.hook.reset_options(next(iter(keys.values())))
        obs, _ = self.engine.reset({s - self.first: ep for s, ep in eps.items()}, options)
        if self.cfg.env_side and self.engine.actor is None:  # built on the env after its first reset
            from realm_ms.eval.policies import make_policy

            self.engine.actor = make_policy(self.cfg.policy).bind_env_policy(self.env.unwrapped)
        if self.cfg.quality:
            from realm_ms.eval.quality import TrajectoryQuality

            for ep in eps.values():
                ep.quality = TrajectoryQuality(self.env) if self.num_envs == 1 else RowQuality()
        self._frames(obs, list(eps))
        return self._observe(obs, list(keys))

    def step(self, cmds: dict[int, np.ndarray | None], n: int | None = None, delays: dict[int, int] | None = None) -> dict[int, tuple[dict | None, dict | None]]:
        """Execute each slot's chunk (at most ``n``, default ``replan_every`` steps; ``None``: the
        env-side policy acts), each after holding its previous target for ``delays[slot]`` steps
        (the policy's latency). Returns (observation, None) per slot, or (None, record) when finished."""
        if self.unsupported:
            return {s: (None, self._finish(s, unsupported_record(self.cfg, self.eps[s].key, self.unsupported))) for s in cmds}
        self.engine.run(n or self.cfg.replan_every, {s - self.first: a for s, a in cmds.items() if a is not None},
                        {s - self.first: d for s, d in (delays or {}).items() if s in cmds})
        live = sorted(cmds)
        running = [s for s in live if not self.eps[s].done]
        views = self._observe(self.engine.obs, running) if running else {}
        return {s: (views[s], None) if s in views else (None, self._finish(s, self._record(self.eps[s], "ok", self.eps[s].stalled)))
                for s in live}

    def abort(self, aborts: dict[int, str]) -> dict[int, dict]:
        """End these slots' episodes as failed by the policy side (e.g. its server stayed down)."""
        out = {}
        for s, msg in aborts.items():
            ep = self.eps[s]
            out[s] = self._finish(s, self._record(ep, "error", self.env.unwrapped.stalled_stage()[ep.row], msg))
        return out

    def _finish(self, slot: int, rec: dict) -> dict:
        ep = self.eps.pop(slot)
        if self.engine is not None and self.engine.episodes[ep.row] is ep:
            self.engine.drop(ep.row)
        return rec

    def _record(self, ep: SlotEpisode, status: str, stalled: str, error: str | None = None) -> dict:
        rec = episode_record(self.cfg, ep, status, skill=self.env.unwrapped.task_spec.skill, success=ep.success,
                             stalled=stalled, error=error)
        if self.cfg.hook is not None:
            rec[HOOKED], ep.hooked = self.cfg.hook.finish(ep, ep.hooked), []
        return rec

    def _horizon(self) -> int:
        """The env's episode length: ``max_episode_steps``, else the task's horizon."""
        u = self.env.unwrapped
        return u.spec.max_episode_steps or u.task_spec.horizon

    def close(self) -> None:
        if self.env is not None:
            self.env.close()
        self.env, self.engine, self.cell, self.unsupported, self.batch = None, None, None, None, None

    # ------------------------------------------------------------------ per step: quality, frames
    def _before_step(self, obs) -> None:
        for r in self.engine.running():
            self.seen[self.first + r] = self.cfg.hook.observe(obs, r)

    def _after_step(self, step: Step) -> None:
        slots = [self.first + r for r in step.rows]
        if self.cfg.quality and self.num_envs > 1:
            u = self.env.unwrapped
            q, tcp = _host(u.agent.arm_qpos), _host(u.agent.tcp_pose.p)
        for s in slots:
            ep = self.eps[s]
            if isinstance(ep.quality, RowQuality):
                ep.quality.add(q[ep.row], tcp[ep.row])
            elif ep.quality is not None:
                ep.quality.update()
        self._frames(step.obs, slots)  # the finishing step's frame included
        if self.cfg.hook is not None:
            actions = _host(step.action)
            for s in slots:
                self.eps[s].hooked.append(self.cfg.hook.frame(self.seen.pop(s), actions[s - self.first], self.eps[s]))

    def _frames(self, obs, slots: list[int]) -> None:
        if self.cfg.videos == "none":
            return
        cams = [_host(obs["sensor_data"][c]["rgb"]) for c in VIDEO_CAMERAS]
        h = min(c.shape[1] for c in cams)
        for s in slots:
            r = s - self.first
            self.eps[s].frames.append(np.concatenate([c[r, :h] for c in cams], axis=1))

    def _observe(self, obs, slots: list[int]) -> dict[int, dict]:
        """One host copy of the batch; each slot gets row views of it."""
        u = self.env.unwrapped
        images = {cam: _host(obs["sensor_data"][cam]["rgb"]) for cam in self.cfg.obs.cameras}
        self.batch = batch = ObsBatch(state=_host(u.agent.droid_state()).astype(np.float32, copy=False), images=images)
        out = {}
        for s in slots:
            r, ep = s - self.first, self.eps[s]
            out[s] = {"state": batch.state[r], "images": {c: a[r] for c, a in images.items()}, "instruction": ep.instruction,
                      "steps": ep.steps, "batch": batch, "row": r}
        return out


class EpisodeRunner:
    """The one-slot case: episodes of any (task, perturbation, seed) on one env (num_envs = 1)."""

    def __init__(self, cfg: RunConfig, env_factory=build_cell_env):
        self.slots = CellSlots(cfg, env_factory=env_factory)

    @property
    def cell(self) -> tuple[str, str] | None:
        return self.slots.cell

    def start(self, key: EpisodeKey) -> dict:
        """Reset to ``key``; returns the first observation (``state`` (8,), ``images[cam]``, ...)."""
        return self.slots.start({0: key})[0]

    def step(self, actions: np.ndarray | None = None, n: int | None = None, delay: int = 0) -> tuple[dict | None, dict | None]:
        """Execute ``actions`` (T, 8) open-loop, at most ``n`` of them (default ``replan_every``), or
        ``n`` env-side policy steps, after holding the previous target for ``delay`` steps. Returns
        (observation, None) or (None, record) when finished."""
        return self.slots.step({0: actions}, n, {0: delay})[0]

    def abort(self, error: str) -> dict:
        return self.slots.abort({0: error})[0]

    def close(self) -> None:
        self.slots.close()


def _host(t) -> np.ndarray:
    """A tensor as numpy: no copy for CPU tensors, one device-to-host transfer otherwise."""
    return t.detach().cpu().numpy() if hasattr(t, "detach") else np.asarray(t)


__all__ = ["CellSlots", "EpisodeRunner", "SlotEpisode", "ObsBatch", "RowQuality"]
