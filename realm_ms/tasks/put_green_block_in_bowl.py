"""REALM task 0, REALM-PutGreenBlockInBowl-v1: put the green block in the bowl (skill "put")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PutGreenBlockInBowl-v1",
    skill="put",
    instruction="put the green block in the bowl",
    description="Put a 3 cm green cube into a bowl on a dining table set with glasses, a wine bottle and cutlery",
    scene="dining_room",
    init_qpos=(0.0056, -0.4623, -0.1084, -2.2245, -0.0222, 1.6369, -0.2847),  # REALM task 0 reset pose
    objects=(
        SceneObject("green_block", O["green cube"], role="main"),
        SceneObject("bowl", O["bowl"], role="target", region=(0.35, 0.75, -0.30, 0.30)),
        SceneObject("corkscrew", O["corkscrew"]),
        SceneObject("table_knife", O["knife"]),
        SceneObject("wineglass", O["wineglass"]),
        SceneObject("water_glass", O["water glass"]),
        SceneObject("bottle_of_wine", O["wine bottle"], region=(0.55, 0.85, -0.40, 0.40)),
    ),
    spawn_region=(0.30, 0.80, -0.40, 0.40),
    min_separation=0.03,
)

PutGreenBlockInBowlEnv = register_task(SPEC)
