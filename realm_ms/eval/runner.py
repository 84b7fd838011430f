"""What a ``realm eval`` run is made of, and the driver that runs a plan of episodes.

``RunConfig`` holds the env-side settings of a run; ``cell_config`` / ``build_cell_env`` describe
and build the env of a (task, perturbation) cell through ``tasks.make_env``; ``episode_record`` is
the one record schema every backend writes (the episodes themselves run on the episode engine,
``tasks.episode``, through ``slots.CellSlots``: ``EpisodeRunner`` is its one-slot case).

``run_plan`` is the driver of ``realm eval`` and ``realm export``: it keeps every slot of a backend
busy (``backends/``: in-process, N worker processes, batched sub-envs; Ray shards run it per cell),
calls the policy once per round on the batch of slots that need actions, hands each finished record
to its caller (an ``EpisodeHook``'s frames riding with it), and shows a live progress bar.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from realm_ms.eval.policies.policy import ObsRequest
from realm_ms.eval.protocol import DEFAULT, EpisodeKey
from realm_ms.eval.provenance import code_version
from realm_ms.jsonable import jsonable

VIDEO_CAMERAS = ("exterior_1", "wrist")
HOOKED = "hooked"  # the record field that carries what an ``EpisodeHook`` made of the episode


class EpisodeHook(Protocol):
    """Per-step data an episode's record carries beyond ``realm eval``'s fields (``realm export``:
    its dataset frames). It runs where the env steps (a worker process too: it must pickle); what
    ``finish`` returns rides in ``record[HOOKED]`` to ``run_plan``'s ``on_record``."""

    def reset_options(self, key: EpisodeKey) -> dict | None:
        """``env.reset`` options of the key's episode (e.g. recorded perturbation draws to replay)."""

    def observe(self, obs: dict, row: int) -> Any:
        """Before a step: what to keep of sub-env ``row``'s observation its action is chosen from."""

    def frame(self, seen: Any, action: np.ndarray, ep) -> Any:
        """After the step: one frame from ``observe``'s result, the action applied and the episode
        (``tasks.episode.Episode``: progression, success, done, instruction as of this step)."""

    def finish(self, ep, frames: list) -> Any:
        """The episode's frames (and anything else of the episode) as they ride with its record."""


@dataclass
class RunConfig:
    """Env-side settings of a run (picklable: sent to worker processes)."""

    policy: str = "zero"  # policy spec (recorded; env-side policies are rebuilt from it)
    env_side: bool = False
    max_steps: int | None = 800  # control steps per episode; None: the task's horizon
    replan_every: int = 8
    success_tail: int = 15
    obs: ObsRequest = field(default_factory=ObsRequest)
    videos: str = "none"  # none | failures | all
    videos_dir: str | None = None
    quality: bool = True
    env_kwargs: dict = field(default_factory=dict)
    policy_latency: str = "0"  # "0" | "measured" | seconds (``latency.py``): the hold before each chunk
    shader: str = "default"  # camera shader (``rendering.SHADERS``)
    hook: EpisodeHook | None = None  # per-step frames a record carries (``realm export``)

    def needs_rgb(self) -> bool:
        return bool(self.obs.cameras) or self.videos != "none" or self.hook is not None

    def every_frame(self) -> bool:
        """Capture cameras at every step (videos, dataset frames), not only where a policy looks."""
        return self.videos != "none" or self.hook is not None


def cell_config(task: str, perturbation, cfg: RunConfig):
    """The env of one (task, perturbation) cell as a ``RealmEnvConfig``, built here once (what every
    backend builds, every record stores, export datasets and the LeRobot env use), with
    ``cfg.env_kwargs`` (``gym.make`` keywords: a robot model, an action space, the batched backend's
    ``num_envs`` / ``sim_backend``) folded in; returns it and the ManiSkill keywords it has no field for."""
    from realm_ms.rendering import CameraSettings
    from realm_ms.tasks.config import RealmEnvConfig

    config = RealmEnvConfig(
        task=task,
        cameras=CameraSettings(width=cfg.obs.width, height=cfg.obs.height, shader=cfg.shader),
        perturbation=None if perturbation == DEFAULT else perturbation,
        horizon=cfg.max_steps,
        success_tail=cfg.success_tail,
        obs_mode="rgb" if cfg.needs_rgb() else "state_dict",
        control_mode="droid_joint_pos",
    )
    return config.with_kwargs(cfg.env_kwargs)


def build_cell_env(task: str, perturbation: str, cfg: RunConfig):
    """The env for one (task, perturbation) cell, through the one factory ``tasks.make_env``."""
    from realm_ms.tasks.config import make_env

    config, rest = cell_config(task, perturbation, cfg)
    return make_env(config, **rest)


# ---------------------------------------------------------------------------------------- records
def _base_record(cfg: RunConfig, key: EpisodeKey) -> dict:
    from realm_ms.agents.droid_action_spaces import action_space_name

    config = cell_config(key.task, key.perturbation, cfg)[0]
    return dict(task=key.task, perturbation=key.perturbation, seed=key.seed, policy=cfg.policy, action_space=action_space_name(cfg.env_kwargs),
                robot_model=robot_model_name(config.robot_model), config=config.to_dict())


def robot_model_name(robot_model) -> str:
    """What a record calls the robot: ``nominal`` (no model), a named model, a MODEL.yaml path, or
    ``inline`` (a model given as a dict)."""
    return "nominal" if robot_model is None else robot_model if isinstance(robot_model, str) else "inline"


def unsupported_record(cfg: RunConfig, key: EpisodeKey, why: str) -> dict:
    """The record of a cell the perturbation does not support (REALM: 9 of 160)."""
    return _base_record(cfg, key) | dict(status="unsupported", error=why, success=False, progression=0.0, steps=0)


def error_record(cfg: RunConfig, key: EpisodeKey | None, why: str, traceback: str | None = None) -> dict:
    """The record of an episode that failed before it could finish (its worker process died or
    raised): the same schema, ``status`` "error"; ``traceback``: the worker's, cut to its last 4000 characters."""
    rec = (_base_record(cfg, key) if key is not None else {}) | dict(status="error", error=why, success=False, progression=0.0, steps=0)
    if traceback:
        rec["traceback"] = traceback[-4000:]
    return rec


def episode_record(cfg: RunConfig, ep, status: str, skill, success: bool, stalled: str, error: str | None = None) -> dict:
    """One finished episode's record, the schema every backend writes. ``ep``: a ``slots.SlotEpisode``
    (the engine's bookkeeping with its key, quality and frames); its frames are written to a video
    as ``cfg.videos`` says, then dropped."""
    rec = _base_record(cfg, ep.key) | dict(
        status=status,
        perturbation_params=ep.perturbation_info,
        instruction=ep.instruction,
        skill=skill,
        success=success,
        progression=round(ep.best, 6),
        progression_timestamps=ep.rises,
        stages=ep.latched,
        stalled_stage=stalled,
        steps=ep.steps,
        max_steps=ep.max_steps,
        replan_every=cfg.replan_every,
        wall_s=round(ep.wall_s(), 3),
        quality=ep.quality.summary() if ep.quality is not None else None,
        code_version=code_version(),  # package version + git revision: provenance for report headers
    )
    if error:
        rec["error"] = error
    if ep.frames and (cfg.videos == "all" or (cfg.videos == "failures" and not success)):
        rec["video"] = _write_video(cfg, ep.key, ep.frames)
    ep.frames = []
    return jsonable(rec)


def _write_video(cfg: RunConfig, key: EpisodeKey, frames: list[np.ndarray]) -> str:
    import imageio.v2 as imageio

    d = Path(cfg.videos_dir or "videos")
    d.mkdir(parents=True, exist_ok=True)
    path = d / f"{key.task}__{key.perturbation}__{key.seed}.mp4"
    # H.264 in yuv420p needs even sizes: pad odd ones with a black row / column instead of letting
    # imageio resize (stretch) every frame to its macro block, which it also warns about
    h, w = frames[0].shape[:2]
    pad = ((0, h % 2), (0, w % 2), (0, 0))
    if h % 2 or w % 2:
        frames = [np.pad(f, pad) for f in frames]
    imageio.mimwrite(path, frames, fps=15, macro_block_size=1)
    return str(path)


# ---------------------------------------------------------------------------------------- driver
@dataclass
class Progress:
    """Live counters behind the progress bar (and the throughput bench)."""

    total: int = 0
    done: int = 0
    successes: int = 0
    errors: int = 0
    env_steps: int = 0
    started: float = field(default_factory=time.perf_counter)

    def steps_per_s(self) -> float:
        return self.env_steps / max(time.perf_counter() - self.started, 1e-9)


def run_plan(keys: list[EpisodeKey], policy, backend, on_record, progress_bar: bool = True, replan_every: int = 8,
             policy_latency: str = "0", env_kwargs: dict | None = None, skip: Callable[[EpisodeKey], bool] | None = None,
             desc: str = "episodes") -> Progress:
    """Run ``keys`` on ``backend`` with ``policy``; ``on_record(record)`` is called per finished episode.
    ``skip(key)``: asked before a key starts; True drops it (``realm export --success-only``: its
    cell has its episodes).

    One round: free slots start the next keys (``backend.assign``: preferring a slot's current
    (task, perturbation), so envs are reused), the policy acts once on the batch of slots that need
    actions (``backend.policy_input``), its output is validated (``policies.replies``: shape,
    numbers, finite, within the bounds of the action space ``env_kwargs`` name), and every active
    slot executes its chunk after holding its previous target for the policy's latency
    (``latency.py``). A policy's error, exception or bad output for a row fails that episode only;
    records state the latency setting and the latencies measured per server."""
    from tqdm import tqdm

    from realm_ms.eval.backends.base import Failed, Unsupported
    from realm_ms.eval.latency import hold_steps, parse_latency
    from realm_ms.eval.policies.replies import check_output

    policy_latency = parse_latency(policy_latency)
    measured: dict[int, dict[str, list[float]]] = {}  # slot -> server -> request wall times (s)
    queue = list(keys)
    prog = Progress(total=len(keys))
    bar = tqdm(total=len(keys), desc=desc, unit="ep", disable=not progress_bar, dynamic_ncols=True)
    active: dict[int, EpisodeKey] = {}
    pending: dict[int, dict] = {}  # slot -> latest observation

    def postfix() -> dict:
        return dict(success=f"{prog.successes}/{prog.done}", errors=prog.errors, steps_s=f"{prog.steps_per_s():.1f}")

    def count_steps(slot: int, steps: int) -> None:
        obs = pending.get(slot)
        prev = (obs.get("steps", 0) or 0) if isinstance(obs, dict) else 0  # an Unsupported slot has no steps
        prog.env_steps += max(0, int(steps or 0) - prev)

    def finish(slot: int, rec: dict) -> None:
        count_steps(slot, rec.get("steps", 0))
        active.pop(slot, None)
        pending.pop(slot, None)
        lat = measured.pop(slot, None)
        if rec.get("status") in ("ok", "error"):
            rec = dict(rec, policy_latency=policy_latency)
            if lat:
                rec["latency_s"] = {k: [round(v, 4) for v in vals] for k, vals in lat.items()}
        on_record(rec)
        prog.done += 1
        prog.successes += int(bool(rec.get("success")))
        prog.errors += int(rec.get("status") == "error")
        if rec.get("status") == "error":  # shown the moment it happens, not at the end of the run
            bar.write(f"error: {rec.get('task')} x {rec.get('perturbation')} seed {rec.get('seed')}: "
                      f"{' '.join(str(rec.get('error', '')).split())[:200]}", file=sys.stderr)
        bar.update(1)
        bar.set_postfix(postfix(), refresh=False)

    try:
        while queue or active:
            if skip is not None and queue:
                kept = [k for k in queue if not skip(k)]
                if len(kept) < len(queue):
                    prog.total -= len(queue) - len(kept)
                    bar.total, queue[:] = prog.total, kept
                    bar.refresh()
            starts = backend.assign([s for s in range(backend.n_slots) if s not in active], queue) if queue else {}
            if starts:
                for slot, obs in backend.start(starts).items():
                    if isinstance(obs, Failed):  # the worker could not even reset: that episode fails
                        finish(slot, obs.record)
                        continue
                    active[slot] = starts[slot]
                    pending[slot] = obs
                if not policy.env_side:
                    policy.reset(sorted(s for s in starts if s in active))
            commands: dict[int, np.ndarray | None] = {}
            aborts: dict[int, str] = {}
            delays: dict[int, int] = {}
            ready = sorted(s for s in active if not isinstance(pending[s], Unsupported))
            if policy.env_side or not ready:
                commands = {s: None for s in active}
                if policy.env_side and policy_latency != "0":  # a privileged policy thinks in no time: measured = 0
                    delays = {s: hold_steps(policy_latency, 0.0) for s in ready}
            else:
                t0 = time.perf_counter()
                try:
                    out = policy.act(backend.policy_input(ready, pending))
                except Exception as e:  # noqa: BLE001  a policy's failure fails these episodes, never the run
                    from realm_ms.eval.policies.policy import PolicyOutput

                    out = PolicyOutput(np.zeros((len(ready), 1, 8), np.float32), [f"{policy.spec()}: {type(e).__name__}: {e}"] * len(ready))
                wall = time.perf_counter() - t0
                actions, errors = check_output(out, len(ready), env_kwargs, policy.spec())
                lat, servers = getattr(out, "latency_s", None), getattr(out, "servers", None)  # server policies time each row
                lat = list(lat) if lat is not None and len(lat) == len(ready) else [wall] * len(ready)
                servers = list(servers) if servers is not None and len(servers) == len(ready) else [policy.spec()] * len(ready)
                for i, s in enumerate(ready):
                    if errors and errors[i]:
                        aborts[s] = errors[i]
                    else:  # a failed request's time (retries, timeouts) is not the policy's latency
                        measured.setdefault(s, {}).setdefault(servers[i], []).append(lat[i])
                        commands[s] = actions[i, :replan_every]
                        if policy_latency != "0":
                            delays[s] = hold_steps(policy_latency, lat[i])
                commands.update({s: None for s in active if s not in ready})
            if aborts:
                for slot, rec in backend.abort(aborts).items():
                    finish(slot, rec)
            stepped = backend.step(commands, delays) if any(delays.values()) else backend.step(commands)
            for slot, (obs, rec) in stepped.items():
                if rec is not None:
                    finish(slot, rec)
                else:
                    count_steps(slot, obs.get("steps", 0))
                    pending[slot] = obs
            bar.set_postfix(postfix(), refresh=False)
    finally:
        bar.close()
    return prog


def default_workers() -> int:
    return max(1, min(os.cpu_count() or 1, 16))


__all__ = ["RunConfig", "EpisodeHook", "HOOKED", "error_record", "run_plan", "build_cell_env", "cell_config", "Progress", "default_workers"]
