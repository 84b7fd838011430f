"""Stage predicates and the latched rubric on constructed states (no simulation)."""

from __future__ import annotations

import math

import pytest
import torch

from realm_ms.tasks.progression import RUBRICS, PREDICATES, ProgressionTracker, Stage, StageInputs, Thresholds, rotation_vector_z

T = Thresholds()
S = Stage


def yaw_q(a: float) -> torch.Tensor:
    return torch.tensor([[math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)]])


def state(**kw) -> StageInputs:
    """One env at rest: object at the origin, fingers 0.3 m above it, nothing touching."""
    base = dict(
        obj_pos=torch.zeros(1, 3), obj_pos0=torch.zeros(1, 3),
        finger_pos=torch.tensor([[[0.0, 0.04, 0.3], [0.0, -0.04, 0.3]]]),
        touching=torch.tensor([False]), grasped=torch.tensor([False]),
        obj_quat=yaw_q(0.0), obj_quat0=yaw_q(0.0),
        target_pos=torch.tensor([[0.3, 0.0, 0.0]]),
        placed_into=torch.tensor([False]), placed_onto=torch.tensor([False]),
        toggled=torch.tensor([False]), openness=torch.zeros(1), openness0=torch.zeros(1),
    )
    base.update(kw)
    return StageInputs(**base)


def holds(stage: Stage, x: StageInputs) -> bool:
    return bool(PREDICATES[stage](x, T)[0])


@pytest.mark.parametrize("stage", list(PREDICATES))
def test_no_stage_holds_at_rest(stage):
    x = state(extra={"opening": True})
    if stage in (S.CLOSE_JOINT_SMALL, S.CLOSE_JOINT_LARGE, S.CLOSE_JOINT_FULL):
        x.openness = x.openness0 = torch.ones(1)  # a closing task starts open
    assert not holds(stage, x)


def test_reach():
    assert holds(S.REACH, state(finger_pos=torch.tensor([[[0.0, 0.0, 0.099], [0.0, 0.0, 0.5]]])))
    assert not holds(S.REACH, state(finger_pos=torch.tensor([[[0.0, 0.0, 0.101], [0.0, 0.0, 0.5]]])))
    assert holds(S.REACH, state(touching=torch.tensor([True])))


def test_grasp_touch():
    assert holds(S.GRASP, state(grasped=torch.tensor([True])))
    assert not holds(S.GRASP, state(touching=torch.tensor([True])))  # touching is not grasping
    assert holds(S.TOUCH, state(touching=torch.tensor([True])))


def test_lifts_need_height_and_distance():
    assert holds(S.LIFT_SLIGHT, state(obj_pos=torch.tensor([[0.0, 0.0, 0.051]])))
    assert not holds(S.LIFT_SLIGHT, state(obj_pos=torch.tensor([[0.0, 0.0, 0.04]])))  # not moved 5 cm
    assert not holds(S.LIFT_SLIGHT, state(obj_pos=torch.tensor([[0.2, 0.0, 0.005]])))  # slid, not lifted
    assert holds(S.LIFT_LARGE, state(obj_pos=torch.tensor([[0.0, 0.0, 0.101]])))
    assert not holds(S.LIFT_LARGE, state(obj_pos=torch.tensor([[0.0, 0.08, 0.07]])))


def test_rotated_about_vertical():
    assert holds(S.ROTATED, state(obj_quat=yaw_q(1.2)))
    assert holds(S.ROTATED, state(obj_quat=yaw_q(-1.2)))
    assert not holds(S.ROTATED, state(obj_quat=yaw_q(1.0)))
    # a 1.5 rad tilt about x is not a rotation about the vertical
    tilt = torch.tensor([[math.cos(0.75), math.sin(0.75), 0.0, 0.0]])
    assert not holds(S.ROTATED, state(obj_quat=tilt))
    assert rotation_vector_z(yaw_q(0.5), yaw_q(-0.5)).item() == pytest.approx(1.0, abs=1e-5)


def test_move_close_and_place():
    assert holds(S.MOVE_CLOSE, state(obj_pos=torch.tensor([[0.2, 0.0, 0.0]])))
    assert not holds(S.MOVE_CLOSE, state(obj_pos=torch.tensor([[0.17, 0.0, 0.0]])))
    assert holds(S.PLACE_INTO, state(placed_into=torch.tensor([True])))
    assert not holds(S.PLACE_INTO, state(placed_into=torch.tensor([True]), grasped=torch.tensor([True])))
    assert holds(S.PLACE_ONTO, state(placed_onto=torch.tensor([True])))
    assert not holds(S.PLACE_ONTO, state(placed_onto=torch.tensor([True]), grasped=torch.tensor([True])))
    assert not holds(S.PLACE_ONTO, state(placed_into=torch.tensor([True])))


def test_toggled():
    assert holds(S.TOGGLED_ON, state(toggled=torch.tensor([True])))


def test_drawer_stages():
    t = torch.tensor([True])
    # opening: must touch AND have opened by > 0.025 of the range
    assert holds(S.TOUCH_AND_MOVE_JOINT, state(touching=t, openness=torch.tensor([0.03]), extra={"opening": True}))
    assert not holds(S.TOUCH_AND_MOVE_JOINT, state(touching=t, openness=torch.tensor([0.02]), extra={"opening": True}))
    assert not holds(S.TOUCH_AND_MOVE_JOINT, state(openness=torch.tensor([0.5]), extra={"opening": True}))
    # closing: moved the other way
    closing = dict(openness0=torch.ones(1), extra={"opening": False})
    assert holds(S.TOUCH_AND_MOVE_JOINT, state(touching=t, openness=torch.tensor([0.97]), **closing))
    assert not holds(S.TOUCH_AND_MOVE_JOINT, state(touching=t, openness=torch.tensor([1.0]), **closing))
    for stage, thr in zip((S.OPEN_JOINT_SMALL, S.OPEN_JOINT_LARGE, S.OPEN_JOINT_FULL), T.open_fractions):
        assert holds(stage, state(openness=torch.tensor([thr + 0.01])))
        assert not holds(stage, state(openness=torch.tensor([thr - 0.01])))
    for stage, thr in zip((S.CLOSE_JOINT_SMALL, S.CLOSE_JOINT_LARGE, S.CLOSE_JOINT_FULL), T.close_fractions):
        assert holds(stage, state(openness=torch.tensor([thr - 0.01])))
        assert not holds(stage, state(openness=torch.tensor([thr + 0.01])))


def test_rubrics_match_realm():
    assert [s.value for s in RUBRICS["put"]] == ["REACH", "GRASP", "LIFT_SLIGHT", "MOVE_CLOSE", "PLACE_INTO"]
    assert [s.value for s in RUBRICS["stack"]][-1] == "PLACE_ONTO"
    assert [s.value for s in RUBRICS["pick"]] == ["REACH", "GRASP", "LIFT_LARGE"]
    assert [s.value for s in RUBRICS["rotate"]] == ["REACH", "GRASP", "ROTATED"]
    assert [s.value for s in RUBRICS["push"]] == ["REACH", "TOUCH", "TOGGLED_ON"]
    assert len(RUBRICS["open_drawer"]) == len(RUBRICS["close_drawer"]) == 5


def test_tracker_latches_in_order():
    tr = ProgressionTracker("pick", 1, "cpu")
    near = torch.tensor([[[0.0, 0.0, 0.05], [0.0, 0.0, 0.05]]])
    # lifted without reach/grasp first: nothing counts (stages are consecutive)
    tr.update(state(obj_pos=torch.tensor([[0.0, 0.0, 0.2]])))
    assert tr.progression.item() == 0.0
    tr.update(state(finger_pos=near))
    assert tr.progression.item() == pytest.approx(1 / 3)
    tr.update(state(finger_pos=near, grasped=torch.tensor([True])))
    assert tr.progression.item() == pytest.approx(2 / 3)
    tr.update(state())  # REACH/GRASP latched: moving away keeps them
    assert tr.progression.item() == pytest.approx(2 / 3)
    tr.update(state(obj_pos=torch.tensor([[0.0, 0.0, 0.2]])))
    assert tr.progression.item() == 1.0 and bool(tr.success[0])
    assert tr.stalled_stage() == ["DONE"]
    tr.reset()
    assert tr.progression.item() == 0.0 and tr.stalled_stage() == ["REACH"]


def test_tracker_is_per_env():
    tr = ProgressionTracker("push", 2, "cpu")
    a, b = vars(state(touching=torch.tensor([True]))), vars(state())
    x2 = StageInputs(**{k: (torch.cat([a[k], b[k]]) if isinstance(a[k], torch.Tensor) else a[k]) for k in a})
    tr.update(x2)
    assert tr.progression.tolist() == pytest.approx([2 / 3, 0.0])
