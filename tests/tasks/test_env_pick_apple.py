"""REALM-PickApple-v1 as a ManiSkill env: spaces, obs modes, rendering, recording, determinism."""

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

import realm_ms  # noqa: F401

ENV = "REALM-PickApple-v1"
SMALL = dict(camera_width=64, camera_height=36)


def hold_action(env, gripper=0.0):
    return torch.cat([env.unwrapped.agent.arm_qpos[0], torch.tensor([gripper])])


def test_spaces_and_state_obs():
    env = gym.make(ENV, obs_mode="state", control_mode="droid_joint_pos")
    obs, info = env.reset(seed=0)
    u = env.unwrapped
    assert env.action_space.shape == (8,)
    lo, hi = env.action_space.low, env.action_space.high
    np.testing.assert_allclose(lo[:7], [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973], atol=1e-4)
    assert (lo[7], hi[7]) == (0.0, 1.0)  # gripper command, 1 = closed
    assert obs.shape == (1, env.observation_space.shape[-1]) and torch.isfinite(obs).all()
    assert u.agent.droid_state().shape == (1, 8)
    assert u.control_mode == "droid_joint_pos" and u.sim_freq == 120 and u.control_freq == 15
    assert u.get_language_instruction() == ["pick up the apple"]
    assert set(["progression", "success", "stage_reach", "stage_grasp", "stage_lift_large"]) <= set(info)
    env.close()


@pytest.mark.parametrize("mode", ["pd_joint_pos", "pd_joint_delta_pos", "pd_ee_delta_pose"])
def test_maniskill_control_modes_move_the_robot(mode):
    env = gym.make(ENV, obs_mode="state", control_mode=mode)
    env.reset(seed=0)
    u = env.unwrapped
    q0, p0 = u.agent.arm_qpos[0].clone(), u.agent.tcp_pose.p[0].clone()
    a = torch.zeros(env.action_space.shape)
    if mode == "pd_joint_pos":
        a[:7] = q0 + 0.1
    elif mode == "pd_joint_delta_pos":
        a[0] = 0.5  # normalised: +0.05 rad per step on joint 1
    else:
        a[0] = 1.0  # normalised: +0.1 m along x per step (clipped by the PD tracking)
    for _ in range(10):
        env.step(a)
    dq = u.agent.arm_qpos[0] - q0
    if mode == "pd_joint_pos":
        assert (dq - 0.1).abs().max() < 0.02, dq
    elif mode == "pd_joint_delta_pos":
        assert dq[0] > 0.2 and dq[1:].abs().max() < 0.05, dq
    else:
        dp = u.agent.tcp_pose.p[0] - p0
        assert dp[0] > 0.05 and dp[1:].abs().max() < 0.5 * dp[0], dp
    env.close()


@pytest.mark.parametrize("obs_mode,textures", [("rgb", {"rgb"}), ("rgb+depth", {"rgb", "depth"}), ("rgb+segmentation", {"rgb", "segmentation"})])
def test_visual_obs_modes(obs_mode, textures):
    env = gym.make(ENV, obs_mode=obs_mode, **SMALL)
    obs, _ = env.reset(seed=0)
    obs, *_ = env.step(hold_action(env))
    assert set(obs["sensor_data"]) == {"exterior_1", "exterior_2", "wrist"}
    for cam, data in obs["sensor_data"].items():
        assert textures <= set(data), (cam, data.keys())
        assert data["rgb"].shape == (1, 36, 64, 3) and data["rgb"].dtype == torch.uint8
        assert data["rgb"].float().std() > 5, f"{cam} image is blank"
    if "segmentation" in textures:
        seg = obs["sensor_data"]["wrist"]["segmentation"]
        assert len(torch.unique(seg)) > 2
    env.close()


def test_render_rgb_array_and_record_episode(tmp_path):
    from mani_skill.utils.wrappers import RecordEpisode

    env = gym.make(ENV, obs_mode="state", render_mode="rgb_array", max_episode_steps=6)
    env = RecordEpisode(env, str(tmp_path), save_video=True, save_trajectory=True, video_fps=15)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape[-1] == 3 and frame.shape[-3:-1] == (360, 640)
    a = hold_action(env)
    for _ in range(6):
        env.step(a)
    env.close()
    assert list(tmp_path.glob("*.mp4")) and list(tmp_path.glob("*.h5"))
    meta = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert meta["env_info"]["env_id"] == ENV


@pytest.mark.render
def test_seeded_reset_is_reproducible_and_seeds_differ():
    env = gym.make(ENV, obs_mode="state")
    u = env.unwrapped

    def layout(seed):
        env.reset(seed=seed)
        return torch.cat([o.pose.raw_pose for o in u.objects.values()])

    a, b, c = layout(7), layout(7), layout(8)
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    assert (a - c).abs().max() > 0.01

    def rollout(seed):
        env.reset(seed=seed)
        act = hold_action(env) + torch.tensor([0.05] * 7 + [1.0])
        for _ in range(10):
            env.step(act)
        return u.agent.robot.get_qpos().clone(), u.main.pose.raw_pose.clone()

    (q1, p1), (q2, p2) = rollout(3), rollout(3)
    torch.testing.assert_close(q1, q2, rtol=0, atol=1e-6)
    torch.testing.assert_close(p1, p2, rtol=0, atol=1e-6)
    env.close()


def test_progression_zero_at_reset_and_while_holding_still():
    env = gym.make(ENV, obs_mode="state")
    for seed in range(3):
        _, info = env.reset(seed=seed)
        assert info["progression"].item() == 0
        a = hold_action(env)
        for _ in range(30):
            _, _, term, trunc, info = env.step(a)
        assert info["progression"].item() == 0, f"seed {seed}: a stage latched without motion: {info}"
        assert not term.any()
    env.close()


def test_gripper_opens_and_closes_in_env():
    env = gym.make(ENV, obs_mode="state")
    env.reset(seed=0)
    u = env.unwrapped
    assert u.agent.gripper_position.item() < 0.05
    close = hold_action(env, 1.0)
    for _ in range(15):
        env.step(close)
    closed = u.agent.gripper_position.item()
    for _ in range(15):
        env.step(hold_action(env, 0.0))
    assert closed > 0.9 and u.agent.gripper_position.item() < 0.05
    env.close()


def test_horizon_is_configurable_and_truncates():
    env = gym.make(ENV, obs_mode="state", max_episode_steps=4)
    env.reset(seed=0)
    a = hold_action(env)
    truncs = [env.step(a)[3].item() for _ in range(4)]
    assert truncs == [False, False, False, True]
    assert gym.spec(ENV).max_episode_steps == 800  # REALM's paper horizon by default
    env.close()


def test_bad_robot_model_path_is_a_clear_error(tmp_path):
    with pytest.raises(Exception, match="missing.yaml"):
        gym.make(ENV, obs_mode="state", robot_model=str(tmp_path / "missing.yaml"))


def test_scripted_pick_reaches_full_progression():
    from realm_ms.expert import run_episode

    env = gym.make(ENV, obs_mode="state")
    res = run_episode(env, seed=0, max_steps=300)
    assert res["progression"] == 1.0 and res["success"], res
    u = env.unwrapped
    assert u.tracker.met.all()
    # the lift is real: the apple is >7.5 cm above where it settled
    assert (u.main.anchor_pos() - u._obj_pos0)[0, 2] > 0.075
    env.close()


def test_demo_runs_the_quick_protocol_and_writes_reports(tmp_path):
    from realm_ms.cli import main

    rc = main(["demo", "--tasks", ENV, "--perturbations", "Default", "--out", str(tmp_path), "--max-steps", "120"])
    assert rc == 0
    (rec,) = [json.loads(line) for line in (tmp_path / "expert" / "records.jsonl").read_text().splitlines()]
    assert rec["task"] == ENV and rec["success"] and rec["progression"] == 1.0
    steps = rec["stages"]
    assert steps["REACH"] <= steps["GRASP"] <= steps["LIFT_LARGE"]
    assert Path(rec["video"]).stat().st_size > 10_000
    assert json.loads((tmp_path / "expert" / "metrics.json").read_text())["overall"]["success_rate"] == 1.0
    assert (tmp_path / "lerobot_tiny" / "records.jsonl").read_text().count("\n") == 1
    index = (tmp_path / "index.html").read_text()
    assert "expert/report.html" in index and "lerobot_tiny/report.html" in index


def test_robot_model_payload_sags_as_the_impedance_law_predicts(tmp_path):
    """A MODEL.yaml with an unmodelled 1 kg payload loads into the env (effects + the presets it was
    fitted on) and makes the arm sag by K_p^-1 J^T m g: the identified model is the model that runs."""
    import yaml

    offset = [0.0, 0.0, 0.15]
    model = {"gains": "polymetis", "joint_physics": "none", "physics_hz": 120,
             "effects": [{"name": "payload", "params": {"mass": 1.0}, "config": {"offset": offset}}]}
    path = tmp_path / "MODEL.yaml"
    path.write_text(yaml.safe_dump(model))
    env = gym.make(ENV, obs_mode="state", robot_model=str(path))
    env.reset(seed=0)
    u = env.unwrapped
    drv = u.agent.arm_controller.driver
    assert drv.joint_physics.friction == (0.0,) * 7  # the preset the model was fitted on
    q0 = u.agent.arm_qpos[0].clone()
    for _ in range(45):
        env.step(torch.cat([q0, torch.zeros(1)]))
    sag = u.agent.arm_qpos[0] - q0
    m = drv.model
    q = q0[None]
    flange = m.fk(q)[0]
    r = flange[:3, :3] @ torch.tensor(offset)
    jac = m.jacobian(q)[0]
    j_point = jac[:3] - torch.linalg.cross(r.expand(7, 3), jac[3:].T, dim=-1).T
    tau = j_point.T @ torch.tensor([0.0, 0.0, -9.81])
    g = drv.gains
    kp = torch.diag(g.kq[0]) + jac.T @ torch.diag(g.kx[0]) @ jac
    predicted = torch.linalg.solve(kp, tau)
    assert predicted.abs().max() > 5e-3  # a visible effect
    torch.testing.assert_close(sag, predicted, atol=0.2 * predicted.abs().max().item(), rtol=0)
    env.close()


def test_gripper_state_does_not_leak_across_resets():
    """A gripper closed at the end of one episode is open in the next (the drive target is reset)."""
    env = gym.make(ENV, obs_mode="state")
    env.reset(seed=0)
    u = env.unwrapped
    for _ in range(15):
        env.step(hold_action(env, 1.0))
    assert u.agent.gripper_position.item() > 0.9
    env.reset(seed=1)
    for _ in range(10):
        env.step(hold_action(env, 0.0))
    assert u.agent.gripper_position.item() < 0.05
    env.close()
