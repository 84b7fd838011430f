"""Pairwise contact forces for many pairs at once.

ManiSkill's ``scene.get_pairwise_contact_forces`` walks every contact in Python for each pair on the
CPU backend; the REALM rubric asks for a dozen pairs per step (gripper links x object, pads x
object, object x target), which cost more than the physics. On CPU we walk the contacts once; on
GPU we use ManiSkill's batched contact queries unchanged.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import torch


def pairwise_forces(scene, pairs: list[tuple]) -> list[torch.Tensor]:
    """Net force (N) on ``a`` from ``b`` for each (a, b) pair of ManiSkill Actors/Links: (num_envs, 3) each."""
    if scene.gpu_sim_enabled:
        return [scene.get_pairwise_contact_forces(a, b) for a, b in pairs]
    wanted = {(a._bodies[0].entity, b._bodies[0].entity) for a, b in pairs}
    involved = {e for pair in wanted for e in pair}
    impulse: dict[tuple, np.ndarray] = defaultdict(lambda: np.zeros(3))
    for c in scene.px.get_contacts():
        e0, e1 = c.bodies[0].entity, c.bodies[1].entity
        if e0 not in involved or e1 not in involved:
            continue
        imp = np.sum([p.impulse for p in c.points], axis=0) if c.points else np.zeros(3)
        impulse[(e0, e1)] += imp  # impulse acts on the first body, as in mani_skill.utils.sapien_utils
        impulse[(e1, e0)] -= imp
    dt = scene.px.timestep
    return [torch.as_tensor(impulse[(a._bodies[0].entity, b._bodies[0].entity)] / dt, dtype=torch.float32)[None] for a, b in pairs]


def any_contact(scene, group_a: list, group_b: list, min_force: float = 1e-3) -> torch.Tensor:
    """(num_envs,) bool: any member of ``group_a`` touches any member of ``group_b``."""
    if scene.gpu_sim_enabled:
        forces = pairwise_forces(scene, [(a, b) for a in group_a for b in group_b])
        return torch.stack([f.norm(dim=-1) > min_force for f in forces]).any(dim=0)
    ea = {a._bodies[0].entity for a in group_a}
    eb = {b._bodies[0].entity for b in group_b}
    threshold = min_force * scene.px.timestep  # impulse over one step
    for c in scene.px.get_contacts():
        e0, e1 = c.bodies[0].entity, c.bodies[1].entity
        if ((e0 in ea and e1 in eb) or (e1 in ea and e0 in eb)) and c.points:
            if np.linalg.norm(np.sum([p.impulse for p in c.points], axis=0)) > threshold:
                return torch.ones(1, dtype=torch.bool)
    return torch.zeros(1, dtype=torch.bool)
