"""``BuildTarget``: one PhysX articulation that build-time effects (armature, payload) modify.

The nominal joint armature and flange inertial are remembered on first use, so an effect always
sets absolute values (nominal + effect) and can be re-applied before every rollout.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from realm_ms.agents.effects.parameter import NUM_JOINTS


class BuildTarget:
    """One PhysX articulation whose nominal joint/link properties are remembered on first use, so
    build-time effects set *absolute* values (nominal + effect) and can be re-applied per rollout."""

    _cache: dict[int, "BuildTarget"] = {}

    def __init__(self, articulation: Any, joint_indices: list[int] | None = None,
                 flange_offset: np.ndarray | None = None):
        """``flange_offset``: position of the flange in ``panda_link7`` (m), needed only for an
        articulation whose flange is lumped into link 7 (the sysid replay arm)."""
        self.art = articulation
        joints = articulation.get_active_joints()
        idx = list(range(NUM_JOINTS)) if joint_indices is None else [int(i) for i in joint_indices]
        self.joints = [joints[i] for i in idx]
        self.nominal_armature = [float(np.asarray(j.get_armature()).reshape(-1)[0]) for j in self.joints]
        # ManiSkill prefixes link names per sub-scene ("scene-0-panda_droid_panda_link8"): key by suffix
        links = {}
        for l in articulation.get_links():
            name = l.get_name()
            for base in ("panda_link8", "panda_link7"):
                if name == base or name.endswith("_" + base):
                    links[base] = l
        if "panda_link8" in links:
            self.flange, self.flange_offset = links["panda_link8"], np.zeros(3)
        elif flange_offset is not None:  # locked replay URDF: the flange is lumped into link 7
            self.flange, self.flange_offset = links["panda_link7"], np.asarray(flange_offset, dtype=float)
        else:
            raise ValueError("articulation has no panda_link8 (flange): pass flange_offset for a lumped arm")
        self.nominal_mass = float(self.flange.get_mass())
        self.nominal_cmass = self.flange.get_cmass_local_pose()
        self.nominal_inertia = np.asarray(self.flange.get_inertia(), dtype=float)

    @classmethod
    def of(cls, articulation: Any, joint_indices: list[int] | None = None) -> "BuildTarget":
        key = id(articulation)
        t = cls._cache.get(key)
        if t is None or t.art is not articulation:
            t = cls._cache[key] = cls(articulation, joint_indices)
        return t

    def reset(self) -> None:
        for j, a in zip(self.joints, self.nominal_armature):
            j.set_armature([a])
        self.flange.set_mass(self.nominal_mass)
        self.flange.set_cmass_local_pose(self.nominal_cmass)
        self.flange.set_inertia(self.nominal_inertia)

    def add_armature(self, values: np.ndarray) -> None:
        for j, a, v in zip(self.joints, self.nominal_armature, values):
            j.set_armature([a + float(v)])

    def add_point_mass(self, mass: float, offset_in_flange: np.ndarray) -> None:
        """Rigidly attach a point mass at ``offset_in_flange`` (m, flange frame) to the flange link."""
        if mass <= 0:
            return
        import sapien
        import torch
        from mani_skill.utils.geometry.rotation_conversions import matrix_to_quaternion, quaternion_to_matrix

        from realm_ms.agents.arm_model import _Inertial

        pose = self.nominal_cmass
        rot = quaternion_to_matrix(torch.as_tensor(np.asarray(pose.q, dtype=np.float64))).numpy()
        body = _Inertial(self.nominal_mass, np.asarray(pose.p, dtype=float), rot @ np.diag(self.nominal_inertia) @ rot.T)
        point = _Inertial(float(mass), self.flange_offset + np.asarray(offset_in_flange, dtype=float), np.zeros((3, 3)))
        merged = _Inertial.merge([body, point])
        w, v = np.linalg.eigh(merged.inertia)
        if np.linalg.det(v) < 0:
            v[:, 0] = -v[:, 0]
        quat = matrix_to_quaternion(torch.as_tensor(v)).numpy().astype(np.float32)  # wxyz, as sapien
        self.flange.set_mass(merged.mass)
        self.flange.set_cmass_local_pose(sapien.Pose(merged.com.astype(np.float32), quat))
        self.flange.set_inertia(np.maximum(w, 1e-8).astype(np.float32))
