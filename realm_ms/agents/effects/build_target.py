"""``BuildTarget``: one PhysX articulation that build-time effects (armature, payload, link_mass) modify.

The nominal joint armature and link inertials are remembered on first use and restored by
``reset``: armature is set absolute (nominal + effect); inertial changes apply on top of the link's
current inertial (so a payload and a link-7 correction compose), after a ``reset`` before every
rollout.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from realm_ms.agents.effects.parameter import NUM_JOINTS


class BuildTarget:
    """One PhysX articulation whose nominal joint/link properties are remembered on first use, so
    build-time effects can be re-applied per rollout after a ``reset``."""

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
        self._nominal_links: dict[int, tuple] = {}  # id(link) -> (link, mass, cmass pose, inertia)

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
        for link, mass, pose, inertia in self._nominal_links.values():
            link.set_mass(mass)
            link.set_cmass_local_pose(pose)
            link.set_inertia(inertia)

    def add_armature(self, values: np.ndarray) -> None:
        for j, a, v in zip(self.joints, self.nominal_armature, values):
            j.set_armature([a + float(v)])

    def _link(self, body: int):
        """PhysX link of arm body ``body`` (0-based: panda_link{body+1})."""
        name = f"panda_link{body + 1}"
        for l in self.art.get_links():
            n = l.get_name()
            if n == name or n.endswith("_" + name):
                return l
        raise ValueError(f"articulation has no {name}")

    def _remember(self, link) -> None:
        """Nominal inertial of a link whose inertial an effect changes (``reset`` restores it)."""
        if id(link) not in self._nominal_links:
            self._nominal_links[id(link)] = (link, float(link.get_mass()), link.get_cmass_local_pose(),
                                             np.asarray(link.get_inertia(), dtype=float))

    def add_point_mass(self, mass: float, offset_in_flange: np.ndarray) -> None:
        """Rigidly attach a point mass at ``offset_in_flange`` (m, flange frame) to the flange link."""
        self.add_body(mass, offset_in_flange, np.zeros((3, 3)))

    def add_body(self, mass: float, offset_in_flange: np.ndarray, inertia: np.ndarray) -> None:
        """Rigidly attach a body (``inertia`` about its CoM, flange axes) at ``offset_in_flange`` (m,
        flange frame) to the flange link, on top of its current inertial."""
        if mass <= 0:
            return
        from realm_ms.agents.arm_model import _Inertial

        self._remember(self.flange)
        body = _Inertial(*get_inertial(self.flange))
        point = _Inertial(float(mass), self.flange_offset + np.asarray(offset_in_flange, dtype=float), np.asarray(inertia, dtype=float))
        merged = _Inertial.merge([body, point])
        set_inertial(self.flange, merged.mass, merged.com, merged.inertia)

    def map_link_inertial(self, body: int, fn) -> None:
        """Replace arm body ``body``'s inertial (0-based) by ``fn(mass, com, inertia)`` of its current
        one (link frame, inertia about the CoM) -> the same triple."""
        link = self._link(body)
        self._remember(link)
        set_inertial(link, *fn(*get_inertial(link)))


def get_inertial(link) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, CoM, inertia about the CoM) of a PhysX link, link frame."""
    import torch
    from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

    pose = link.get_cmass_local_pose()
    rot = quaternion_to_matrix(torch.as_tensor(np.asarray(pose.q, dtype=np.float64))).numpy()
    return float(link.get_mass()), np.asarray(pose.p, dtype=float), rot @ np.diag(np.asarray(link.get_inertia(), dtype=float)) @ rot.T


def set_inertial(link, mass: float, com: np.ndarray, inertia: np.ndarray) -> None:
    """Set a PhysX link's inertial from (mass, CoM, inertia about the CoM), link frame: PhysX takes
    the principal moments and the principal axes' rotation."""
    import sapien
    import torch
    from mani_skill.utils.geometry.rotation_conversions import matrix_to_quaternion

    w, v = np.linalg.eigh(np.asarray(inertia, dtype=float))
    if np.linalg.det(v) < 0:
        v[:, 0] = -v[:, 0]
    quat = matrix_to_quaternion(torch.as_tensor(v)).numpy().astype(np.float32)  # wxyz, as sapien
    link.set_mass(float(mass))
    link.set_cmass_local_pose(sapien.Pose(np.asarray(com, dtype=np.float32), quat))
    link.set_inertia(np.maximum(w, 1e-8).astype(np.float32))
