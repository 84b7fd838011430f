"""REALM task 4, REALM-PickSpoon-v1: pick up the spoon (a teaspoon; skill "pick")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PickSpoon-v1",
    skill="pick",
    instruction="pick up the spoon",
    description="Pick a teaspoon up from a dining table with a soda can, half an apple, a beaker, a plate and a tray",
    scene="living_room",
    objects=(
        SceneObject("teaspoon", O["teaspoon"], role="main"),
        SceneObject("can_of_soda", O["can of soda"]),
        SceneObject("half_apple", O["half apple"]),
        SceneObject("beaker", O["beaker"]),
        SceneObject("plate", O["plate"], role="fixture", pose=(0.90, 0.50, 0.002, 0.0)),  # REALM immutables
        SceneObject("tray", O["tray"], role="fixture", pose=(0.88, -0.52, 0.002, 1.5708)),
    ),
    spawn_region=(0.30, 0.74, -0.36, 0.36),
    min_separation=0.03,
)

PickSpoonEnv = register_task(SPEC)
