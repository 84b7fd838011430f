"""Batched damped-least-squares IK for the DROID arm on the robot's own model (``droid_arm_model``).

Targets are TCP poses in the robot base frame. The TCP is rigidly attached to the flange
(``panda_link8``); the flange->TCP transform is read once from the simulated robot, so it follows
whatever mount the URDF renders (``urdf.MOUNT_YAW``, ``TCP_OFFSET_FROM_FLANGE``).

Gripper frame convention (checked on the sim): TCP z points out of the gripper (down for a top-down
grasp), TCP y is the closing direction (pad to pad).
"""

from __future__ import annotations

import math

import torch

from realm_ms.agents.panda_droid import droid_arm_model
from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

# a comfortable posture for null-space bias (DROID reset pose)
REST_Q = (0.0, -math.pi / 5, 0.0, -4 * math.pi / 5, 0.0, 3 * math.pi / 5, 0.0)


def pose_matrix(p: torch.Tensor, q_wxyz: torch.Tensor) -> torch.Tensor:
    t = torch.eye(4, dtype=p.dtype, device=p.device).repeat(p.shape[0], 1, 1)
    t[:, :3, :3] = quaternion_to_matrix(q_wxyz)
    t[:, :3, 3] = p
    return t


def top_down_rotation(yaw: torch.Tensor, tilt: torch.Tensor | None = None) -> torch.Tensor:
    """TCP rotation (B,3,3) pointing down with closing direction (TCP y) at angle ``yaw`` in the xy plane.

    ``tilt`` (rad) pitches the approach axis about the closing axis (0 = straight down)."""
    c, s = torch.cos(yaw), torch.sin(yaw)
    z0 = torch.zeros_like(yaw)
    y = torch.stack([c, s, z0], -1)
    z = torch.stack([z0, z0, -torch.ones_like(yaw)], -1)
    x = torch.linalg.cross(y, z, dim=-1)
    r = torch.stack([x, y, z], -1)  # columns
    if tilt is not None:
        # rotate about the TCP y axis (closing direction), in the TCP frame
        ct, st = torch.cos(tilt), torch.sin(tilt)
        o, l = torch.zeros_like(tilt), torch.ones_like(tilt)
        ry = torch.stack([torch.stack([ct, o, st], -1), torch.stack([o, l, o], -1), torch.stack([-st, o, ct], -1)], -2)
        r = r @ ry
    return r


def rotation_error(r_target: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
    """Axis-angle vector (B,3) of r_target @ r^T (world frame)."""
    e = r_target @ r.transpose(-1, -2)
    cos = ((e.diagonal(dim1=-2, dim2=-1).sum(-1) - 1) / 2).clamp(-1, 1)
    ang = torch.acos(cos)
    v = torch.stack([e[:, 2, 1] - e[:, 1, 2], e[:, 0, 2] - e[:, 2, 0], e[:, 1, 0] - e[:, 0, 1]], -1)
    s = torch.sin(ang)
    k = torch.where(s.abs() > 1e-5, ang / (2 * s.clamp(min=1e-5)), torch.full_like(ang, 0.5))
    return v * k[:, None]


class ArmIK:
    """DLS IK from TCP poses (base frame) to the 7 arm joints; batched over envs."""

    def __init__(self, flange_to_tcp: torch.Tensor, damping: float = 0.05, rest_q=REST_Q, null_gain: float = 0.05):
        self.model = droid_arm_model().to("cpu", torch.float64)
        self.flange_to_tcp = flange_to_tcp.to(torch.float64)  # (4,4)
        self.damping = damping
        self.lo = torch.as_tensor(self.model.q_limits[:, 0], dtype=torch.float64) + 0.02
        self.hi = torch.as_tensor(self.model.q_limits[:, 1], dtype=torch.float64) - 0.02
        self.rest = torch.as_tensor(rest_q, dtype=torch.float64)
        self.null_gain = null_gain

    @classmethod
    def from_agent(cls, agent, **kw) -> "ArmIK":
        """Read the flange->TCP transform off the simulated robot (env 0)."""
        model = droid_arm_model().to("cpu", torch.float64)
        q = agent.arm_qpos[:1].detach().cpu().to(torch.float64)
        base = agent.robot.pose
        t_base = pose_matrix(base.p[:1].cpu().double(), base.q[:1].cpu().double())
        tcp = agent.tcp_pose
        t_tcp = pose_matrix(tcp.p[:1].cpu().double(), tcp.q[:1].cpu().double())
        t_flange = t_base @ model.fk(q)
        return cls(torch.linalg.inv(t_flange[0]) @ t_tcp[0], **kw)

    def tcp_fk(self, q: torch.Tensor) -> torch.Tensor:
        return self.model.fk(q.double()) @ self.flange_to_tcp

    def solve(self, q0: torch.Tensor, p: torch.Tensor, r: torch.Tensor, iters: int = 30, tol: float = 1e-4,
              rot_weight: float = 0.5) -> tuple[torch.Tensor, torch.Tensor]:
        """Joint solution (B,7) near ``q0`` for TCP position ``p`` (B,3) and rotation ``r`` (B,3,3)
        in the base frame; also returns the final position error norm (B,)."""
        q = q0.detach().double().clone()
        p, r = p.double(), r.double()
        eye = torch.eye(6, dtype=q.dtype)
        w = torch.tensor([1, 1, 1, rot_weight, rot_weight, rot_weight], dtype=q.dtype)
        for _ in range(iters):
            frames = self.model.link_frames(q)
            t = frames[:, -1] @ self.model.tip_offset @ self.flange_to_tcp
            ep = p - t[:, :3, 3]
            er = rotation_error(r, t[:, :3, :3])
            err = torch.cat([ep, er], -1)
            if float(err.abs().max()) < tol:
                break
            jf = self.model.jacobian(q, frames)  # flange Jacobian; shift to the TCP point
            off = t[:, :3, 3] - (frames[:, -1] @ self.model.tip_offset)[:, :3, 3]
            jw = jf[:, 3:].transpose(1, 2)  # (B,7,3) angular columns
            jv = jf[:, :3] + torch.linalg.cross(jw, off[:, None, :].expand_as(jw), dim=-1).transpose(1, 2)
            j = torch.cat([jv, jf[:, 3:]], 1) * w[None, :, None]
            e = err * w
            jjt = j @ j.transpose(1, 2) + (self.damping**2) * eye
            dq = (j.transpose(1, 2) @ torch.linalg.solve(jjt, e[..., None]))[..., 0]
            # null-space pull toward the rest posture
            jp = j.transpose(1, 2) @ torch.linalg.solve(jjt, j)
            n = torch.eye(7, dtype=q.dtype) - jp
            dq = dq + self.null_gain * (n @ (self.rest - q)[..., None])[..., 0]
            q = torch.clamp(q + dq.clamp(-0.3, 0.3), self.lo, self.hi)
        t = self.tcp_fk(q)
        return q, (p - t[:, :3, 3]).norm(dim=-1)
