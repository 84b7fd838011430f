"""The episode engine: every REALM episode loop runs through it (``realm eval``'s in-process runner
and batched backend, ``realm export``, the expert's ``run_episode``).

``EpisodeEngine`` drives one env of ``num_envs`` sub-envs; each sub-env row is a slot holding at most
one ``Episode`` (stage latches, best progression and the steps where it rose, steps, success, the
stage it stalled at). One slot is the case ``num_envs = 1``.

- ``reset({row: episode})`` starts episodes. With one sub-env, or when every row starts, it is a
  whole reset (``reset(seed=s)``, ``reset(seed=[...])``); otherwise ManiSkill's partial reset
  (``options={"env_idx": rows}``), whose seed list carries every row's current episode seed, since
  ManiSkill sets the episode seeds of all sub-envs from it. A scene rebuilt every reset
  (``needs_reconfigure``) allows whole resets only: callers start such envs in waves.
- ``run(n, chunks, delays)`` steps up to ``n`` times: a row with an action chunk executes it
  open-loop; with an ``actor`` (an env-side policy such as the scripted expert) the actor is asked
  every step; rows without a running episode hold their last action. ``delays[row] = k`` first holds
  the row's previous joint target for k steps (the policy's latency: on the robot the arm keeps
  tracking the last target while the policy thinks), then its chunk or actor starts; in a batch, a
  row whose delay is shorter than the longest keeps its chunk's last action until the others end.
- Stopping rules, per slot: termination (success + ``success_tail``), truncation, the episode's
  ``max_steps``, the end of the actor's script (``actor.done[row]``).
- Sparse capture: an open-loop chunk is looked at after its last step only, so the steps before it
  skip camera capture (``RealmEnv.capture_sensors``), unless ``every_frame`` (videos, datasets).
- Hooks: ``before_step(obs)`` sees the observation an action is chosen from, ``after_step(step)``
  a ``Step`` (the action, the new observation and info, the rows that ran and the rows that ended).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import torch

from realm_ms.jsonable import jsonable

# keys of ``info["perturbation"]`` that hold one entry per sub-env (a slot keeps its row's entry)
PER_ENV_PERTURBATION_KEYS = ("episode_seed", "instruction", "skill", "params")


@dataclass(kw_only=True)
class Episode:
    """One slot's episode: what records, exports and the expert's results read."""

    seed: int
    max_steps: int
    t0: float = field(default_factory=time.perf_counter)
    t_end: float | None = None
    row: int = 0
    instruction: str = ""
    perturbation: dict | None = None  # this row's part of ``info["perturbation"]`` after the reset
    stages: list[str] = field(default_factory=list)
    latched: dict[str, int | None] = field(default_factory=dict)  # first step each stage was met
    best: float = 0.0
    rises: list[int] = field(default_factory=list)  # steps at which the best progression rose
    steps: int = 0
    progression: float = 0.0  # as of the last step
    success: bool = False  # as of the last step
    done: bool = False
    stalled: str | None = None  # the first unmet stage when the episode ended

    def advance(self, progression: float, success: bool, stage_hits) -> None:
        """One env step of bookkeeping."""
        self.steps += 1
        self.progression, self.success = progression, success
        if progression > self.best + 1e-9:
            self.best = progression
            self.rises.append(self.steps)
        for st, hit in zip(self.stages, stage_hits):
            if self.latched[st] is None and hit:
                self.latched[st] = self.steps

    def end(self, stalled: str) -> None:
        self.done, self.stalled, self.t_end = True, stalled, time.perf_counter()

    def wall_s(self) -> float:
        return (self.t_end or time.perf_counter()) - self.t0


@dataclass
class Step:
    """What ``after_step`` hooks see of one env step."""

    action: torch.Tensor  # (num_envs, dim) as applied
    obs: dict
    info: dict
    rows: list[int]  # rows whose episodes ran this step (the ending ones included)
    ended: list[int]  # rows whose episodes ended at this step


def row_perturbation(pert: dict, row: int, num_envs: int) -> dict:
    """A sub-env's part of ``info["perturbation"]`` in the shape a one-sub-env env reports it."""
    if num_envs == 1:
        return pert
    return {k: [v[row]] if k in PER_ENV_PERTURBATION_KEYS and isinstance(v, list) and len(v) == num_envs else v for k, v in pert.items()}


class EpisodeEngine:
    """Episodes on the sub-env rows of one env; see the module docstring."""

    def __init__(self, env, actor=None, every_frame: bool = False, before_step: Callable | None = None,
                 after_step: Callable[[Step], None] | None = None):
        self.env, self.u = env, env.unwrapped
        self.num_envs = int(self.u.num_envs)
        self.actor = actor  # reset with every whole reset; ``reset_rows(rows)`` on partial ones
        self.every_frame, self.before_step, self.after_step = every_frame, before_step, after_step
        self.episodes: list[Episode | None] = [None] * self.num_envs
        self.seeds = [0] * self.num_envs  # current episode seed per row
        self.reset_once = False
        self.obs = None  # the env's latest (batched) observation
        self.hold = None  # (num_envs, dim) last applied action; None right after a whole reset
        self.target = None  # (num_envs, 8) joint target of the last applied action (non-default action spaces)

    @property
    def whole_batch_resets(self) -> bool:
        """Resets must include every row: one sub-env, or the perturbation rebuilds the scene each reset."""
        return self.num_envs == 1 or bool(self.u.perturbations.needs_reconfigure)

    # ------------------------------------------------------------------ starting episodes
    def reset(self, episodes: dict[int, Episode], options: dict | None = None) -> tuple[dict, dict]:
        """Reset the rows of ``episodes`` with their seeds (``options``: e.g. recorded perturbation
        draws to replay) and start them; returns the env's (obs, info)."""
        rows = list(episodes)
        whole = len(rows) == self.num_envs or not self.reset_once or self.whole_batch_resets
        if whole:  # rows left idle (fewer episodes than rows) reuse the first episode's seed
            self.seeds = [episodes[rows[0]].seed] * self.num_envs
        for r, ep in episodes.items():
            self.seeds[r] = ep.seed
        if whole:
            seed = self.seeds[0] if self.num_envs == 1 else list(self.seeds)
            obs, info = self.env.reset(seed=seed) if options is None else self.env.reset(seed=seed, options=options)
            self.hold, self.target, self.episodes = None, None, [None] * self.num_envs
        else:
            idx = torch.as_tensor(rows, dtype=torch.long, device=self.u.device)
            obs, info = self.env.reset(seed=list(self.seeds), options={"env_idx": idx} | (options or {}))
            if self.hold is not None:  # the new rows keep still until they get actions
                self.hold[idx] = self._still()[idx]
            if self.target is not None:
                self.target[rows] = self._state()[rows]
        self.reset_once, self.obs = True, obs
        if self.actor is not None and whole:
            self.actor.reset()
        elif self.actor is not None:
            self.actor.reset_rows(rows)
        instructions = self.u.get_language_instruction()
        stages = [s.value for s in self.u.tracker.stages]
        pert = info.get("perturbation")
        for r, ep in episodes.items():
            ep.row, ep.instruction, ep.stages = r, instructions[r], list(stages)
            ep.latched = {s: None for s in stages}
            ep.perturbation = None if pert is None else jsonable(row_perturbation(pert, r, self.num_envs))
            self.episodes[r] = ep
        return obs, info

    def drop(self, row: int) -> Episode | None:
        """Take the episode off ``row`` (it ended, or was aborted); the row holds from now on."""
        ep, self.episodes[row] = self.episodes[row], None
        return ep

    # ------------------------------------------------------------------ stepping
    def running(self) -> list[int]:
        return [r for r, ep in enumerate(self.episodes) if ep is not None and not ep.done]

    def run(self, n: int, chunks: dict[int, np.ndarray] | None = None, delays: dict[int, int] | None = None) -> list[int]:
        """Step up to ``n`` times (at most a chunk's length), after each row's delay (module
        docstring); stops early once every running episode has ended; returns the rows whose
        episodes ended."""
        chunks = {r: np.asarray(c, dtype=np.float32) for r, c in (chunks or {}).items()}
        n = min([n] + [len(c) for c in chunks.values()])
        live = self.running()
        if not live:
            return []
        delays = {r: int(d) for r, d in (delays or {}).items() if d and int(d) > 0 and r in live}
        total = n + max(delays.values(), default=0)
        held = self._previous_targets() if delays else None
        sparse = self.actor is None and not self.every_frame
        ended: list[int] = []
        for i in range(total):
            rows = [r for r in live if not self.episodes[r].done]
            if self.before_step is not None:
                self.before_step(self.obs)
            waiting = [r for r in rows if i < delays.get(r, 0)]
            action = self._action(i, rows, chunks, delays)
            if waiting:
                action = self._hold_targets(action, waiting, held)
            self.u.capture_sensors = not sparse or i == total - 1
            if self._conv() is not None and i == total - 1:  # the target a later delay holds
                self.target = self._joint_target(action)
            try:
                obs, _, term, trunc, info = self.env.step(action)
            finally:
                self.u.capture_sensors = True
            self.hold, self.obs = action, obs
            now = self._advance(rows, term, trunc, info)
            ended += now
            if self.after_step is not None:
                self.after_step(Step(action, obs, info, rows, now))
            if all(self.episodes[r].done for r in live):
                break
        return ended

    def _still(self) -> torch.Tensor:
        from realm_ms.agents.droid_action_spaces import hold_action

        return hold_action(self.u)

    def _held(self) -> torch.Tensor:
        if self.hold is None:  # nothing applied since the reset: keep the reset state
            self.hold = self._still()
        return self.hold

    def _action(self, i: int, rows: list[int], chunks: dict[int, np.ndarray], delays: dict[int, int] | None = None) -> torch.Tensor:
        idle = [r for r in range(self.num_envs) if r not in rows]
        if self.actor is not None:
            a = self.actor.act(self.obs) if any(i >= (delays or {}).get(r, 0) for r in rows) else self._held().clone()
            if idle:
                mask = torch.zeros(self.num_envs, dtype=torch.bool, device=a.device)
                mask[idle] = True
                a = torch.where(mask[:, None], self._held().to(a.device), a)
            return a

        def step_of(r: int) -> np.ndarray:  # after its delay; past its chunk's end, the chunk's last action
            c = chunks[r]
            return c[min(max(i - (delays or {}).get(r, 0), 0), len(c) - 1)]

        fed = [r for r in rows if r in chunks]
        if len(fed) == self.num_envs:  # every row has its action (one slot: always)
            return torch.as_tensor(np.stack([step_of(r) for r in fed]), device=self.u.device)
        a = self._held().clone()
        if fed:
            a[torch.as_tensor(fed, device=a.device)] = torch.as_tensor(np.stack([step_of(r) for r in fed]), device=a.device)
        return a

    # ------------------------------------------------------------------ the policy's latency
    def _conv(self):
        return getattr(self.u, "droid_actions", None)  # the env's action-space converter (None: droid_joint_pos)

    def _state(self) -> np.ndarray:
        return self.u.agent.droid_state().detach().cpu().double().numpy()

    def _joint_target(self, action: torch.Tensor) -> np.ndarray:
        """(num_envs, 8) joint targets ``action`` asks for from the current state (as the env's converter)."""
        from realm_ms.agents.droid_action_spaces import Q_LIMITS

        conv, s = self._conv(), self._state()
        t = conv.space.to_joint_target(action.detach().cpu().double().numpy().reshape(self.num_envs, -1), s[:, :7], s[:, 7], conv.ik)
        t[:, :7] = np.clip(t[:, :7], Q_LIMITS[:, 0], Q_LIMITS[:, 1])
        return t

    def _previous_targets(self):
        """What a delayed row holds: the last applied action (joint_position: it is the target), or,
        in the other action spaces, the joint target it asked for (None: the state right after a reset)."""
        if self._conv() is None:
            return self._held().clone()
        return self.target.copy() if self.target is not None else self._state()

    def _hold_targets(self, action: torch.Tensor, rows: list[int], held) -> torch.Tensor:
        """``action`` with ``rows`` holding their previous joint target, in the env's action space."""
        a = action.clone()
        idx = torch.as_tensor(rows, device=a.device)
        conv = self._conv()
        if conv is None:
            a[idx] = held[idx].to(a.device, a.dtype)
            return a
        s = self._state()
        hold = conv.space.from_joint_target(held[rows], s[rows, :7], s[rows, 7], conv.ik)
        a[idx] = torch.as_tensor(hold, dtype=a.dtype, device=a.device)
        return a

    def _advance(self, rows: list[int], term, trunc, info) -> list[int]:
        """Bookkeeping of the running rows after one step; ends those a stopping rule stops."""
        if not rows:
            return []
        stage_keys = [f"stage_{st.lower()}" for st in self.episodes[rows[0]].stages]
        flags = torch.stack([info["progression"].float(), info["success"].float(), term.float(), trunc.float().to(term.device),
                             *[info[k].float() for k in stage_keys]]).cpu().numpy()
        script = getattr(self.actor, "done", None) if self.actor is not None else None
        ended = []
        for r in rows:
            ep = self.episodes[r]
            ep.advance(float(flags[0, r]), bool(flags[1, r] > 0.5), flags[4:, r] > 0.5)
            script_over = script is not None and bool(script[r])
            if flags[2, r] > 0.5 or flags[3, r] > 0.5 or ep.steps >= ep.max_steps or script_over:
                ended.append(r)
        if ended:
            stalled = self.u.stalled_stage()
            for r in ended:
                self.episodes[r].end(stalled[r])
        return ended


__all__ = ["Episode", "EpisodeEngine", "Step", "row_perturbation", "PER_ENV_PERTURBATION_KEYS"]
