"""Batched rigid-body model of a serial arm, parsed from a URDF: the robot's *own* model.

This is what the real controller knows about the arm (libfranka's gravity model, Polymetis'
pinocchio model): forward kinematics, the end-effector Jacobian, and inverse dynamics (RNEA) for
gravity and Coriolis feed-forward. The physics engine simulates the *true* articulation; any
difference between the two (a payload, a mis-modelled link) is a physical effect, which is exactly
what the sysid workbench looks for.

Everything is batched over a leading env dimension and written once against an array namespace
(``arrays.py``): torch, so physx_cpu and physx_cuda share one code path, or float64 numpy for the
CPU law with few envs. RNEA is written in world coordinates with prefix/suffix sums instead of
per-joint Python recursion: ~40 array ops per call regardless of the batch size.
"""

from __future__ import annotations

import copy
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch

from realm_ms.agents.arrays import NumpyOps, TorchOps

GRAVITY = (0.0, 0.0, -9.81)


def _rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _origin(elem: ET.Element | None) -> np.ndarray:
    t = np.eye(4)
    if elem is None:
        return t
    xyz = [float(v) for v in elem.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in elem.get("rpy", "0 0 0").split()]
    t[:3, :3] = _rpy_matrix(*rpy)
    t[:3, 3] = xyz
    return t


@dataclass
class _Inertial:
    mass: float
    com: np.ndarray  # (3,) in the link frame
    inertia: np.ndarray  # (3,3) about the CoM, link-frame axes

    @staticmethod
    def parse(link: ET.Element) -> "_Inertial":
        el = link.find("inertial")
        if el is None:
            return _Inertial(0.0, np.zeros(3), np.zeros((3, 3)))
        o = _origin(el.find("origin"))
        m = float(el.find("mass").get("value"))
        i = el.find("inertia")
        g = lambda k: float(i.get(k, 0.0))  # noqa: E731
        inertia = np.array(
            [[g("ixx"), g("ixy"), g("ixz")], [g("ixy"), g("iyy"), g("iyz")], [g("ixz"), g("iyz"), g("izz")]]
        )
        return _Inertial(m, o[:3, 3].copy(), o[:3, :3] @ inertia @ o[:3, :3].T)

    def transformed(self, t: np.ndarray) -> "_Inertial":
        """Same body expressed in a parent frame, t = T_parent_link."""
        return _Inertial(self.mass, t[:3, :3] @ self.com + t[:3, 3], t[:3, :3] @ self.inertia @ t[:3, :3].T)

    @staticmethod
    def merge(parts: list["_Inertial"]) -> "_Inertial":
        m = sum(p.mass for p in parts)
        if m <= 0:
            return _Inertial(0.0, np.zeros(3), np.zeros((3, 3)))
        c = sum(p.mass * p.com for p in parts) / m
        inertia = np.zeros((3, 3))
        for p in parts:  # parallel-axis theorem
            d = p.com - c
            inertia += p.inertia + p.mass * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
        return _Inertial(m, c, inertia)


class Links(NamedTuple):
    """Per-link world quantities at one configuration, batch first (slice each to take rows): the
    n moving bodies' frames, their joint origins p, joint axes z, centres of mass c and inertias
    about the CoM (``None`` where only kinematics was asked for)."""

    frames: Any
    p: Any
    z: Any
    c: Any = None
    inertia: Any = None


class ArmModel:
    """Serial chain from ``base_link`` to ``tip_link`` with revolute joints.

    Links hanging off the chain (the gripper, cameras) are lumped rigidly into the chain link they
    are attached to, at their zero configuration, as a robot vendor's model of a mounted end
    effector would be.

    One implementation on either array namespace (``arrays.py``): ``to(device, dtype)`` puts the
    model on torch, ``numpy()`` gives the same model in float64 numpy.
    """

    # the model's parameter arrays: what ``numpy()`` converts
    _ARRAYS = ("origins", "axes", "masses", "coms", "inertias", "tip_offset", "gravity", "_OK", "_OK2", "_com_h")

    def __init__(
        self,
        joint_names: list[str],
        origins: np.ndarray,
        axes: np.ndarray,
        inertials: list[_Inertial],
        tip_offset: np.ndarray,
        q_limits: np.ndarray,
        effort_limits: np.ndarray,
        device: torch.device | str = "cpu",
        dtype: torch.dtype = torch.float32,
    ):
        self.joint_names = joint_names
        self.dof = len(joint_names)
        self.q_limits = q_limits
        self.effort_limits = effort_limits
        self._np = dict(origins=origins, axes=axes, inertials=inertials, tip_offset=tip_offset)
        self.to(device, dtype)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_urdf(cls, urdf: str | Path, base_link: str, tip_link: str, **kw) -> "ArmModel":
        root = ET.parse(str(urdf)).getroot()
        links = {l.get("name"): l for l in root.findall("link")}
        joints = root.findall("joint")
        child_joint = {j.find("child").get("link"): j for j in joints}
        children: dict[str, list[ET.Element]] = {}
        for j in joints:
            children.setdefault(j.find("parent").get("link"), []).append(j)

        # chain joints, walking up from the tip
        chain: list[ET.Element] = []
        link = tip_link
        while link != base_link:
            if link not in child_joint:
                raise ValueError(f"{tip_link!r} is not below {base_link!r} in {urdf}")
            j = child_joint[link]
            chain.insert(0, j)
            link = j.find("parent").get("link")
        moving = [j for j in chain if j.get("type") in ("revolute", "continuous")]
        if any(j.get("type") == "prismatic" for j in chain):
            raise ValueError("prismatic joints on the arm chain are not supported")

        # Body i (i = 0..n-1) is everything rigidly attached after moving joint i, expressed in the
        # frame of that joint (after rotation). Fixed joints on the chain are folded into origins.
        chain_links = [base_link] + [j.find("child").get("link") for j in chain]
        moving_idx = {id(j): k for k, j in enumerate(moving)}

        def subtree(link_name: str, t: np.ndarray, out: list[_Inertial]) -> None:
            out.append(_Inertial.parse(links[link_name]).transformed(t))
            for j in children.get(link_name, []):
                c = j.find("child").get("link")
                if c in chain_links and id(child_joint[c]) in moving_idx:
                    continue  # the next moving body starts here
                # fixed joints on the chain and side branches (gripper, camera) are lumped rigidly,
                # side branches at their zero configuration
                subtree(c, t @ _origin(j.find("origin")), out)

        origins, axes, inertials = [], [], []
        pending = np.eye(4)  # fixed transforms accumulated since the previous moving joint
        for j in chain:
            o = _origin(j.find("origin"))
            if j.get("type") == "fixed":
                pending = pending @ o
                continue
            origins.append(pending @ o)
            axes.append(np.array([float(v) for v in (j.find("axis").get("xyz") if j.find("axis") is not None else "1 0 0").split()]))
            pending = np.eye(4)
            parts: list[_Inertial] = []
            subtree(j.find("child").get("link"), np.eye(4), parts)
            inertials.append(_Inertial.merge(parts))
        tip_offset = pending  # fixed transform from the last moving body to the tip link
        lim = np.array([[float(j.find("limit").get("lower")), float(j.find("limit").get("upper"))] for j in moving])
        eff = np.array([float(j.find("limit").get("effort")) for j in moving])
        return cls([j.get("name") for j in moving], np.stack(origins), np.stack(axes), inertials, tip_offset, lim, eff, **kw)

    def to(self, device=None, dtype=None) -> "ArmModel":
        """The model on torch, ``device`` and ``dtype`` (default: as it is), in place."""
        device = torch.device(device) if device is not None else self.device
        dtype = dtype or self.dtype
        self.device, self.dtype = device, dtype
        t = lambda a: torch.as_tensor(np.asarray(a), device=device, dtype=dtype)  # noqa: E731
        n = self._np
        self.origins = t(n["origins"])  # (n,4,4) parent body frame -> joint frame at q=0
        self.axes = t(n["axes"] / np.linalg.norm(n["axes"], axis=1, keepdims=True))  # (n,3) in joint frame
        self.masses = t([i.mass for i in n["inertials"]])  # (n,)
        self.coms = t(np.stack([i.com for i in n["inertials"]]))  # (n,3) body frame
        self.inertias = t(np.stack([i.inertia for i in n["inertials"]]))  # (n,3,3) body frame, about CoM
        self.tip_offset = t(n["tip_offset"])
        self.gravity = t(GRAVITY)
        # Rodrigues pieces for rotation about each (unit) joint axis, folded into the joint origins:
        # local_i(q) = O_i Rot(a_i, q) = O_i + sin(q) O_i K_i + (1 - cos q) O_i K_i^2 (4x4, no translation part)
        a = self.axes
        k = torch.zeros(self.dof, 4, 4, device=device, dtype=dtype)
        k[:, 0, 1], k[:, 0, 2], k[:, 1, 0] = -a[:, 2], a[:, 1], a[:, 2]
        k[:, 1, 2], k[:, 2, 0], k[:, 2, 1] = -a[:, 0], -a[:, 1], a[:, 0]
        self._OK, self._OK2 = self.origins @ k, self.origins @ (k @ k)
        self._com_h = torch.cat([self.coms, torch.ones(self.dof, 1, device=device, dtype=dtype)], 1)[..., None]
        return self._on(TorchOps)

    def numpy(self) -> "ArmModel":
        """The same model (its parameters as they are on torch, in float64) on numpy: for the CPU
        law with few envs, where numpy's per-op overhead is ~5x below eager torch's."""
        out = copy.copy(self)
        for name in self._ARRAYS:
            setattr(out, name, getattr(self, name).detach().cpu().double().numpy())
        return out._on(NumpyOps)

    def _on(self, xp) -> "ArmModel":
        """Derive, in the namespace's own precision, what every evaluation reuses."""
        self.xp = xp
        like = self.masses
        self._m_suf = xp.suffix_sum(like[None])[0][:, None]  # mass of links i..n-1
        i = xp.arange(self.dof, like)
        self._upper = i[:, None] <= i[None]
        self._eye3 = xp.eye(3, like)
        return self

    # ------------------------------------------------------------------ kinematics
    def link_frames(self, q):
        """World (base) transforms of the n moving bodies, shape (B, n, 4, 4)."""
        xp = self.xp
        s, c = xp.sin(q)[..., None, None], xp.cos(q)[..., None, None]
        local = self.origins + s * self._OK + (1 - c) * self._OK2
        frames = xp.copy(local)  # written in place: cheaper than stacking on numpy's tiny arrays
        t = local[:, 0]
        for i in range(1, self.dof):
            frames[:, i] = t = t @ local[:, i]
        return frames

    def links(self, frames, dynamics: bool = True) -> Links:
        """The per-link world quantities at ``frames`` (``link_frames(q)``), shared by ``jacobian_at``,
        ``bias_at`` and ``mass_at``; ``dynamics=False``: the kinematic ones only."""
        rot = frames[..., :3, :3]
        z = (rot @ self.axes[..., None])[..., 0]
        if not dynamics:
            return Links(frames, frames[..., :3, 3], z)
        c = (frames @ self._com_h)[..., :3, 0]
        return Links(frames, frames[..., :3, 3], z, c, rot @ self.inertias @ self.xp.swap(rot))

    def fk(self, q, frames=None):
        """Tip pose (B, 4, 4) in the base frame."""
        frames = self.link_frames(q) if frames is None else frames
        return frames[:, -1] @ self.tip_offset

    def jacobian(self, q, frames=None):
        """Geometric Jacobian of the tip (B, 6, n): rows [linear velocity; angular velocity], base frame."""
        return self.jacobian_at(self.links(self.link_frames(q) if frames is None else frames, dynamics=False))

    def jacobian_at(self, links: Links):
        xp = self.xp
        tip = (links.frames[:, -1] @ self.tip_offset)[:, None, :3, 3]
        return xp.swap(xp.cat([xp.cross(links.z, tip - links.p), links.z], -1))

    # ------------------------------------------------------------------ dynamics
    def rnea(self, q, qd, qdd=None, gravity: bool = True, frames=None):
        """Inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q), batched (B, n)."""
        return self.bias_at(self.links(self.link_frames(q) if frames is None else frames), qd, gravity, qdd)

    def motion(self, links: Links, qd, gravity: bool = True, qdd=None) -> tuple:
        """Per body, world axes: angular velocity w, angular acceleration dw and the linear
        acceleration a of its joint origin (with -g as the base's: gravity as an acceleration)."""
        xp, p, z = self.xp, links.p, links.z
        cross = xp.cross
        w_rel = z * qd[..., None]
        w = w_rel.cumsum(1)
        dw = cross(w - w_rel, w_rel)
        if qdd is not None:
            dw = dw + z * qdd[..., None]
        dw = dw.cumsum(1)
        # base accel (-g for gravity) + rigid transport from each joint origin to the next
        d, wp = p[:, 1:] - p[:, :-1], w[:, :-1]
        a = xp.zeros(p.shape, p)
        if gravity:
            a[:, 0] = -self.gravity
        a[:, 1:] = cross(dw[:, :-1], d) + cross(wp, cross(wp, d))
        return w, dw, a.cumsum(1)

    def bias_at(self, links: Links, qd, gravity: bool = True, qdd=None):
        """Recursive Newton-Euler in world coordinates with prefix/suffix sums instead of per-joint
        recursion: C(q, qd) qd [+ g(q)] [+ M(q) qdd]."""
        xp, (_, p, z, c, inertia) = self.xp, links
        cross = xp.cross
        w, dw, a = self.motion(links, qd, gravity, qdd)
        r = c - p  # CoM offset in world axes
        f = self.masses[:, None] * (a + cross(dw, r) + cross(w, cross(w, r)))
        iw = inertia @ xp.stack([w, dw], -1)
        nn = iw[..., 1] + cross(w, iw[..., 0])
        # suffix sums: force/moment of all bodies beyond joint i, moments about p_i
        return (z * (xp.suffix_sum(nn + cross(c, f)) - cross(p, xp.suffix_sum(f)))).sum(-1)

    def gravity_torque(self, q):
        return self.rnea(q, self.xp.zeros(q.shape, q))

    def bias_torque(self, q, qd, frames=None):
        """Coriolis/centrifugal + gravity, C(q, qd) qd + g(q)."""
        return self.rnea(q, qd, frames=frames)

    def coriolis_torque(self, q, qd):
        return self.rnea(q, qd, gravity=False)

    def mass_matrix(self, q, frames=None):
        """M(q), (B, n, n)."""
        return self.mass_at(self.links(self.link_frames(q) if frames is None else frames))

    def mass_at(self, links: Links):
        """M(q) by the composite-rigid-body algorithm in world coordinates.

        With S_i = (z_i, p_i x z_i) joint i's unit twist (about the world origin) and F_j the
        momentum (angular about the origin, linear) of the composite body j..n-1 moving with S_j,
        M_ij = S_i . F_j for i <= j: ~20 batched array ops (one RNEA costs about as much).
        """
        xp, (_, p, z, c, inertia) = self.xp, links
        m = self.masses
        cc = (c * c).sum(-1)[..., None, None] * self._eye3 - c[..., :, None] * c[..., None, :]
        i_o = xp.suffix_sum(inertia + m[:, None, None] * cc)  # composite rotational inertia about the origin
        h = xp.suffix_sum(m[:, None] * c)  # composite first moment
        v = xp.cross(p, z)  # linear part of the unit twist at the origin
        ang = (i_o @ z[..., None])[..., 0] + xp.cross(h, v)
        lin = self._m_suf * v + xp.cross(z, h)
        g = z @ xp.swap(ang) + v @ xp.swap(lin)  # g[i, j] = S_i . F_j
        return xp.where(self._upper, g, xp.swap(g))

    def mass_matrix_rnea(self, q):
        """M(q) by n unit-acceleration RNEAs (slower; kept as an independent check of the CRBA)."""
        xp, (b, n) = self.xp, q.shape
        qn = xp.repeat(q, n)
        eye = xp.repeat(xp.eye(n, q)[None], b).reshape(b * n, n)
        return xp.swap(self.rnea(qn, xp.zeros(qn.shape, qn), eye, gravity=False).reshape(b, n, n))
