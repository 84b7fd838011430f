"""Perturbations without a simulator: registry, ids, ranges, seeded per-sub-env draws, every cell
meaningful (each task x perturbation changes something), V-AUG / V-VIEW maths, the CLI table."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import torch

pytest.importorskip("mani_skill")

import realm_ms  # noqa: E402,F401
from realm_ms.perturbations import PERTURBATIONS, PerturbationSet, all_perturbations  # noqa: E402
from realm_ms.perturbations.v_aug import blur_contrast, blur_contrast_torch, gaussian_kernels  # noqa: E402
from realm_ms.registry import UnknownNameError  # noqa: E402
from realm_ms.tasks import TASKS  # noqa: E402

NAMES = ["Default", "V-AUG", "V-VIEW", "V-SC", "V-LIGHT", "S-PROP", "S-LANG", "S-MO", "S-AFF", "S-INT",
         "B-HOBJ", "SB-NOUN", "SB-VRB", "VB-POSE", "VB-MOBJ", "VSB-NOBJ"]
SCENE_CHANGING = {"V-SC", "V-VIEW", "SB-NOUN", "SB-VRB", "VB-MOBJ", "VSB-NOBJ"}
# perturbations whose effect is on the running episode (hooks), not on the task spec
EPISODE_HOOKS = {"V-AUG": "on_observation", "V-VIEW": "camera_pose", "V-LIGHT": "on_episode_init",
                 "B-HOBJ": "on_episode_init", "VB-POSE": "on_episode_init"}


def fake_env(env_id: str, seeds) -> SimpleNamespace:
    return SimpleNamespace(task_spec=TASKS[env_id], num_envs=len(seeds), _episode_seed=np.asarray(seeds))


def drawn(env_id: str, name, seeds) -> PerturbationSet:
    ps = PerturbationSet.resolve(name)
    ps.draw(fake_env(env_id, seeds), range(len(seeds)))
    return ps


def test_registry_ids_and_names():
    assert [p.name for p in all_perturbations()] == NAMES
    assert [p.pid for p in all_perturbations()] == list(range(16))
    for i, n in enumerate(NAMES):
        assert PERTURBATIONS.get(i) is PERTURBATIONS.get(n) is PERTURBATIONS.get(str(i))
        assert PERTURBATIONS.get(n.lower()).name == n
    with pytest.raises(UnknownNameError, match="V-LIGHT"):
        PERTURBATIONS.get("V-LITE")
    assert {p.name for p in all_perturbations() if p.reconfigure} == SCENE_CHANGING


def test_resolve_forms():
    assert PerturbationSet.resolve(None).names == ["Default"]
    assert PerturbationSet.resolve(0).names == ["Default"]
    assert PerturbationSet.resolve(4).names == ["V-LIGHT"]
    assert PerturbationSet.resolve(["V-LIGHT", 13]).names == ["V-LIGHT", "VB-POSE"]
    assert PerturbationSet.resolve("V-LIGHT+VB-POSE").name == "V-LIGHT+VB-POSE"
    assert PerturbationSet.resolve(["Default", "V-AUG", "V-AUG"]).names == ["V-AUG"]
    assert not PerturbationSet.resolve("V-LIGHT").needs_reconfigure
    assert PerturbationSet.resolve(["V-LIGHT", "V-SC"]).needs_reconfigure


@pytest.mark.parametrize("name", NAMES[1:])
def test_draws_seeded_per_sub_env(name):
    """Same episode seed -> same draw; other seeds (and other sub-envs of a batch) differ."""
    for env_id in ("REALM-PutBananaInBox-v1", "REALM-OpenDrawer-v1", "REALM-PushSwitch-v1"):
        a = drawn(env_id, name, [11, 12, 13, 14, 15, 16]).record()["params"]
        b = drawn(env_id, name, [11, 12, 13, 14, 15, 16]).record()["params"]
        assert a == b
        if name == "SB-VRB" and env_id != "REALM-PutBananaInBox-v1":
            continue  # open <-> close, push -> turn off: a single alternative verb, nothing to draw
        episodes = {json.dumps(drawn(env_id, name, [s]).record()["params"], sort_keys=True) for s in range(8)}
        assert len(episodes) > 1, f"{name} on {env_id}: eight episode seeds drew the same parameters"
        if name != "SB-VRB":  # its verb is one per batch (one rubric tracker); receivers are per sub-env
            distinct = {json.dumps(p, sort_keys=True) for p in a}
            assert len(distinct) > 1, f"{name} on {env_id}: six sub-envs drew the same parameters"


@pytest.mark.parametrize("env_id", sorted(TASKS))
def test_every_cell_is_meaningful(env_id):
    """Every task x perturbation changes something: the task (objects / instruction / skill) or, for
    the episode-level factors, it acts through a hook. Non-scene-changing factors never touch objects."""
    pristine = TASKS[env_id]
    for p in all_perturbations()[1:]:
        specs = drawn(env_id, p.name, [1, 2, 3, 4]).specs
        changed = [s != pristine for s in specs]
        if p.name in EPISODE_HOOKS:
            assert type(p).__dict__.get(EPISODE_HOOKS[p.name]) is not None
        else:
            assert all(changed), f"{p.name} leaves {env_id} unchanged"
        if not p.reconfigure:
            assert all(s.objects == pristine.objects for s in specs), f"{p.name} changed objects without reconfiguration"
        if p.name.startswith("S-"):
            assert all(s.skill == pristine.skill for s in specs)
            assert len({s.instruction for s in drawn(env_id, p.name, list(range(30))).specs}) >= 4
    assert TASKS[env_id] is pristine and TASKS[env_id] == pristine  # the registered task is never edited


def test_ranges_respected():
    env_id = "REALM-PickApple-v1"
    seeds = list(range(200))
    vaug = [p["V-AUG"] for p in drawn(env_id, "V-AUG", seeds).record()["params"]]
    assert all(0 <= v["sigma"] <= 2.5 and 0.25 <= v["alpha"] <= 1.5 for v in vaug)
    light = [p["V-LIGHT"] for p in drawn(env_id, "V-LIGHT", seeds).record()["params"]]
    assert all(2e4 <= v["intensity"] <= 7.5e5 for v in light)
    c = np.array([v["colours"] for v in light]).reshape(-1, 3) * 255
    assert np.allclose(c.mean(0), [255 * 0.97, 214, 170], atol=3)  # red clipped at 255
    view = [p["V-VIEW"]["exterior_1"] for p in drawn(env_id, "V-VIEW", seeds).record()["params"]]
    assert all(abs(v[k]) <= 0.2 for v in view for k in ("dx", "dy", "dz", "pitch", "yaw"))
    mobj = [p["VB-MOBJ"] for p in drawn(env_id, "VB-MOBJ", seeds).record()["params"]]
    assert all(np.prod(v["draw"]) <= 1.5 and all(0.5 <= s <= 1.5 for s in v["draw"]) for v in mobj)
    assert all(0.02 - 1e-9 <= e <= 0.175 + 1e-9 for v in mobj for e in v["extents"])
    hobj = [p["B-HOBJ"]["mass_scale"] for p in drawn(env_id, "B-HOBJ", seeds).record()["params"]]
    assert min(hobj) >= np.exp(-1) and max(hobj) <= np.exp(1)
    pose = [p["VB-POSE"]["dyaw"] for p in drawn(env_id, "VB-POSE", seeds).record()["params"]]
    assert 2.5 < np.std(pose) < 3.8
    drawer = [p["VB-POSE"]["dyaw"] for p in drawn("REALM-OpenDrawer-v1", "VB-POSE", seeds).record()["params"]]
    assert min(drawer) >= 0 and max(drawer) <= 0.57
    sw = [p["VB-POSE"] for p in drawn("REALM-PushSwitch-v1", "VB-POSE", seeds).record()["params"]]
    assert all(abs(v["dx"]) <= 0.075 and 0 <= v["dz"] <= 0.15 for v in sw)


def test_vsb_nobj_draws_only_objects_a_pinch_can_hold():
    """StackCubes caps the new object at 5 cm: a toothbrush shrunk that far is a 3.4 mm wide, 2.6 mm
    tall handle the pads slide over (seed 3 of the 10-seed table). Every side must be >= 5 mm."""
    from realm_ms.perturbations.common import GRASPABLE_MIN, graspable, object_spec

    assert not graspable([0.05, 0.0035, 0.0052]) and graspable([0.03, 0.03, 0.03])
    for p in drawn("REALM-StackCubes-v1", "VSB-NOBJ", list(range(40))).record()["params"]:
        d = p["VSB-NOBJ"]
        ext = object_spec(d["asset"]).extents * np.asarray(d["scale"])
        assert ext.min() >= GRASPABLE_MIN and ext.max() <= 0.05 + 1e-9, (d, ext)


def test_scene_factors_on_specs():
    from realm_ms.perturbations.common import object_spec

    # V-SC: 3 extra distractors of unseen categories, every distractor swapped, all <= 0.12 m
    for env_id in ("REALM-PickSpoon-v1", "REALM-PushSwitch-v1", "REALM-CloseDrawer-v1"):
        for s in drawn(env_id, "V-SC", [1, 2, 3]).specs:
            pristine = TASKS[env_id]
            clutter = [o for o in s.objects if o.name.startswith("clutter_")]
            assert len(clutter) == 3 and all(not object_spec(o.asset).record.seen for o in clutter)
            for o in s.objects:
                if o.role in ("distractor",) and not o.asset.startswith("articulated/"):
                    assert max(object_spec(o.asset).extents * np.asarray(o.scale)) <= 0.12 + 1e-6
                    old = next((p for p in pristine.objects if p.name == o.name), None)
                    assert old is None or old.asset != o.asset
            assert s.main == pristine.main and s.instruction == pristine.instruction
    # VSB-NOBJ: an unseen category, named in the instruction, <= 0.15 m
    for s in drawn("REALM-PickApple-v1", "VSB-NOBJ", [1, 2, 3]).specs:
        o = object_spec(s.main.asset)
        assert not o.record.seen and o.noun in s.instruction and "apple" not in s.instruction
        assert max(o.extents * np.asarray(s.main.scale)) <= 0.15 + 1e-6
    # SB-NOUN: the main object swaps with a distractor; the instruction names the new one
    for s in drawn("REALM-RotateMug-v1", "SB-NOUN", [1, 2, 3]).specs:  # (drawers: REALM's {middle, top})
        assert s.main.asset != TASKS["REALM-RotateMug-v1"].main.asset and "mug" not in s.instruction
    assert {s.instruction for s in drawn("REALM-OpenDrawer-v1", "SB-NOUN", list(range(10))).specs} == {
        "open the middle drawer", "open the top drawer"}
    # SB-VRB: the verb matrix, rubric follows
    skills = {drawn("REALM-PutGreenBlockInBowl-v1", "SB-VRB", [k]).specs[0].skill for k in range(20)}
    assert skills == {"pick", "rotate", "stack"}
    s = drawn("REALM-OpenDrawer-v1", "SB-VRB", [0]).specs[0]
    assert s.skill == "close_drawer" and s.instruction == "close the top drawer" and "open=1" in s.main.asset
    s = drawn("REALM-PushSwitch-v1", "SB-VRB", [0]).specs[0]
    assert s.instruction == "turn off the light switch" and "goal=off" in s.main.asset


def test_sb_vrb_receivers_fit_the_object():
    """A new verb's receiver lets its rubric finish: a 17 cm bottle gets a bowl deep enough for its
    centre to sink below the PLACE_INTO band, stacked centres stay within MOVE_CLOSE's distance."""
    from realm_ms.perturbations.common import object_spec
    from realm_ms.perturbations.sb_vrb import INTO_RIM_BAND, receiver_fits
    from realm_ms.tasks.progression import Thresholds

    bottle = (0.058, 0.058, 0.17)
    assert not receiver_fits("put", bottle, (0.15, 0.15, 0.046))  # a shallow bowl: centre 4 cm above the rim
    assert receiver_fits("put", bottle, (0.185, 0.185, 0.081))
    assert not receiver_fits("stack", bottle, (0.2, 0.15, 0.09))  # centres 13 cm apart once stacked
    seen = {}
    for env_id in ("REALM-PickWaterBottle-v1", "REALM-PickApple-v1", "REALM-RotateMarker-v1"):
        for k in range(40):
            s = drawn(env_id, "SB-VRB", [k]).specs[0]
            if s.skill not in ("put", "stack"):
                continue
            main = object_spec(s.main.asset).extents * np.asarray(s.main.scale)
            (t,) = s.by_role("target")
            recv = object_spec(t.asset).extents * np.asarray(t.scale)
            assert receiver_fits(s.skill, main, recv)
            if s.skill == "put":
                assert main[2] / 2 < recv[2] + INTO_RIM_BAND
            else:
                assert (main[2] + recv[2]) / 2 < Thresholds().move_close_dist
            seen[(env_id, s.skill)] = t.asset
    assert ("REALM-PickWaterBottle-v1", "put") in seen and ("REALM-PickWaterBottle-v1", "stack") in seen


def test_composition_keeps_each_draw():
    """A composition draws each factor from its own stream: the same params as alone, both applied."""
    both = drawn("REALM-OpenDrawer-v1", ["S-LANG", "VB-MOBJ"], [5, 6]).record()["params"]
    lang = drawn("REALM-OpenDrawer-v1", "S-LANG", [5, 6]).record()["params"]
    mobj = drawn("REALM-OpenDrawer-v1", "VB-MOBJ", [5, 6]).record()["params"]
    for i in range(2):
        assert both[i]["S-LANG"] == lang[i]["S-LANG"] and both[i]["VB-MOBJ"] == mobj[i]["VB-MOBJ"]
    s = drawn("REALM-OpenDrawer-v1", ["S-LANG", "VB-MOBJ"], [5]).specs[0]
    assert s.instruction == lang[0]["S-LANG"]["instruction"] and "sx=" in s.main.asset


def test_v_aug_blur_and_contrast():
    rng = np.random.default_rng(0)
    img = torch.as_tensor(rng.integers(0, 256, (3, 24, 32, 3)), dtype=torch.uint8)
    out = blur_contrast(img, torch.tensor([0.0, 0.0, 2.0]), torch.tensor([1.0, 0.5, 1.0]))
    assert out.dtype == torch.uint8 and out.shape == img.shape
    assert torch.equal(out[0], img[0])  # sigma 0, alpha 1: identity
    assert abs(out[1].float().mean() - img[1].float().mean() * 0.5) < 1.0  # contrast scales
    lap = lambda x: (x[1:-1, 1:-1].float() * 4 - x[:-2, 1:-1] - x[2:, 1:-1] - x[1:-1, :-2] - x[1:-1, 2:]).var()  # noqa: E731
    assert lap(out[2]) < 0.1 * lap(img[2])  # blurred: high frequencies gone
    assert abs(out[2].float().mean() - img[2].float().mean()) < 2.0  # blur keeps the mean
    # batched == one by one; the torch (GPU) path matches OpenCV's within uint8 rounding
    one = blur_contrast(img[2:3], torch.tensor([2.0]), torch.tensor([1.0]))
    assert torch.equal(one[0], out[2])
    both = blur_contrast_torch(img, torch.tensor([0.0, 0.0, 2.0]), torch.tensor([1.0, 0.5, 1.0]))
    assert (both.int() - out.int()).abs().max() <= 1
    # the kernel is OpenCV's: odd int(4 sigma + 1) taps
    k = gaussian_kernels(torch.tensor([1.0]))[0]
    assert int((k > 0).sum()) == 5 and abs(float(k.sum()) - 1) < 1e-6


def test_v_view_offsets_are_exact():
    from mani_skill.utils.structs.pose import Pose

    from realm_ms.perturbations.v_view import offset_pose

    base = Pose.create_from_pq(torch.tensor([[0.3, 0.7, 0.5]]), torch.tensor([[1.0, 0, 0, 0]]))
    d = torch.tensor([[0.1, -0.2, 0.05], [0.0, 0.0, 0.0]])
    out = offset_pose(base, d, torch.tensor([0.0, 0.2]), torch.tensor([0.2, 0.0]))
    assert torch.allclose(out.p, base.p + d)
    w, z = float(out.q[0, 0]), float(out.q[0, 3])  # yaw only: rotation about z by 0.2
    assert abs(2 * np.arctan2(z, w) - 0.2) < 1e-6
    w, y = float(out.q[1, 0]), float(out.q[1, 2])  # pitch only: about the camera's y by 0.2
    assert abs(2 * np.arctan2(y, w) - 0.2) < 1e-6


def test_cli_list(capsys):
    from realm_ms.cli import main

    assert main(["perturbations", "list", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == NAMES and all(r["ranges"] for r in rows)
    assert main(["perturbations", "list"]) == 0
    assert "VB-MOBJ" in capsys.readouterr().out
