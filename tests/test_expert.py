"""The scripted expert solves every REALM task on a fixed seed (CPU sim, state obs)."""

from __future__ import annotations


import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.expert import SKILLS, make_expert, run_episode  # noqa: E402
from realm_ms.expert.ik import ArmIK, top_down_rotation  # noqa: E402
from realm_ms.tasks import TASKS  # noqa: E402

SEED = 0


def test_every_skill_has_an_expert():
    assert {t.skill for t in TASKS.values()} <= set(SKILLS)


def test_ik_round_trip():
    env = gym.make("REALM-PickApple-v1", obs_mode="state")
    try:
        env.reset(seed=0)
        ik = ArmIK.from_agent(env.unwrapped.agent)
        q0 = env.unwrapped.agent.arm_qpos.double()
        tcp = env.unwrapped.agent.tcp_pose.p.double() - env.unwrapped.agent.robot.pose.p.double()
        assert torch.allclose(ik.tcp_fk(q0)[:, :3, 3], tcp, atol=1e-4)  # model TCP = simulated TCP
        p = torch.tensor([[0.55, 0.15, 0.05]], dtype=torch.float64)
        r = top_down_rotation(torch.tensor([0.3], dtype=torch.float64))
        q, err = ik.solve(q0, p, r, iters=60)
        assert err.item() < 1e-3
        assert torch.allclose(ik.tcp_fk(q)[:, :3, :3], r, atol=1e-3)
    finally:
        env.close()


def test_expert_actions_are_smooth():
    env = gym.make("REALM-PickApple-v1", obs_mode="state")
    try:
        obs, _ = env.reset(seed=SEED)
        ex = make_expert(env)
        prev = env.unwrapped.agent.arm_qpos.clone()
        for _ in range(40):
            a = ex.act(obs)
            assert a.shape == (1, 8) and 0.0 <= float(a[0, 7]) <= 1.0
            assert (a[:, :7] - prev).abs().max() <= ex.max_joint_step + 1e-5
            prev = a[:, :7].clone()
            obs, *_ = env.step(a)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_expert_solves_fixed_seed(env_id):
    env = gym.make(env_id, obs_mode="state")
    try:
        res = run_episode(env, SEED)
        assert res["progression"] == 1.0, res
        assert res["success"] and res["stalled_stage"] == "DONE"
        assert res["steps"] < 400
    finally:
        env.close()


@pytest.mark.slow
@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_expert_five_seeds(env_id):
    env = gym.make(env_id, obs_mode="state")
    try:
        results = [run_episode(env, s) for s in range(1, 6)]
        assert sum(r["progression"] == 1.0 for r in results) >= 4, results
    finally:
        env.close()
