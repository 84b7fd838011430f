"""13 VB-POSE: the main object's initial pose, drawn per reset relative to the task's own placement.

REALM: the main object re-placed uniformly in the spawn box, collision-free against the others
(which stay), yaw noise N(0, 3.14 rad) added; drawers: yaw + clip(N(0.25, 0.12), 0, 0.57) rad;
the push switch: z += U(-0.15, 0.15) m, x += U(-0.075, 0.075) m. Fixed here: always relative to the
pose the task placed this episode (never to the previous perturbed pose).

Our Default already samples the main object uniformly in its region with a random yaw (REALM's
Default uses the config pose), so for rigid objects VB-POSE enlarges the region by ``GROW`` m on
every side (clipped to the reachable table area) before re-placing, and adds the yaw noise. Our
switch sits on the table, not on a wall: its height offset is |U(-0.15, 0.15)| (it is raised as if
mounted on a wall box; it cannot sink into the table).
"""

from __future__ import annotations

import numpy as np
import torch

from realm_ms.tasks.perturbation import Perturbation, as_float
from realm_ms.tasks.placement import sample_placements
from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix

YAW_STD = 3.14
GROW = 0.08  # m added to each side of the main object's region
REACH = (0.28, 0.85, -0.50, 0.50)  # x_min, x_max, y_min, y_max the arm reaches top-down
SWITCH_X = 0.075
SWITCH_Z = 0.15
DRAWER_YAW = (0.25, 0.12, 0.0, 0.57)  # mean, std, clip lo, hi


def grown_region(region) -> tuple[float, float, float, float]:
    x0, x1, y0, y1 = region
    return (max(x0 - GROW, REACH[0]), min(x1 + GROW, REACH[1]), max(y0 - GROW, REACH[2]), min(y1 + GROW, REACH[3]))


def current_yaw(q: torch.Tensor) -> torch.Tensor:
    r = quaternion_to_matrix(q)
    return torch.atan2(r[..., 1, 0], r[..., 0, 0])


class VBPose(Perturbation):
    pid = 13
    name = "VB-POSE"
    acts_on = "the main object's initial pose"
    ranges = (f"rigid: uniform in the main region grown by {GROW} m, yaw += N(0, {YAW_STD}); "
              f"drawer: yaw += clip(N{DRAWER_YAW[:2]}, {DRAWER_YAW[2]}, {DRAWER_YAW[3]}); switch: x += U(+-{SWITCH_X}), z += |U(+-{SWITCH_Z})| m")

    def draw(self, rng, ctx):
        skill = ctx.spec.skill
        if skill == "push":
            return dict(dx=as_float(rng.uniform(-SWITCH_X, SWITCH_X)), dz=as_float(abs(rng.uniform(-SWITCH_Z, SWITCH_Z))))
        if skill in ("open_drawer", "close_drawer"):
            m, s, lo, hi = DRAWER_YAW
            return dict(dyaw=as_float(np.clip(rng.normal(m, s), lo, hi)))
        return dict(dyaw=as_float(rng.normal(0.0, YAW_STD)), placement_seed=int(rng.integers(2**31)))

    def on_episode_init(self, env, env_idx, params):
        main = env.main
        spec = env.active_spec
        idx = [int(i) for i in env_idx]
        pose = main.pose
        p = pose.p[idx].clone()
        yaw = current_yaw(pose.q[idx])
        if spec.skill == "push":
            p[:, 0] += torch.tensor([x["dx"] for x in params], device=p.device)
            p[:, 2] += torch.tensor([x["dz"] for x in params], device=p.device)
        elif spec.skill in ("open_drawer", "close_drawer"):
            yaw = yaw + torch.tensor([x["dyaw"] for x in params], device=p.device)
        else:
            others = [o for name, o in env.objects.items() if o is not main]
            region = grown_region(spec.main.region or spec.spawn_region)
            for k, (i, x) in enumerate(zip(idx, params)):
                obstacles = [(float(o.pose.p[i, 0]), float(o.pose.p[i, 1]), o.footprint_radius) for o in others]
                xy, _ = sample_placements([np.random.default_rng(x["placement_seed"])], [main.footprint_radius], [region], [(0.0, 0.0)],
                                          min_separation=spec.min_separation, obstacles=obstacles)
                p[k, 0], p[k, 1] = float(xy[0, 0, 0]), float(xy[0, 0, 1])
            yaw = yaw + torch.tensor([x["dyaw"] for x in params], device=p.device)
        main.set_pose(p, yaw)  # sized to the reset sub-envs (ManiSkill's reset mask)
        for k, x in enumerate(params):
            x["pose"] = [as_float(v) for v in p[k].tolist()] + [as_float(torch.remainder(yaw[k] + np.pi, 2 * np.pi) - np.pi)]  # x, y, z, yaw
