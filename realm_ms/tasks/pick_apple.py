"""REALM-PickApple-v1: pick up the apple (REALM skill "pick": REACH -> GRASP -> LIFT_LARGE)."""

from realm_ms.tasks.spec import SceneObject, TaskSpec, register_task

SPEC = TaskSpec(
    env_id="REALM-PickApple-v1",
    skill="pick",
    instruction="pick up the apple",
    description="Pick the apple up from a table with a few household distractors and lift it by more than 7.5 cm",
    objects=(
        SceneObject("apple", "proc/apple/0", role="main"),
        SceneObject("bowl", "proc/bowl/1", region=(0.45, 0.75, -0.30, 0.30)),
        SceneObject("mug", "proc/mug/2"),
        SceneObject("can", "proc/can_of_soda/0"),
    ),
)

PickAppleEnv = register_task(SPEC)
