"""REALM task 3, REALM-RotateMug-v1: rotate the mug (skill "rotate")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-RotateMug-v1",
    skill="rotate",
    instruction="rotate the mug",
    description="Rotate a mug on an office desk by more than 1.1 rad about the vertical",
    scene="office",
    objects=(
        SceneObject("mug", O["mug"], role="main"),
        SceneObject("chocolate_bar", O["chocolate bar"]),
        SceneObject("tea_bag", O["tea bag"]),
        SceneObject("bag_of_cookies", O["bag of cookies"]),
    ),
    min_separation=0.04,
)

RotateMugEnv = register_task(SPEC)
