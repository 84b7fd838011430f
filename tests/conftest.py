"""Shared test options: ``--run-slow`` enables tests marked ``slow`` (``make test-slow``)."""

import os
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

os.environ.setdefault("MS_SKIP_ASSET_DOWNLOAD_PROMPT", "1")
if os.environ.get("PYTEST_XDIST_WORKER"):
    # `make test` runs pytest-xdist workers side by side: one OpenMP/BLAS thread each (and in the
    # commands they start), so that two workers share two cores instead of oversubscribing them
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("MKL_NUM_THREADS", "1")


def pytest_addoption(parser):
    parser.addoption("--run-slow", action="store_true", default=False, help="run tests marked slow")


#: the files that take minutes (a trained checkpoint, diagnose and fit runs, renders), longest first:
#: the workers start on them, so that the suite does not end with one worker running a long file
#: alone while the other idles (`make test` passes --no-loadscope-reorder, so this is the schedule)
LONG_FILES = ("sysid/test_droid_formats.py", "lerobot/test_export.py", "bad_inputs/test_bad_inputs.py", "sysid/test_sysid_cli.py",
              "expert/test_expert.py", "lerobot/test_example.py", "perturbations/test_perturbations_env.py",
              "tasks/test_env_pick_apple.py", "perturbations/test_physics_neutral.py", "sysid/test_optimize.py",
              "eval/test_e2e.py", "sysid/test_torque.py", "sysid/test_effects.py", "lerobot/test_policy_transfer.py",
              "sysid/test_reference_mujoco.py", "eval/test_installed_cli.py", "sysid/test_link_mass.py", "sysid/test_hidden.py",
              "eval/test_policy_latency.py", "eval/test_batched.py", "assets/test_pipeline.py", "tasks/test_envs.py")


def _start_rank(item) -> int:
    name = item.path.relative_to(TESTS).as_posix()
    return LONG_FILES.index(name) if name in LONG_FILES else len(LONG_FILES)


def pytest_collection_modifyitems(config, items):
    items.sort(key=_start_rank)  # stable: each file's tests keep their order
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: run with `make test-slow` (pytest --run-slow)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


TABLE_TOP = 0.80  # height of the table top in ``table_scene``


@pytest.fixture
def table_scene():
    """A CPU PhysX scene with a large static table whose top is at ``TABLE_TOP`` (friction 0.8)."""
    import sapien

    from realm_ms.assets import make_cpu_scene

    scene = make_cpu_scene(ground=False)
    table = scene.create_actor_builder()
    table.add_box_collision(half_size=[4, 4, 0.02], material=sapien.physx.PhysxMaterial(0.8, 0.8, 0))
    table.initial_pose = sapien.Pose(p=[0, 0, TABLE_TOP - 0.02])
    table.build_static(name="table")
    return scene
