"""Batched rigid-body model of a serial arm, parsed from a URDF: the robot's *own* model.

This is what the real controller knows about the arm (libfranka's gravity model, Polymetis'
pinocchio model): forward kinematics, the end-effector Jacobian, and inverse dynamics (RNEA) for
gravity and Coriolis feed-forward. The physics engine simulates the *true* articulation; any
difference between the two (a payload, a mis-modelled link) is a physical effect, which is exactly
what the sysid workbench looks for.

Everything is batched torch over a leading env dimension so physx_cpu and physx_cuda share one
code path. RNEA is written in world coordinates with prefix/suffix sums instead of per-joint Python
recursion: ~40 tensor ops per call regardless of the batch size.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

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


class ArmModel:
    """Serial chain from ``base_link`` to ``tip_link`` with revolute joints.

    Links hanging off the chain (the gripper, cameras) are lumped rigidly into the chain link they
    are attached to, at their zero configuration, as a robot vendor's model of a mounted end
    effector would be.
    """

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
        return self

    # ------------------------------------------------------------------ kinematics
    def link_frames(self, q: torch.Tensor) -> torch.Tensor:
        """World (base) transforms of the n moving bodies, shape (B, n, 4, 4)."""
        s, c = torch.sin(q)[..., None, None], torch.cos(q)[..., None, None]
        local = (self.origins + s * self._OK + (1 - c) * self._OK2).unbind(1)
        t = local[0]
        frames = [t]
        for m in local[1:]:
            t = t @ m
            frames.append(t)
        return torch.stack(frames, dim=1)

    def fk(self, q: torch.Tensor, frames: torch.Tensor | None = None) -> torch.Tensor:
        """Tip pose (B, 4, 4) in the base frame."""
        frames = self.link_frames(q) if frames is None else frames
        return frames[:, -1] @ self.tip_offset

    def jacobian(self, q: torch.Tensor, frames: torch.Tensor | None = None) -> torch.Tensor:
        """Geometric Jacobian of the tip (B, 6, n): rows [linear velocity; angular velocity], base frame."""
        frames = self.link_frames(q) if frames is None else frames
        z = (frames[..., :3, :3] @ self.axes[..., None])[..., 0]  # (B,n,3)
        p = frames[..., :3, 3]
        tip = (frames[:, -1] @ self.tip_offset)[:, None, :3, 3]
        return torch.cat([torch.linalg.cross(z, tip - p, dim=-1), z], dim=-1).transpose(1, 2)

    # ------------------------------------------------------------------ dynamics
    def rnea(
        self,
        q: torch.Tensor,
        qd: torch.Tensor,
        qdd: torch.Tensor | None = None,
        gravity: bool = True,
        frames: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """Inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q), batched (B, n)."""
        frames = self.link_frames(q) if frames is None else frames
        rot, p = frames[..., :3, :3], frames[..., :3, 3]  # (B,n,3,3), (B,n,3)
        z = (rot @ self.axes[..., None])[..., 0]
        cross = torch.linalg.cross
        w_rel = z * qd[..., None]
        w = torch.cumsum(w_rel, dim=1)  # angular velocity of body i
        w_prev = w - w_rel
        dw_terms = cross(w_prev, w_rel, dim=-1)
        if qdd is not None:
            dw_terms = dw_terms + z * qdd[..., None]
        dw = torch.cumsum(dw_terms, dim=1)
        # linear acceleration of each body's origin: base accel (-g for gravity) + rigid transport
        d = torch.diff(p, dim=1)  # p_i - p_{i-1}, i >= 1
        dw_prev, w_prev_body = dw[:, :-1], w[:, :-1]
        trans = cross(dw_prev, d, dim=-1) + cross(w_prev_body, cross(w_prev_body, d, dim=-1), dim=-1)
        a0 = (-self.gravity if gravity else torch.zeros_like(self.gravity)).expand(q.shape[0], 1, 3)
        a = torch.cumsum(torch.cat([a0, trans], dim=1), dim=1)
        c = (frames @ self._com_h)[..., :3, 0]  # CoM positions
        r = c - p  # CoM offset in world axes
        ac = a + cross(dw, r, dim=-1) + cross(w, cross(w, r, dim=-1), dim=-1)
        f = self.masses[:, None] * ac  # (B,n,3)
        inertia_w = rot @ self.inertias @ rot.transpose(-1, -2)
        iw, idw = (inertia_w @ torch.stack([w, dw], dim=-1)).unbind(-1)
        nn = idw + cross(w, iw, dim=-1)
        # suffix sums: force/moment of all bodies beyond joint i, moments about p_i
        rev = lambda x: torch.flip(torch.cumsum(torch.flip(x, [1]), 1), [1])  # noqa: E731
        f_sum = rev(f)
        moment = rev(nn + cross(c, f, dim=-1)) - cross(p, f_sum, dim=-1)
        return (z * moment).sum(-1)

    def gravity_torque(self, q: torch.Tensor) -> torch.Tensor:
        return self.rnea(q, torch.zeros_like(q))

    def bias_torque(self, q: torch.Tensor, qd: torch.Tensor, frames: torch.Tensor | None = None) -> torch.Tensor:
        """Coriolis/centrifugal + gravity, C(q, qd) qd + g(q)."""
        return self.rnea(q, qd, frames=frames)

    def coriolis_torque(self, q: torch.Tensor, qd: torch.Tensor) -> torch.Tensor:
        return self.rnea(q, qd, gravity=False)

    def mass_matrix(self, q: torch.Tensor, frames: torch.Tensor | None = None) -> torch.Tensor:
        """M(q), (B, n, n), by the composite-rigid-body algorithm in world coordinates.

        With S_i = (z_i, p_i x z_i) joint i's unit twist (about the world origin) and F_j the
        momentum (angular about the origin, linear) of the composite body j..n-1 moving with S_j,
        M_ij = S_i . F_j for i <= j: ~20 batched tensor ops (one RNEA costs about as much).
        """
        frames = self.link_frames(q) if frames is None else frames
        rot, p = frames[..., :3, :3], frames[..., :3, 3]
        z = (rot @ self.axes[..., None])[..., 0]
        c = (frames @ self._com_h)[..., :3, 0]  # CoM positions (B,n,3)
        m = self.masses
        cross = torch.linalg.cross
        inertia_w = rot @ self.inertias @ rot.transpose(-1, -2)
        cc = (c * c).sum(-1)[..., None, None] * torch.eye(3, device=q.device, dtype=q.dtype) - c[..., :, None] * c[..., None, :]
        rev = lambda x: torch.flip(torch.cumsum(torch.flip(x, [1]), 1), [1])  # noqa: E731
        i_o = rev(inertia_w + m[:, None, None] * cc)  # composite rotational inertia about the origin
        h = rev(m[:, None] * c)  # composite first moment
        m_suf = rev(m[None].expand(q.shape[0], -1))[..., None]
        v = cross(p, z, dim=-1)  # linear part of the unit twist at the origin
        ang = (i_o @ z[..., None])[..., 0] + cross(h, v, dim=-1)
        lin = m_suf * v + cross(z, h, dim=-1)
        g = z @ ang.transpose(1, 2) + v @ lin.transpose(1, 2)  # g[i, j] = S_i . F_j
        upper = torch.triu(g)
        return upper + torch.triu(g, 1).transpose(1, 2)

    def mass_matrix_rnea(self, q: torch.Tensor) -> torch.Tensor:
        """M(q) by n unit-acceleration RNEAs (slower; kept as an independent check of the CRBA)."""
        b, n = q.shape
        qn = q.repeat_interleave(n, 0)
        eye = torch.eye(n, device=q.device, dtype=q.dtype).repeat(b, 1)
        cols = self.rnea(qn, torch.zeros_like(qn), eye, gravity=False)
        return cols.view(b, n, n).transpose(1, 2)


_P1, _P2 = np.array([1, 2, 0]), np.array([2, 0, 1])


def _suffix_sum(x: np.ndarray) -> np.ndarray:
    """Sum over links i..n-1 (axis 1): what link i carries of the links after it."""
    return x[:, ::-1].cumsum(1)[:, ::-1]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis, as permuted products (7 array ops; ~3x faster than np.cross and
    than a Levi-Civita einsum on the (B*steps, 7, 3) arrays of a batched plan)."""
    return a[..., _P1] * b[..., _P2] - a[..., _P2] * b[..., _P1]


class NumpyArmModel:
    """The same kinematics and dynamics in float64 numpy, for the CPU controller with few envs:
    the law is ~150 tiny array ops per model evaluation, and numpy's per-op overhead is ~5x below
    eager torch's. Mirrors ``ArmModel`` op for op (tests check they agree)."""

    def __init__(self, model: ArmModel):
        f = lambda t: t.detach().cpu().double().numpy()  # noqa: E731
        self.dof = model.dof
        self.origins, self.axes, self.masses = f(model.origins), f(model.axes), f(model.masses)
        self.inertias, self.tip_offset, self.gravity = f(model.inertias), f(model.tip_offset), f(model.gravity)
        self._OK, self._OK2, self._com_h = f(model._OK), f(model._OK2), f(model._com_h)
        self._eye3 = np.eye(3)
        self._m_suf = np.cumsum(self.masses[::-1])[::-1].copy()  # mass of links i..n-1
        self._upper = np.triu(np.ones((self.dof, self.dof), dtype=bool))
        self._zero3 = np.zeros(3)

    def link_frames(self, q: np.ndarray) -> np.ndarray:
        s, c = np.sin(q)[..., None, None], np.cos(q)[..., None, None]
        local = self.origins + s * self._OK + (1 - c) * self._OK2
        frames = np.empty_like(local)
        frames[:, 0] = t = local[:, 0]
        for i in range(1, self.dof):
            frames[:, i] = t = t @ local[:, i]
        return frames

    def jacobian(self, frames: np.ndarray) -> np.ndarray:
        z = frames[..., :3, :3] @ self.axes[..., None]
        tip = (frames[:, -1] @ self.tip_offset)[:, None, :3, 3]
        return np.concatenate([_cross(z[..., 0], tip - frames[..., :3, 3]), z[..., 0]], axis=-1).transpose(0, 2, 1)

    def rnea(self, frames: np.ndarray, qd: np.ndarray, gravity: bool = True) -> np.ndarray:
        """C(q, qd) qd (+ g(q)): ``ArmModel.rnea`` with zero acceleration."""
        return self.bias(self.world(frames), qd, gravity)

    def mass_matrix(self, frames: np.ndarray) -> np.ndarray:
        return self.mass(self.world(frames))

    def bias_and_mass(self, frames: np.ndarray, qd: np.ndarray, gravity: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(C(q, qd) qd [+ g(q)], M(q)) sharing the per-link world quantities of both."""
        world = self.world(frames)
        return self.bias(world, qd, gravity), self.mass(world)

    def world(self, frames: np.ndarray) -> tuple:
        """Per-link world quantities shared by ``bias`` and ``mass``: joint origins p, axes z, centres
        of mass c, inertias (a tuple of arrays with the batch first; slice them to take a sub-batch)."""
        rot, p = frames[..., :3, :3], frames[..., :3, 3]
        z = (rot @ self.axes[..., None])[..., 0]
        c = (frames @ self._com_h)[..., :3, 0]
        inertia_w = rot @ self.inertias @ rot.transpose(0, 1, 3, 2)
        return p, z, c, inertia_w

    def bias(self, world: tuple, qd: np.ndarray, gravity: bool = True) -> np.ndarray:
        """Recursive Newton-Euler with zero joint acceleration."""
        p, z, c, inertia_w = world
        w_rel = z * qd[..., None]
        w = w_rel.cumsum(1)
        dw = _cross(w - w_rel, w_rel).cumsum(1)
        d = p[:, 1:] - p[:, :-1]
        wp = w[:, :-1]
        a = np.empty_like(p)
        a[:, 0] = -self.gravity if gravity else self._zero3
        a[:, 1:] = _cross(dw[:, :-1], d) + _cross(wp, _cross(wp, d))
        a = a.cumsum(1)
        r = c - p
        f = self.masses[:, None] * (a + _cross(dw, r) + _cross(w, _cross(w, r)))
        iw_dw = inertia_w @ np.stack([w, dw], axis=-1)
        nn = iw_dw[..., 1] + _cross(w, iw_dw[..., 0])
        return (z * (_suffix_sum(nn + _cross(c, f)) - _cross(p, _suffix_sum(f)))).sum(-1)

    def mass(self, world: tuple) -> np.ndarray:
        """Composite rigid bodies: M(q), symmetric."""
        p, z, c, inertia_w = world
        m = self.masses
        cc = (c * c).sum(-1)[..., None, None] * self._eye3 - c[..., :, None] * c[..., None, :]
        i_o = _suffix_sum(inertia_w + m[:, None, None] * cc)
        h = _suffix_sum(m[:, None] * c)
        v = _cross(p, z)
        ang = (i_o @ z[..., None])[..., 0] + _cross(h, v)
        lin = self._m_suf[:, None] * v + _cross(z, h)
        g = z @ ang.transpose(0, 2, 1) + v @ lin.transpose(0, 2, 1)
        return np.where(self._upper, g, g.transpose(0, 2, 1))
