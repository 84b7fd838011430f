"""2 V-VIEW: external camera extrinsics shifted per reset (exterior_1, exterior_2; wrist untouched).

REALM picks one of 10 DROID-episode extrinsics per camera and adds U(-0.2, 0.2) m on x, y, z and
U(-0.2, 0.2) rad on pitch (Euler x of its USD camera) and yaw; no look-at correction. Our
nominal extrinsics are the task's DROID-like cameras; the offsets are REALM's: translation in the
robot base frame, yaw about the world vertical through the camera, pitch about the camera's own
lateral axis. Applied at reconfiguration (the camera configs are rebuilt with one pose per sub-env).
"""

from __future__ import annotations

import torch
from mani_skill.utils.structs.pose import Pose

from realm_ms.tasks.perturbation import Perturbation, as_float

SHIFT = 0.2  # m
TURN = 0.2  # rad


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ], -1)


def axis_quat(angle: torch.Tensor, axis: int) -> torch.Tensor:
    q = torch.zeros(angle.shape[0], 4, dtype=torch.float64)
    q[:, 0] = torch.cos(angle / 2)
    q[:, 1 + axis] = torch.sin(angle / 2)
    return q


def offset_pose(pose: Pose, d: torch.Tensor, pitch: torch.Tensor, yaw: torch.Tensor) -> Pose:
    """Batched: ``pose`` (1 or B) moved by ``d`` (B, 3), turned by ``yaw`` about world z and by
    ``pitch`` about the camera's local y (SAPIEN cameras: x forward, y left, z up)."""
    b = d.shape[0]
    raw = pose.raw_pose.detach().cpu().double().expand(b, 7)
    p = raw[:, :3] + d.double()
    q = quat_mul(quat_mul(axis_quat(yaw.double(), 2), raw[:, 3:]), axis_quat(pitch.double(), 1))
    return Pose.create_from_pq(p.float(), q.float())


class VView(Perturbation):
    pid = 2
    name = "V-VIEW"
    reconfigure = True
    acts_on = "external camera extrinsics (exterior_1, exterior_2)"
    ranges = f"per camera: x, y, z += U(-{SHIFT}, {SHIFT}) m; pitch, yaw += U(-{TURN}, {TURN}) rad"

    def draw(self, rng, ctx):
        out = {}
        for uid in ctx.camera_uids:
            dx, dy, dz = (as_float(v) for v in rng.uniform(-SHIFT, SHIFT, 3))
            pitch, yaw = (as_float(v) for v in rng.uniform(-TURN, TURN, 2))
            out[uid] = dict(dx=dx, dy=dy, dz=dz, pitch=pitch, yaw=yaw)
        return out

    def camera_pose(self, uid, pose, params):
        if not params or uid not in params[0]:
            return pose
        v = [p[uid] for p in params]
        d = torch.tensor([[x["dx"], x["dy"], x["dz"]] for x in v])
        return offset_pose(Pose.create(pose), d, torch.tensor([x["pitch"] for x in v]), torch.tensor([x["yaw"] for x in v]))
