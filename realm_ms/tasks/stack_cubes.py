"""REALM task 6, REALM-StackCubes-v1: stack the green block on the yellow block (skill "stack")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-StackCubes-v1",
    skill="stack",
    instruction="stack the green block on the yellow block",
    description="Stack a 3 cm green cube on a 3 cm yellow cube among dice and other coloured cubes",
    scene="kitchen",
    objects=(
        SceneObject("green_block", O["green cube"], role="main"),
        SceneObject("yellow_block", O["yellow cube"], role="target"),
        SceneObject("toy_dice_0", O["dice"]),
        SceneObject("blue_block", O["blue cube"]),
        SceneObject("toy_dice_1", "proc/dice/1?color=red", role="fixture", pose=(0.80, 0.42, 0.002, 0.3)),  # REALM immutables
        SceneObject("orange_block", O["orange cube"], role="fixture", pose=(0.78, -0.40, 0.002, -0.2)),
    ),
    min_separation=0.04,
)

StackCubesEnv = register_task(SPEC)
