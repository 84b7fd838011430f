"""Build catalog objects as ManiSkill actors: GLB visual + convex collision parts, mass, friction."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from realm_ms.assets.object_spec import ObjectSpec

BODY_TYPES = ("dynamic", "kinematic", "static")


def _scale3(scale: float | Sequence[float]) -> tuple[float, float, float]:
    s = np.broadcast_to(np.asarray(scale, float), (3,))
    if np.any(s <= 0):
        raise ValueError(f"scale must be positive, got {scale}")
    return (float(s[0]), float(s[1]), float(s[2]))


def build_actor(
    scene: Any,
    spec: ObjectSpec | str,
    name: str,
    *,
    pose: Any = None,
    scale: float | Sequence[float] = 1.0,
    body_type: str = "dynamic",
    mass: float | None = None,
    friction: float | None = None,
    restitution: float = 0.0,
    scene_idxs: Sequence[int] | None = None,
    visual: bool = True,
):
    """Build ``spec`` into ``scene`` (a ``ManiSkillScene``; a plain ``sapien.Scene`` also works).

    ``pose`` places the object's bottom centre (the catalog origin), so ``z = table height`` rests it
    on the table. ``scale`` may be per-axis (VB-MOBJ). Mass follows the catalog's density, so it grows
    with ``prod(scale)``; pass ``mass=`` to override (B-HOBJ). Returns the built actor.
    """
    import sapien

    if isinstance(spec, str):
        from realm_ms.assets.catalog import get_object_spec

        spec = get_object_spec(spec)
    if body_type not in BODY_TYPES:
        raise ValueError(f"body_type must be one of {BODY_TYPES}")
    s = _scale3(scale)
    vol = spec.record.collision_volume * s[0] * s[1] * s[2]
    density = (mass / max(vol, 1e-12)) if mass is not None else spec.density
    mu = spec.record.friction if friction is None else friction
    material = sapien.physx.PhysxMaterial(static_friction=mu, dynamic_friction=mu, restitution=restitution)

    builder = scene.create_actor_builder()
    builder.add_multiple_convex_collisions_from_file(str(spec.collision_path), scale=s, material=material, density=density)
    if visual:
        builder.add_visual_from_file(str(spec.visual_path), scale=s)
    if scene_idxs is not None and hasattr(builder, "set_scene_idxs"):
        builder.set_scene_idxs(list(scene_idxs))
    if pose is not None:
        builder.initial_pose = pose if not isinstance(pose, (list, tuple, np.ndarray)) else sapien.Pose(p=list(pose))
    elif hasattr(builder, "set_scene_idxs"):
        builder.initial_pose = sapien.Pose()  # explicit: ManiSkill warns (and GPU sim slows) without one
    if body_type == "dynamic":
        return builder.build(name=name)
    return builder.build_kinematic(name=name) if body_type == "kinematic" else builder.build_static(name=name)


def make_cpu_scene(timestep: float = 1 / 100, ground: bool = True):
    """A single CPU-physics ``ManiSkillScene`` without rendering: for tests, checks and the build's
    settle stage. Returns the scene."""
    import sapien
    from mani_skill.envs.scene import ManiSkillScene
    from mani_skill.envs.utils.system.backend import parse_sim_and_render_backend

    # SAPIEN's body defaults are process-global and every ManiSkill env sets its own (REALM envs: no
    # sleeping): restore SAPIEN's defaults so this scene behaves the same whatever ran before
    sapien.physx.set_body_config(solver_position_iterations=10, solver_velocity_iterations=1, sleep_threshold=0.005)
    sub = sapien.Scene([sapien.physx.PhysxCpuSystem()])
    scene = ManiSkillScene([sub], backend=parse_sim_and_render_backend("physx_cpu", "none"), device="cpu")
    scene.px.timestep = timestep
    if ground:
        b = scene.create_actor_builder()
        b.add_plane_collision(sapien.Pose(q=[0.7071068, 0, -0.7071068, 0]))
        b.initial_pose = sapien.Pose()
        b.build_static(name="ground")
    return scene
