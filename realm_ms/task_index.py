"""Names every layer shares, at no import cost: the REALM tasks and their modules, REALM's horizon,
the unperturbed setting's name.

``TASK_MODULES`` is the one list of tasks: ``realm_ms.tasks`` imports exactly these modules, and
``import realm_ms`` registers exactly these ids (``realm_ms.registration``).
"""

# env id -> module under realm_ms.tasks that declares its TaskSpec (and calls register_task)
TASK_MODULES: dict[str, str] = {
    "REALM-PickApple-v1": "pick_apple",
    "REALM-PickSpoon-v1": "pick_spoon",
    "REALM-PickWaterBottle-v1": "pick_water_bottle",
    "REALM-PutGreenBlockInBowl-v1": "put_green_block_in_bowl",
    "REALM-PutBananaInBox-v1": "put_banana_in_box",
    "REALM-StackCubes-v1": "stack_cubes",
    "REALM-RotateMarker-v1": "rotate_marker",
    "REALM-RotateMug-v1": "rotate_mug",
    "REALM-OpenDrawer-v1": "open_drawer",
    "REALM-CloseDrawer-v1": "close_drawer",
    "REALM-PushSwitch-v1": "push_switch",
}
HORIZON = 800  # control steps, REALM's episode length (TaskSpec.horizon's default)
DEFAULT = "Default"  # the unperturbed setting (perturbation id 0): the one spelling every layer uses
# the package whose import registers every perturbation into realm_ms.tasks.perturbation.PERTURBATIONS:
# an env that is asked for one loads it by this name (a plugin, as gymnasium's "module:EnvId")
PERTURBATION_PACKAGE = "realm_ms.perturbations"
