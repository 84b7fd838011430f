"""Every REALM env id: create, reset, step (state and rgb obs), no vacuous stage, seeded resets."""

from __future__ import annotations

import numpy as np
import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.tasks import TASKS  # noqa: E402

ENV_IDS = sorted(TASKS)
EXPECTED = {
    "REALM-PutGreenBlockInBowl-v1", "REALM-PutBananaInBox-v1", "REALM-RotateMarker-v1", "REALM-RotateMug-v1",
    "REALM-PickSpoon-v1", "REALM-PickWaterBottle-v1", "REALM-PickApple-v1", "REALM-StackCubes-v1",
    "REALM-PushSwitch-v1", "REALM-OpenDrawer-v1", "REALM-CloseDrawer-v1",
}


def hold_action(env) -> torch.Tensor:
    u = env.unwrapped
    return torch.cat([u.agent.arm_qpos, torch.zeros(u.num_envs, 1)], 1)


def object_poses(env) -> np.ndarray:
    u = env.unwrapped
    return np.concatenate([o.pose.raw_pose.cpu().numpy().ravel() for o in u.objects.values()])


def test_all_env_ids_registered():
    assert EXPECTED <= set(ENV_IDS)
    for eid in EXPECTED:
        assert eid in gym.registry


def test_instructions_exact():
    want = {
        "REALM-PutGreenBlockInBowl-v1": "put the green block in the bowl",
        "REALM-PutBananaInBox-v1": "put the banana in the box",
        "REALM-RotateMarker-v1": "rotate the marker",
        "REALM-RotateMug-v1": "rotate the mug",
        "REALM-PickSpoon-v1": "pick up the spoon",
        "REALM-PickWaterBottle-v1": "pick up the water bottle",
        "REALM-PickApple-v1": "pick up the apple",
        "REALM-StackCubes-v1": "stack the green block on the yellow block",
        "REALM-PushSwitch-v1": "push the light switch",
        "REALM-OpenDrawer-v1": "open the top drawer",
        "REALM-CloseDrawer-v1": "close the top drawer",
    }
    for eid, instr in want.items():
        assert TASKS[eid].instruction == instr


def test_tasks_use_several_scenes():
    assert len({TASKS[e].scene for e in EXPECTED}) >= 4


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_state_env_holds_still_and_reproduces(env_id):
    env = gym.make(env_id, obs_mode="state")
    try:
        obs, info = env.reset(seed=7)
        assert torch.isfinite(obs).all()
        poses = object_poses(env)
        a = hold_action(env)
        for _ in range(25):
            obs, rew, term, trunc, info = env.step(a)
            assert float(info["progression"][0]) == 0.0, f"vacuous stage at rest: {env.unwrapped.stalled_stage()}"
        assert not bool(info["success"][0]) and not bool(term[0])
        assert {"progression", "success", "stalled_stage_index"} <= set(info)
        assert env.unwrapped.stalled_stage()[0] == env.unwrapped.tracker.stages[0].value
        # seeded resets reproduce the layout exactly; another seed differs
        env.reset(seed=7)
        np.testing.assert_array_equal(object_poses(env), poses)
        env.reset(seed=8)
        assert not np.array_equal(object_poses(env), poses)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rgb_env_tiny(env_id):
    env = gym.make(env_id, obs_mode="rgb", camera_width=64, camera_height=36)
    try:
        obs, _ = env.reset(seed=0)
        obs, *_ = env.step(hold_action(env))
        cams = obs["sensor_data"]
        for uid in ("exterior_1", "exterior_2"):
            rgb = cams[uid]["rgb"]
            assert rgb.shape == (1, 36, 64, 3)
            assert rgb.float().std() > 1.0, f"{uid} renders a flat image"
    finally:
        env.close()


def test_place_into_counts_a_tall_object_resting_in_the_bowl():
    """PLACE_INTO is REALM's Inside or OnTop: a 12 cm glass set down in a 7 cm bowl rests on its
    curved walls with its centre above the inside band, and still counts; where it stands on the
    table, or hovers over the bowl without touching it, it does not."""
    from realm_ms.tasks.objects import RigidTaskObject

    env = gym.make("REALM-PutGreenBlockInBowl-v1", obs_mode="state")
    env.reset(seed=0)
    u = env.unwrapped
    bowl, glass = u.target, u.objects["water_glass"]
    assert isinstance(glass, RigidTaskObject) and glass.extents[2] > bowl.extents[2] + 0.04
    for _ in range(5):
        env.step(hold_action(env))
    assert not bowl.holds(glass, u.scene).any()  # on the table where it spawned

    above = bowl.pose.p + torch.tensor([0.0, 0.0, bowl.extents[2] + 0.05])
    glass.set_pose(above, torch.zeros(1))
    assert not bowl.holds(glass, u.scene).any()  # over the bowl, touching nothing

    glass.set_pose(bowl.pose.p + torch.tensor([0.0, 0.0, 0.05]), torch.zeros(1))
    for _ in range(20):  # it drops onto the bowl's walls and settles
        env.step(hold_action(env))
    assert not bowl.contains(glass).any()  # its centre is above the rim + 2 cm band...
    assert bowl.holds(glass, u.scene).all()  # ...but it rests on the bowl
    env.close()
