"""Per-episode material variants of the household scenes: drawn from the episode seed (same seed,
same look; seeds vary), applied to the built scene's slot materials, physics-neutral, and off with
``materials=nominal`` (the scene's own look, as before)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

gym = pytest.importorskip("gymnasium")
pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.tasks.scenes import get_scene, household  # noqa: E402
from realm_ms.tasks.scenes import textures as tx  # noqa: E402

TASK = "REALM-StackCubes-v1"  # kitchen


@pytest.fixture(scope="module")
def env():
    e = gym.make(TASK, obs_mode="state")
    yield e
    e.close()


def _looks(e, seed):
    e.reset(seed=seed)
    return dict(e.unwrapped.scene_looks[0])


def _slot_shows(e, slot, variant):
    """The slot material of sub-env 0 carries ``variant``'s texture (or its colour without a render device)."""
    u = e.unwrapped
    key, make, fallback = u.scene_def._texture(u.scene_def.slot_specs(slot)[variant])
    m = u.scene_slots[0][slot]
    if key in tx._TEXTURES:
        return np.array_equal(np.asarray(m.base_color_texture.download())[..., :3], make()[..., :3])
    return list(m.base_color) == pytest.approx(list(fallback))


def test_slot_variants_are_the_scene_look_then_its_palette():
    for name in ("kitchen", "dining_room", "office", "living_room", "pomaria"):
        s = get_scene(name)
        for slot in household.SLOTS:
            specs = s.slot_specs(slot)
            assert len(specs) == household.MATERIAL_VARIANTS
            assert len({(a, b) for _, a, b, _ in specs}) == len(specs), (name, slot)  # distinct looks
            assert len({k for k, *_ in specs}) == 1  # a table stays wood, a floor stays tiles
            assert specs == s.slot_specs(slot)  # fixed per scene
        assert s.slot_specs("table")[0][:3] == (s.table_tex[0], tuple(s.table_tex[1]), tuple(s.table_tex[2]))


def test_same_seed_same_material_and_seeds_vary(env):
    draws = {seed: _looks(env, seed) for seed in range(8)}
    assert len({tuple(sorted(d.items())) for d in draws.values()}) >= 4  # seeds vary
    for slot in household.SLOTS:
        assert len({d[slot] for d in draws.values()}) >= 2, slot
    # the same seed again, after other episodes and simulated steps: the same look
    hold = torch.cat([env.unwrapped.agent.arm_qpos, torch.zeros(1, 1)], 1)
    env.step(hold)
    assert _looks(env, 5) == draws[5]
    for slot, v in draws[5].items():
        assert _slot_shows(env, slot, v), slot
    fresh = gym.make(TASK, obs_mode="state")
    try:
        assert _looks(fresh, 5) == draws[5]
    finally:
        fresh.close()


def test_nominal_keeps_the_scene_look_and_draws_change_no_physics(env):
    nominal = gym.make(TASK, obs_mode="state", scene="kitchen?materials=nominal")
    try:
        for seed in (0, 1, 2):
            assert _looks(nominal, seed) == {slot: 0 for slot in household.SLOTS}
            for slot in household.SLOTS:
                assert _slot_shows(nominal, slot, 0) and not _slot_shows(nominal, slot, 1)
            env.reset(seed=seed)
            for k, o in env.unwrapped.objects.items():  # the draw shifts no placement
                assert torch.equal(o.pose.raw_pose, nominal.unwrapped.objects[k].pose.raw_pose), k
    finally:
        nominal.close()


@pytest.mark.render
def test_drawn_material_is_what_the_camera_sees():
    """Same seed, same frame; a seed whose draw is not the nominal look renders differently from the
    nominal scene with the same layout."""
    kw = dict(obs_mode="rgb", camera_width=64, camera_height=36)
    e = gym.make(TASK, **kw)
    n = gym.make(TASK, scene="kitchen?materials=nominal", **kw)
    try:
        seed = next(s for s in range(20) if _looks(e, s)["table"] != 0)
        f1 = e.reset(seed=seed)[0]["sensor_data"]["exterior_1"]["rgb"][0].numpy()
        f2 = e.reset(seed=seed)[0]["sensor_data"]["exterior_1"]["rgb"][0].numpy()
        fn = n.reset(seed=seed)[0]["sensor_data"]["exterior_1"]["rgb"][0].numpy()
        assert np.array_equal(f1, f2)
        assert np.abs(f1.astype(int) - fn.astype(int)).mean() > 2.0
    finally:
        e.close()
        n.close()
