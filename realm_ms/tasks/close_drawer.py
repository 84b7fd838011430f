"""REALM task 9, REALM-CloseDrawer-v1: close the top drawer (skill "close_drawer").

Same cabinet as REALM-OpenDrawer-v1; the top drawer starts fully open (REALM's
``INIT_OPENNESS_FRACTION = 1.0``).
"""

from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-CloseDrawer-v1",
    skill="close_drawer",
    instruction="close the top drawer",
    description="Close the fully open top drawer of a cabinet standing on the table (openness below 5 %)",
    scene="pomaria",
    objects=(
        SceneObject("cabinet", "articulated/drawer_cabinet?open=1", role="main", region=(0.505, 1.195, -0.366, 0.366), yaw=(-0.15, 0.15)),
    ),
)

CloseDrawerEnv = register_task(SPEC)
