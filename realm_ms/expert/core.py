"""The scripted expert: per-env skill generators -> batched IK -> smooth ``droid_joint_pos`` actions."""

from __future__ import annotations

import math

import numpy as np
import torch

from realm_ms.expert.ik import ArmIK, top_down_rotation
from realm_ms.expert.primitives import Ctx, Target, hold

MAX_JOINT_STEP = 0.15  # rad per control step (DROID-like smooth targets at 15 Hz)


class Expert:
    """Privileged scripted policy for REALM envs (reads object poses from the env).

    Usage::

        expert = make_expert(env)          # after env.reset(...)
        action = expert.act()              # (num_envs, 8) torch tensor, droid_joint_pos
                                           # (or the env's DROID action space, see _in_action_space)

    ``reset()`` must be called after every ``env.reset`` (``run_episode`` does it).
    """

    def __init__(self, env, skill=None, max_joint_step: float = MAX_JOINT_STEP):
        from realm_ms.expert.skills import SKILLS

        self.env = env.unwrapped if hasattr(env, "unwrapped") else env
        if self.env.agent.control_mode != "droid_joint_pos":
            raise ValueError(f"the expert drives droid_joint_pos, env uses {self.env.agent.control_mode!r}")
        self._skill_arg = skill
        self.skill_name = skill or getattr(self.env, "active_spec", self.env.task_spec).skill
        self.skill = SKILLS[self.skill_name]
        self.max_joint_step = max_joint_step
        self.ik = ArmIK.from_agent(self.env.agent)
        self.reset()

    def reset(self) -> None:
        env = self.env
        if self._skill_arg is None:  # the task as perturbed this episode (SB-VRB changes the verb)
            from realm_ms.expert.skills import SKILLS

            self.skill_name = getattr(env, "active_spec", env.task_spec).skill
            self.skill = SKILLS[self.skill_name]
        n = env.num_envs
        self.base_p = env.agent.robot.pose.p.detach().cpu().clone()
        self.q_cmd = env.agent.arm_qpos.detach().cpu().double().clone()
        t = self.ik.tcp_fk(self.q_cmd)
        self.ctxs = []
        self.gens = []
        for i in range(n):
            c = Ctx(self, i)
            r = t[i, :3, :3]
            yaw = math.atan2(float(r[1, 1]), float(r[0, 1]))  # TCP y axis = closing direction
            c.cmd = Target(t[i, :3, 3].numpy().copy(), yaw, 0.0)
            self.ctxs.append(c)
            self.gens.append(self.skill(c))
        self.done = [False] * n

    def reset_rows(self, rows: list[int]) -> None:
        """Restart the script for the sub-envs ``rows`` only (after a partial reset of those rows).

        ``reset()`` restarts every row from the env's state; the other rows' per-row state (skill
        generators, contexts, commanded joints, base poses, done flags) is put back afterwards."""
        keep_lists = {a: list(getattr(self, a)) for a in ("ctxs", "gens", "done")}
        keep_rows = {a: getattr(self, a).clone() for a in ("q_cmd", "base_p")}
        self.reset()
        others = [i for i in range(self.env.num_envs) if i not in set(rows)]
        for a, old in keep_lists.items():
            new = getattr(self, a)
            for i in others:
                new[i] = old[i]
        for a, old in keep_rows.items():
            getattr(self, a)[others] = old[others]

    def _next(self, i: int) -> Target:
        if not self.done[i]:
            try:
                return next(self.gens[i])
            except StopIteration:
                self.done[i] = True
                self.gens[i] = hold(self.ctxs[i], 10**9)
        return next(self.gens[i])

    def act(self, obs=None) -> torch.Tensor:
        targets = [self._next(i) for i in range(self.env.num_envs)]
        p = torch.as_tensor(np.stack([t.p for t in targets]), dtype=torch.float64)
        yaw = torch.as_tensor([t.yaw for t in targets], dtype=torch.float64)
        q_ik, _ = self.ik.solve(self.q_cmd, p, top_down_rotation(yaw))
        dq = (q_ik - self.q_cmd).clamp(-self.max_joint_step, self.max_joint_step)
        self.q_cmd = self.q_cmd + dq
        g = torch.as_tensor([[t.grip] for t in targets], dtype=torch.float64)
        return self._in_action_space(torch.cat([self.q_cmd, g], 1)).float().to(self.env.device)

    def _in_action_space(self, target: torch.Tensor) -> torch.Tensor:
        """The joint target as an action of the env's DROID action space (joint velocity, Cartesian
        velocity or pose, gripper velocity: ``DroidActionSpace.from_joint_target``)."""
        conv = getattr(self.env, "droid_actions", None)
        if conv is None:
            return target
        agent = self.env.agent
        q = agent.arm_qpos.detach().cpu().double().numpy()
        g = agent.gripper_position.detach().cpu().double().numpy()
        return torch.as_tensor(conv.space.from_joint_target(target.numpy(), q, g, conv.ik))

    __call__ = act


def make_expert(env, skill: str | None = None, **kw) -> Expert:
    return Expert(env, skill=skill, **kw)


def start_episode(env, seed: int, expert: Expert | None = None) -> tuple:
    """Reset ``env`` with ``seed`` and return (obs, expert): a new expert, or ``expert`` reset for the
    new episode, as the evaluation runner reuses one."""
    obs, _ = env.reset(seed=seed)
    if expert is None:
        return obs, make_expert(env.unwrapped)
    expert.reset()
    return obs, expert


def run_episode(env, seed: int, max_steps: int | None = None, expert: Expert | None = None, on_step=None) -> dict:
    """Reset ``env`` (num_envs = 1) with ``seed`` and run the expert on the episode engine until the
    episode ends (success + tail, truncation, ``max_steps`` (default: the task horizon), or the end
    of the script); ``on_step(env, obs, info)`` after every step. ``expert``: one to reuse
    (``reset()`` for the new episode), as the evaluation runner does.

    Returns ``dict(progression, success, stalled_stage, steps, log)``."""
    from realm_ms.tasks.episode import Episode, EpisodeEngine

    hook = None if on_step is None else (lambda step: on_step(env, step.obs, step.info))
    engine = EpisodeEngine(env, actor=expert, after_step=hook)
    ep = Episode(seed=seed, max_steps=max_steps or env.unwrapped.task_spec.horizon)
    engine.reset({0: ep})
    if engine.actor is None:  # built on the env after its reset
        engine.actor = make_expert(env.unwrapped)
    engine.run(ep.max_steps)
    return dict(progression=ep.best, success=ep.success, stalled_stage=ep.stalled, steps=ep.steps, log=list(engine.actor.ctxs[0].log))
