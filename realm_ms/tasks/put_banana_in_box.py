"""REALM task 1, REALM-PutBananaInBox-v1: put the banana in the box (skill "put"; REALM's "box" is a tray)."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PutBananaInBox-v1",
    skill="put",
    instruction="put the banana in the box",
    description="Put a banana into a shallow box (REALM uses a tray) on an office table with fruit and dice",
    scene="office",
    objects=(
        SceneObject("banana", O["banana"], role="main"),
        SceneObject("box", O["tray"], role="target"),
        SceneObject("orange", O["orange"]),
        SceneObject("lemon", O["lemon"]),
        SceneObject("toy_dice_0", O["dice"]),
        SceneObject("toy_dice_1", "proc/dice/1?color=red"),
    ),
    spawn_region=(0.30, 0.80, -0.46, 0.46),
    min_separation=0.03,
)

PutBananaInBoxEnv = register_task(SPEC)
