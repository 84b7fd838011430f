"""REALM task 2, REALM-RotateMarker-v1: rotate the marker (lying on the counter; skill "rotate")."""

from realm_ms.assets import TASK_OBJECTS as O
from realm_ms.tasks.env import register_task
from realm_ms.tasks.task_spec import SceneObject, TaskSpec

SPEC = TaskSpec(
    env_id="REALM-RotateMarker-v1",
    skill="rotate",
    instruction="rotate the marker",
    description="Rotate a marker lying on a kitchen counter by more than 1.1 rad about the vertical",
    scene="kitchen",
    objects=(
        SceneObject("marker", O["marker"], role="main"),
        SceneObject("ticket", O["ticket"]),
        SceneObject("bowl", O["bowl"]),
        SceneObject("jar_of_puree", O["jar"]),
        SceneObject("teaspoon", O["teaspoon"]),
        SceneObject("plate", O["plate"], role="fixture", pose=(0.90, -0.55, 0.002, 0.0)),  # REALM immutable
    ),
    spawn_region=(0.30, 0.80, -0.40, 0.38),
    min_separation=0.03,
)

RotateMarkerEnv = register_task(SPEC)
