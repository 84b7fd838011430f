"""A drawer cabinet built in code: carcass (fixed root) + N prismatic drawers with bar handles.

Frame: origin at the bottom centre of the footprint; the drawer fronts face local -x (towards the
robot at yaw 0) and drawers open along -x. Each drawer's joint is prismatic with q in
[0, travel] (0 = closed); openness fraction = (q - lower) / (upper - lower) as in REALM.

REALM drives all drawer joints with kp = 0, kd = 1000 ("heavily damped"): a drawer stays where it
is left and only moves while pushed or pulled. We model that with a zero-stiffness joint drive of
``damping`` N.s/m (implicit in PhysX, stable at any value); the default 25 N.s/m resists 2.5 N at
10 cm/s. The top drawer (highest slot) is the task's target, as REALM's "top" joint.

The handle is a horizontal bar standing ``handle_standoff`` in front of the drawer face: wide
enough for the open 2F-85 (85 mm) to straddle it top-down.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sapien
import torch

from realm_ms.tasks.articulated.common import ArticulatedTaskObject, box, mat
from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix


@dataclass(frozen=True)
class CabinetGeometry:
    depth: float = 0.36  # x
    width: float = 0.44  # y
    height: float = 0.30  # z (top drawer handle 0.245 m above the table, 12 cm below the fingers at reset)
    panel: float = 0.015
    n_drawers: int = 3
    travel: float = 0.22  # m, full opening of a drawer
    clearance: float = 0.003
    handle_standoff: float = 0.06  # bar centre in front of the drawer face
    handle_length: float = 0.14
    handle_offsets: tuple = ()  # per drawer (bottom first): lateral handle offset (m); () = centred
    handle_half_xz: tuple = (0.008, 0.011)
    damping: float = 25.0  # N.s/m on the drawer joints
    body_rgba: tuple = (0.93, 0.91, 0.86, 1.0)
    front_rgba: tuple = (0.62, 0.45, 0.30, 1.0)
    handle_rgba: tuple = (0.75, 0.75, 0.78, 1.0)

    @property
    def slot_height(self) -> float:
        inner = self.height - 2 * self.panel
        return (inner - (self.n_drawers - 1) * self.panel) / self.n_drawers

    def slot_centre_z(self, k: int) -> float:
        """Centre height of slot ``k`` (0 = bottom)."""
        h, t = self.slot_height, self.panel
        return t + k * (h + t) + h / 2


# carcass / front / handle colours selectable with ``?look=k`` (perturbations: other cabinet models)
LOOKS = (
    ((0.93, 0.91, 0.86, 1.0), (0.62, 0.45, 0.30, 1.0), (0.75, 0.75, 0.78, 1.0)),
    ((0.30, 0.22, 0.15, 1.0), (0.85, 0.82, 0.75, 1.0), (0.20, 0.20, 0.20, 1.0)),
    ((0.60, 0.68, 0.72, 1.0), (0.92, 0.92, 0.94, 1.0), (0.85, 0.65, 0.25, 1.0)),
    ((0.85, 0.85, 0.85, 1.0), (0.35, 0.50, 0.40, 1.0), (0.90, 0.90, 0.92, 1.0)),
)
DRAWER_NAMES = {"bottom": 0, "middle": 1, "top": 2}


def scaled_geometry(g: CabinetGeometry, sx=1.0, sy=1.0, sz=1.0, look=0) -> CabinetGeometry:
    """Another cabinet model: carcass scaled per axis (travel follows the depth), colours from ``LOOKS``."""
    from dataclasses import replace

    body, front, handle = LOOKS[int(look) % len(LOOKS)]
    depth = g.depth * float(sx)
    return replace(g, depth=depth, width=g.width * float(sy), height=g.height * float(sz), travel=min(g.travel, 0.75 * depth),
                   handle_length=min(g.handle_length, 0.6 * g.width * float(sy)), body_rgba=body, front_rgba=front, handle_rgba=handle)


class DrawerCabinet(ArticulatedTaskObject):
    def __init__(self, env, spec, open: str | float = 0.0, damping: str | float | None = None, geometry: CabinetGeometry | None = None,
                 sx: float = 1.0, sy: float = 1.0, sz: float = 1.0, look: int = 0, drawer: str = "top", stagger: int = 0):
        super().__init__(env)
        g = geometry or CabinetGeometry()
        if damping is not None:
            from dataclasses import replace

            g = replace(g, damping=float(damping))
        if (float(sx), float(sy), float(sz), int(look)) != (1.0, 1.0, 1.0, 0):
            g = scaled_geometry(g, sx, sy, sz, look)
        if int(stagger):  # handles staggered sideways: each one reachable from above past the others
            from dataclasses import replace

            d = 0.13 * g.width / 0.44
            g = replace(g, handle_length=0.12 * g.width / 0.44, handle_offsets=tuple(d * (k - (g.n_drawers - 1) / 2) for k in range(g.n_drawers)))
        self.geom = g
        self.target_index = DRAWER_NAMES[drawer] if drawer in DRAWER_NAMES else int(drawer)  # the task's drawer
        self.init_open = float(open)
        self.footprint_radius = float(np.hypot(g.depth + 2 * g.handle_standoff, g.width) / 2)
        self.art = self._build(env.scene, spec.name)
        self.drawers = [self.art.links_map[f"drawer_{k}"] for k in range(g.n_drawers)]
        self.joints = [self.art.joints_map[f"drawer_{k}_joint"] for k in range(g.n_drawers)]
        self.top = self.drawers[self.target_index]  # the task's drawer ("top" in REALM's instruction)
        self._handle_local = torch.tensor([-g.handle_standoff, self._handle_y(self.target_index), 0.0], device=self.device)

    def _handle_y(self, k: int) -> float:
        return float(self.geom.handle_offsets[k]) if self.geom.handle_offsets else 0.0

    # ---------------------------------------------------------------- building
    def _build(self, scene, name: str):
        g = self.geom
        D, W, H, t, c = g.depth, g.width, g.height, g.panel, g.clearance
        body_m, front_m, handle_m = mat(g.body_rgba, 0.8), mat(g.front_rgba, 0.5), mat(g.handle_rgba, 0.3, 0.8)
        ab = scene.create_articulation_builder()
        root = ab.create_link_builder()
        root.set_name("carcass")
        box(root, (0, W / 2 - t / 2, H / 2), (D / 2, t / 2, H / 2), body_m)
        box(root, (0, -(W / 2 - t / 2), H / 2), (D / 2, t / 2, H / 2), body_m)
        box(root, (D / 2 - t / 2, 0, H / 2), (t / 2, W / 2 - t, H / 2), body_m)
        box(root, (0, 0, H - t / 2), (D / 2, W / 2, t / 2), body_m)
        box(root, (0, 0, t / 2), (D / 2, W / 2 - t, t / 2), body_m)
        h = g.slot_height
        for k in range(1, g.n_drawers):  # dividers
            z = g.slot_centre_z(k) - h / 2 - t / 2
            box(root, (0, 0, z), (D / 2, W / 2 - t, t / 2), body_m)

        dw = W / 2 - t - c  # drawer half width
        dh = h / 2 - c  # drawer half height
        dd = D - 2 * t - 0.01  # drawer depth (front face to back)
        wall = 0.008
        sx, (hx, hz) = g.handle_standoff, g.handle_half_xz
        for k in range(g.n_drawers):
            lb = ab.create_link_builder(root)
            lb.set_name(f"drawer_{k}")
            lb.set_joint_name(f"drawer_{k}_joint")
            # joint frame rotated by pi about z: q > 0 moves the drawer along the cabinet's -x
            flip = [0.0, 0.0, 0.0, 1.0]
            lb.set_joint_properties(
                "prismatic", limits=[[0.0, g.travel]],
                pose_in_parent=sapien.Pose([-D / 2, 0.0, g.slot_centre_z(k)], flip),
                pose_in_child=sapien.Pose([0, 0, 0], flip), friction=0.0, damping=g.damping,
            )
            # drawer frame: origin at the centre of the front face's back plane (flush with the carcass front)
            box(lb, (t / 2, 0, 0), (t / 2, dw, dh), front_m, density=400)  # front panel
            box(lb, (t + dd / 2, 0, -dh + wall / 2), (dd / 2, dw - 0.004, wall / 2), body_m, density=400)  # bottom
            for s in (-1, 1):
                box(lb, (t + dd / 2, s * (dw - 0.004 - wall / 2), -dh / 2 + wall / 2), (dd / 2, wall / 2, dh / 2 - wall), body_m, density=400)
            box(lb, (t + dd - wall / 2, 0, -dh / 2 + wall / 2), (wall / 2, dw - 0.004, dh / 2 - wall), body_m, density=400)
            # bar handle on two posts
            hy = self._handle_y(k)
            box(lb, (-sx, hy, 0), (hx, g.handle_length / 2, hz), handle_m, density=1000)
            for s in (-1, 1):
                box(lb, (-sx / 2, hy + s * (g.handle_length / 2 - 0.01), 0), (sx / 2, 0.006, 0.006), handle_m, density=1000)
        ab.initial_pose = sapien.Pose([0, 0, -2.0])
        art = ab.build(name=name, fix_root_link=True)
        for j in art.active_joints:  # damping only (PhysX joint friction is load-proportional)
            j.set_friction(0.0)
        return art

    # ---------------------------------------------------------------- state
    def _qpos_top(self) -> torch.Tensor:
        return self.art.get_qpos()[:, self.target_index]

    def openness(self) -> torch.Tensor:
        lim = self.art.get_qlimits()[:, self.target_index]  # (B, 2)
        return ((self._qpos_top() - lim[:, 0]) / (lim[:, 1] - lim[:, 0])).clamp(0.0, 1.0)

    def handle_pos(self) -> torch.Tensor:
        pose = self.top.pose
        return pose.p + (quaternion_to_matrix(pose.q) @ self._handle_local)

    def anchor_pos(self) -> torch.Tensor:
        """The top drawer's handle bar centre (REACH is measured to it, like to any object)."""
        return self.handle_pos()

    def touch_entities(self) -> list:
        return [self.top]

    def reset_joints(self, b: int) -> None:
        n = self.geom.n_drawers
        q = torch.zeros(b, n, device=self.device)
        q[:, self.target_index] = self.init_open * self.geom.travel
        self.art.set_qpos(q)
        self.art.set_qvel(torch.zeros_like(q))

    @property
    def front_x_local(self) -> float:
        return -self.geom.depth / 2

    def yaw(self) -> torch.Tensor:
        r = quaternion_to_matrix(self.pose.q)
        return torch.atan2(r[:, 1, 0], r[:, 0, 0])
