"""REALM-PickApple-v1: pick up the apple (REALM skill "pick": REACH -> GRASP -> LIFT_LARGE)."""

from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PickApple-v1",
    skill="pick",
    instruction="pick up the apple",
    description="Pick the apple up from a table with a few household distractors and lift it by more than 7.5 cm",
    objects=(
        SceneObject("apple", "real/apple", role="main"),
        SceneObject("bowl", "real/bowl", region=(0.45, 0.75, -0.30, 0.30)),
        SceneObject("mug", "proc/mug/2"),
        SceneObject("can", "proc/can_of_soda/0"),
    ),
)

PickAppleEnv = register_task(SPEC)
