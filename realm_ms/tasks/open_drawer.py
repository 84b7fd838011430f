"""REALM task 8, REALM-OpenDrawer-v1: open the top drawer (skill "open_drawer").

A three-drawer cabinet (``realm_ms.tasks.articulated.drawer_cabinet``) stands on the table facing
the robot; all drawers start closed. The region is where the cabinet's whole footprint must lie, so
its centre varies by a few centimetres; yaw varies by +-0.15 rad.
"""

from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-OpenDrawer-v1",
    skill="open_drawer",
    instruction="open the top drawer",
    description="Open the top drawer of a cabinet standing on the table by more than 95 % of its travel",
    scene="pomaria",
    objects=(
        SceneObject("cabinet", "articulated/drawer_cabinet?open=0", role="main", region=(0.505, 1.195, -0.366, 0.366), yaw=(-0.15, 0.15)),
    ),
)

OpenDrawerEnv = register_task(SPEC)
