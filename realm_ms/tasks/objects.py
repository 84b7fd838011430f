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
from realm_ms.registry import Registry
from mani_skill.utils.geometry.rotation_conversions import quaternion_apply, quaternion_to_matrix
from realm_ms.tasks.task_spec import SceneObject

# m: a bottom this far above a receptacle's base is on it, not on the table beside it (both settle
# within ~2 mm of the table)
ABOVE_BASE = 0.004

# asset prefix -> builder(env, SceneObject) -> task object (articulated objects register here)
OBJECT_BUILDERS: Registry[Callable] = Registry("object builder")


def register_object_builder(prefix: str):
    return OBJECT_BUILDERS.register(prefix)


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
    """A catalog object; ``variants`` (one ``SceneObject`` per sub-env, same name) lets each sub-env
    hold a different asset / scale (perturbations): then one actor per sub-env is built with
    ``scene_idxs`` and merged, so poses and rubric checks stay batched."""

    def __init__(self, env, spec: SceneObject, variants: list[SceneObject] | None = None):
        from mani_skill.utils.structs.actor import Actor

        from realm_ms.assets import build_actor, get_object_spec

        variants = list(variants) if variants and len(variants) == env.num_envs else [spec]
        uniform = all(v.asset == variants[0].asset and tuple(v.scale) == tuple(variants[0].scale) for v in variants)
        if uniform:
            variants = variants[:1]
        self.assets = [get_object_spec(v.asset) for v in variants]
        self.asset = self.assets[0]
        scales = [np.broadcast_to(np.asarray(v.scale, float), (3,)) for v in variants]
        self.fixed = spec.fixed
        body = "kinematic" if spec.fixed else "dynamic"
        hidden = sapien.Pose(p=[0, 0, -5])
        if uniform:
            self.entity = build_actor(env.scene, self.asset, spec.name, body_type=body, pose=hidden, scale=scales[0])
        else:
            parts = [
                build_actor(env.scene, a, f"{spec.name}-{i}", body_type=body, pose=hidden, scale=s, scene_idxs=[i])
                for i, (a, s) in enumerate(zip(self.assets, scales))
            ]
            self.entity = Actor.merge(parts, name=spec.name)
        ext = np.stack([a.extents * s for a, s in zip(self.assets, scales)])  # (1 or B, 3)
        self.extents = ext[0]  # sub-env 0 (scripted code reading one env)
        self._extents = torch.as_tensor(ext, dtype=torch.float32, device=env.device)
        self.footprint_radius = float(np.max(np.hypot(ext[:, 0], ext[:, 1])) / 2)
        self.rest_height = 0.002  # origin at the bottom centre; 2 mm drop avoids initial penetration
        self.device = env.device
        # bounding-box centre in the object frame (the catalog origin is the bottom centre)
        self._centre = torch.zeros_like(self._extents)
        self._centre[:, 2] = self._extents[:, 2] / 2

    @property
    def pose(self) -> Pose:
        return self.entity.pose

    def set_pose(self, p: torch.Tensor, yaw: torch.Tensor) -> None:
        self.entity.set_pose(Pose.create_from_pq(p.to(self.device), yaw_quat(yaw).to(self.device)))
        if not self.fixed:  # a teleported body keeps its velocity: the last episode's throw must not leak
            zero = torch.zeros(p.shape[0], 3, device=self.device)
            self.entity.set_linear_velocity(zero)
            self.entity.set_angular_velocity(zero)

    def anchor_pos(self) -> torch.Tensor:
        pose = self.entity.pose
        return pose.p + quaternion_apply(pose.q, self._centre)

    def touch_entities(self) -> list:
        return [self.entity]

    # receptacle checks (when this object is a target); geometric, see progression.py
    def contains(self, other: "TaskObject", margin: float = 0.01) -> torch.Tensor:
        """``other``'s centre inside this object's upright footprint and below its rim."""
        local = self._to_local(other.anchor_pos())
        half = self._extents[:, :2].to(local) / 2 - margin
        inside_xy = (local[:, :2].abs() < half).all(dim=1)
        return inside_xy & (local[:, 2] > -0.01) & (local[:, 2] < self._extents[:, 2].to(local) + 0.02)

    def holds(self, other: "TaskObject", scene, margin: float = 0.01) -> torch.Tensor:
        """REALM's PLACE_INTO test: ``other`` is inside this receptacle (``contains``) or rests on it
        (OmniGibson's ``OnTop``: touching it, with nothing of it under ``other``'s centre: the centre
        over this object's footprint, the bottom above its base). A 12 cm glass standing in a 7 cm
        bowl rests 3 cm up the bowl's walls, its centre above ``contains``' band: it is OnTop."""
        local = self._to_local(other.anchor_pos())
        half = self._extents[:, :2].to(local) / 2 - margin
        over = (local[:, :2].abs() < half).all(dim=1) & (self._to_local(other.pose.p)[:, 2] > ABOVE_BASE)
        inside = self.contains(other, margin)
        if not bool((over & ~inside).any()):  # the contact query walks every contact on CPU: skip it
            return inside
        return inside | (over & any_contact(scene, [self.entity], other.touch_entities()).to(over.device))

    def supports(self, other: "TaskObject", scene, tol: float = 0.015) -> torch.Tensor:
        """``other`` rests on this object's top face: footprint, bottom at the top height, contact."""
        local = self._to_local(other.pose.p)  # other's bottom centre
        half = self._extents[:, :2].to(local) / 2
        on_xy = (local[:, :2].abs() < half).all(dim=1)
        on_z = (local[:, 2] - self._extents[:, 2].to(local)).abs() < tol
        touching = any_contact(scene, [self.entity], [other.entity])
        return on_xy & on_z & touching

    def _to_local(self, p_world: torch.Tensor) -> torch.Tensor:
        pose = self.entity.pose
        r = quaternion_to_matrix(pose.q)
        return ((p_world - pose.p)[:, None, :] @ r)[:, 0, :]


def build_task_object(env, spec: SceneObject, variants: list[SceneObject] | None = None) -> TaskObject:
    """``variants``: the object as each sub-env's (perturbed) task has it; articulated objects are
    built from sub-env 0's variant for all sub-envs (their geometry is one articulation layout)."""
    prefix = spec.asset.split("/", 1)[0]
    builder = OBJECT_BUILDERS.get(prefix) if prefix in OBJECT_BUILDERS else None
    if builder is not None:
        return builder(env, variants[0] if variants else spec)
    return RigidTaskObject(env, spec, variants)
