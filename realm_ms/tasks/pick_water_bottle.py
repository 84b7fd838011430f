"""REALM task 5, REALM-PickWaterBottle-v1: pick up the water bottle (skill "pick")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PickWaterBottle-v1",
    skill="pick",
    instruction="pick up the water bottle",
    description="Pick a standing water bottle up from a dining table with a lid, an orange, a bowl and a frying pan",
    scene="dining_room",
    objects=(
        SceneObject("bottle_of_water", O["water bottle"], role="main"),
        SceneObject("lid", O["lid"]),
        SceneObject("orange", O["orange"]),
        SceneObject("bowl", O["bowl"]),
        SceneObject("frying_pan", O["frying pan"], role="fixture", pose=(0.86, -0.56, 0.002, 0.0)),  # REALM immutable
    ),
    spawn_region=(0.30, 0.82, -0.40, 0.40),
    min_separation=0.03,
)

PickWaterBottleEnv = register_task(SPEC)
