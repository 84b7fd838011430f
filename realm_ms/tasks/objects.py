"""Task objects: what the env, the rubric and perturbations need to know about each object.

``RigidTaskObject`` wraps a catalog/procedural object from ``realm_ms.assets``. Articulated objects
(drawer cabinets, light switches) implement the same interface in ``realm_ms.tasks.articulated``
and register a builder under an asset prefix (``"articulated/drawer_cabinet"``), so the env never
branches on object kinds.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import sapien
import torch
from mani_skill.utils.structs.pose import Pose

from realm_ms.contacts import any_contact
from realm_ms.tasks.progression import quat_apply, quat_to_matrix
from realm_ms.tasks.spec import SceneObject

# asset prefix -> builder(env, SceneObject) -> task object (articulated objects register here)
OBJECT_BUILDERS: dict[str, Callable] = {}


def register_object_builder(prefix: str):
    def deco(fn):
        OBJECT_BUILDERS[prefix] = fn
        return fn

    return deco


def yaw_quat(yaw: torch.Tensor) -> torch.Tensor:
    """wxyz quaternions for rotations about +z, (B,) -> (B, 4)."""
    h = yaw / 2
    z = torch.zeros_like(h)
    return torch.stack([torch.cos(h), z, z, torch.sin(h)], dim=-1)


class TaskObject:
    """Interface shared by rigid and articulated task objects (batched over envs)."""

    is_articulated = False
    footprint_radius: float  # xy bounding radius for placement (m)
    rest_height: float  # origin height above the table when resting (m)

    @property
    def pose(self) -> Pose:
        raise NotImplementedError

    def set_pose(self, p: torch.Tensor, yaw: torch.Tensor) -> None:
        raise NotImplementedError

    def anchor_pos(self) -> torch.Tensor:
        """The point the rubric measures to (object centre, drawer handle, switch rocker), (B, 3)."""
        raise NotImplementedError

    def touch_entities(self) -> list:
        raise NotImplementedError

    def reset_fixture(self, env_idx: torch.Tensor, spec: SceneObject, scene_def) -> None:
        x, y, z, yaw = spec.pose
        b = len(env_idx)
        p = torch.tensor([x, y, scene_def.table_top_z + z], dtype=torch.float32).expand(b, 3)
        self.set_pose(p, torch.full((b,), float(yaw)))


class RigidTaskObject(TaskObject):
    def __init__(self, env, spec: SceneObject):
        from realm_ms.assets import build_actor, get_object_spec

        self.asset = get_object_spec(spec.asset)
        body = "kinematic" if spec.fixed else "dynamic"
        self.entity = build_actor(env.scene, self.asset, spec.name, body_type=body, pose=sapien.Pose(p=[0, 0, -5]))
        ext = self.asset.extents
        self.extents = ext
        self.footprint_radius = float(np.hypot(ext[0], ext[1]) / 2)
        self.rest_height = 0.002  # origin at the bottom centre; 2 mm drop avoids initial penetration
        self.device = env.device
        # bounding-box centre in the object frame (the catalog origin is the bottom centre)
        self._centre = torch.tensor([0.0, 0.0, float(ext[2]) / 2], device=env.device)

    @property
    def pose(self) -> Pose:
        return self.entity.pose

    def set_pose(self, p: torch.Tensor, yaw: torch.Tensor) -> None:
        self.entity.set_pose(Pose.create_from_pq(p.to(self.device), yaw_quat(yaw).to(self.device)))

    def anchor_pos(self) -> torch.Tensor:
        pose = self.entity.pose
        return pose.p + quat_apply(pose.q, self._centre)

    def touch_entities(self) -> list:
        return [self.entity]

    # receptacle checks (when this object is a target); geometric, see progression.py
    def contains(self, other: "TaskObject", margin: float = 0.01) -> torch.Tensor:
        """``other``'s centre inside this object's upright footprint and below its rim."""
        local = self._to_local(other.anchor_pos())
        half = torch.as_tensor(self.extents[:2] / 2, device=local.device, dtype=local.dtype) - margin
        inside_xy = (local[:, :2].abs() < half).all(dim=1)
        return inside_xy & (local[:, 2] > -0.01) & (local[:, 2] < float(self.extents[2]) + 0.02)

    def supports(self, other: "TaskObject", scene, tol: float = 0.015) -> torch.Tensor:
        """``other`` rests on this object's top face: footprint, bottom at the top height, contact."""
        local = self._to_local(other.pose.p)  # other's bottom centre
        half = torch.as_tensor(self.extents[:2] / 2, device=local.device, dtype=local.dtype)
        on_xy = (local[:, :2].abs() < half).all(dim=1)
        on_z = (local[:, 2] - float(self.extents[2])).abs() < tol
        touching = any_contact(scene, [self.entity], [other.entity])
        return on_xy & on_z & touching

    def _to_local(self, p_world: torch.Tensor) -> torch.Tensor:
        pose = self.entity.pose
        r = quat_to_matrix(pose.q)
        return ((p_world - pose.p)[:, None, :] @ r)[:, 0, :]


def build_task_object(env, spec: SceneObject) -> TaskObject:
    prefix = spec.asset.split("/", 1)[0]
    builder = OBJECT_BUILDERS.get(prefix)
    if builder is not None:
        return builder(env, spec)
    return RigidTaskObject(env, spec)
