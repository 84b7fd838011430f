"""REALM task 7, REALM-PushSwitch-v1: push the light switch (skill "push": REACH -> TOUCH -> TOGGLED_ON).

The switch is our rocker switch (``realm_ms.tasks.articulated.light_switch``), physically toggled
by pressing its raised end past the centre. Mounted as the scene says: on a wall panel standing on
the table (REALM; the kitchen's default) or on the table (``scene="kitchen?switch_mount=table"``).
"""

from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-PushSwitch-v1",
    skill="push",
    instruction="push the light switch",
    description="Press a rocker light switch (on a wall panel, or on the table) so that it turns on",
    scene="kitchen",
    objects=(
        SceneObject("light_switch", "articulated/light_switch", role="main", region=(0.42, 0.68, -0.20, 0.20), yaw=(-0.5, 0.5)),
    ),
)

PushSwitchEnv = register_task(SPEC)
