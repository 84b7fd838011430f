"""Shared helpers for the articulated objects (materials, boxes on link builders, pose helpers)."""

from __future__ import annotations

import sapien
import torch
from mani_skill.utils.structs.pose import Pose

from realm_ms.tasks.objects import TaskObject, yaw_quat


def mat(rgba, roughness=0.6, metallic=0.0):
    return sapien.render.RenderMaterial(base_color=list(rgba), roughness=roughness, metallic=metallic)


def box(link_builder, centre, half, material, density=500.0, collision=True, phys=None, q=(1.0, 0.0, 0.0, 0.0)):
    pose = sapien.Pose(list(centre), list(q))
    if collision:
        link_builder.add_box_collision(pose=pose, half_size=list(half), density=density, material=phys)
    link_builder.add_box_visual(pose=pose, half_size=list(half), material=material)


class ArticulatedTaskObject(TaskObject):
    """Base for our articulated fixtures: a fixed-root articulation placed by its root pose."""

    is_articulated = True
    rest_height = 0.0  # the root frame is at the bottom centre, on the table

    def __init__(self, env):
        self.env = env
        self.device = env.device

    @property
    def pose(self) -> Pose:
        return self.art.root_pose

    @property
    def entity(self):  # what perturbations / generic code may treat as "the object"
        return self.art

    def set_pose(self, p: torch.Tensor, yaw: torch.Tensor) -> None:
        self.art.set_root_pose(Pose.create_from_pq(p.to(self.device), yaw_quat(yaw).to(self.device)))
        self.reset_joints(p.shape[0])

    def reset_joints(self, b: int) -> None:
        raise NotImplementedError

    def openness(self) -> torch.Tensor:
        return torch.zeros(self.env.num_envs, device=self.device)

    def toggled(self) -> torch.Tensor:
        return torch.zeros(self.env.num_envs, dtype=torch.bool, device=self.device)

    # articulated objects are never receptacles in REALM's tasks
    def contains(self, other, margin: float = 0.01) -> torch.Tensor:
        return torch.zeros(self.env.num_envs, dtype=torch.bool, device=self.device)

    def holds(self, other, scene, margin: float = 0.01) -> torch.Tensor:
        return self.contains(other, margin)

    def supports(self, other, scene, tol: float = 0.015) -> torch.Tensor:
        return torch.zeros(self.env.num_envs, dtype=torch.bool, device=self.device)
