"""A rocker light switch built in code, toggled physically by pressing the rocker past its centre.

Base (fixed root, a small box on the table) + rocker link on a revolute joint about the base's
local y axis, limited to +-``tilt``. The rocker's centre of mass sits above the pivot, so gravity
holds it against whichever limit it leans towards: an over-centre detent, bistable like a real
rocker switch. Pressing the raised end down past the centre flips it, and it snaps to the other
limit. ``toggled()`` = the rocker angle is past ``on_threshold`` on the "on" side (q > 0); there is
no timer and no scripted state. At reset the rocker is set to the "off" limit (or "on" with
``?on=1``).

Mounting (``?mount=wall|table``, default: the scene's ``switch_mount``):
- ``table``: a desk rocker. Origin at the housing's bottom centre; the "off" position raises the
  rocker's +x end (pointing away from the robot at yaw 0), so pressing that end down turns it on.
- ``wall`` (REALM's Light_Switch): a wall panel stands on the table, its front face at the origin
  plane x = 0 and facing the robot (-x); the switch sits on it in a surface box, its centre
  ``height`` above the table (the scene's ``switch_height``). The rocker's "on" end is its top:
  pressing the raised top towards the wall (+x) turns it on (for an "off" goal, ``?goal=off``, the
  switch is mounted upside down, so the end to press is again the top). Gravity cannot make a detent about
  a horizontal axis in a wall by itself, so the rocker's centre of mass is set above its pivot
  (as the table switch has it): the same over-centre detent, the same snap.
The panel goes ``WallMount.sink`` below the table top (hidden under it), so a switch raised by
VB-POSE stays on its wall. ``press_point_local()`` / ``press_direction_local()`` tell a policy
where and which way to press. The "on" half of the rocker carries an orange stripe.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sapien
import torch

from realm_ms.tasks.articulated.common import ArticulatedTaskObject, box, mat
from mani_skill.utils.geometry.rotation_conversions import quaternion_to_matrix


@dataclass(frozen=True)
class SwitchGeometry:
    base_half: tuple = (0.06, 0.045, 0.02)  # x, y, z half sizes of the housing
    rocker_half: tuple = (0.045, 0.032, 0.007)
    pivot_height: float = 0.018  # rocker plate centre above the pivot (CoM above it; plate clears the housing at +-tilt)
    tilt: float = 0.21  # rad, rest angle at either limit (~12 deg)
    on_threshold: float = 0.0  # rad, toggled when q > threshold
    joint_friction: float = 0.0
    joint_damping: float = 0.002
    rocker_density: float = 3000.0
    base_rgba: tuple = (0.92, 0.92, 0.90, 1.0)
    rocker_rgba: tuple = (0.97, 0.97, 0.97, 1.0)
    on_rgba: tuple = (0.95, 0.45, 0.10, 1.0)


@dataclass(frozen=True)
class WallMount:
    """The wall panel a wall switch sits on (root frame: front face at x = 0, table top at z = 0)."""

    standoff: float = 0.03  # surface box between the panel and the switch housing (keeps the hand off the wall)
    # thickness/2, width/2, height/2 of the panel above the table top. 16 cm wide: two switches placed
    # in a task region (footprints apart) never stand in front of each other's (SB-NOUN adds one)
    panel_half: tuple = (0.02, 0.08, 0.28)
    sink: float = 0.16  # panel extends this far below the table top (hidden), covering VB-POSE's raise
    panel_rgba: tuple = (0.90, 0.89, 0.86, 1.0)
    box_rgba: tuple = (0.96, 0.96, 0.95, 1.0)


# colour schemes (base, rocker, on-stripe) selectable with ``?look=k`` (perturbations: other switch models)
LOOKS = (
    ((0.92, 0.92, 0.90, 1.0), (0.97, 0.97, 0.97, 1.0), (0.95, 0.45, 0.10, 1.0)),
    ((0.15, 0.15, 0.16, 1.0), (0.25, 0.25, 0.27, 1.0), (0.10, 0.75, 0.25, 1.0)),
    ((0.80, 0.70, 0.55, 1.0), (0.85, 0.20, 0.15, 1.0), (0.98, 0.95, 0.85, 1.0)),
    ((0.55, 0.60, 0.68, 1.0), (0.90, 0.92, 0.95, 1.0), (0.15, 0.40, 0.90, 1.0)),
)


def scaled_geometry(g: SwitchGeometry, sx=1.0, sy=1.0, sz=1.0, look=0) -> SwitchGeometry:
    """Another switch model: housing / rocker scaled per axis, colours from ``LOOKS``."""
    from dataclasses import replace

    s = (float(sx), float(sy), float(sz))
    base, rocker, on = LOOKS[int(look) % len(LOOKS)]
    return replace(
        g, base_half=tuple(h * k for h, k in zip(g.base_half, s)), rocker_half=tuple(h * k for h, k in zip(g.rocker_half, s)),
        pivot_height=g.pivot_height * s[2], base_rgba=base, rocker_rgba=rocker, on_rgba=on,
        rocker_density=g.rocker_density / (s[0] * s[1] * s[2]) ** 0.5,  # keep the detent torque in range
    )


MOUNTS = ("table", "wall")


class LightSwitch(ArticulatedTaskObject):
    def __init__(self, env, spec, on: str | int = 0, geometry: SwitchGeometry | None = None,
                 sx: float = 1.0, sy: float = 1.0, sz: float = 1.0, look: int = 0, goal: str = "on",
                 mount: str | None = None, height: float | None = None, wall: WallMount | None = None):
        super().__init__(env)
        g = geometry or SwitchGeometry()
        if (float(sx), float(sy), float(sz), int(look)) != (1.0, 1.0, 1.0, 0):
            g = scaled_geometry(g, sx, sy, sz, look)
        self.geom = g
        self.init_on = bool(int(on))
        self.goal_on = goal != "off"  # "off": the task is to turn it off (toggled() = reached the off side)
        scene_def = getattr(env, "scene_def", None)
        self.mount = mount or getattr(scene_def, "switch_mount", "table")
        if self.mount not in MOUNTS:
            raise ValueError(f"light switch mount={self.mount!r}; use one of {MOUNTS} (asset 'articulated/light_switch?mount=wall')")
        self.wall = wall or WallMount()
        self.height = float(height if height is not None else getattr(scene_def, "switch_height", 0.15))
        # placement footprint: the switch, and on a wall also the panel's width
        self.footprint_radius = float(np.hypot(g.base_half[0], g.base_half[1]))
        if self.mount == "wall":
            self.footprint_radius = max(self.footprint_radius, self.wall.panel_half[1])
        self.mount_pose = self._mount_pose()
        self.art = self._build(env.scene, spec.name)
        self.rocker = self.art.links_map["rocker"]
        self._anchor_local = torch.tensor([0.0, 0.0, g.pivot_height], device=self.device)

    def _mount_pose(self) -> sapien.Pose:
        """The switch frame (housing bottom centre, rocker along +x, facing +z) in the root frame."""
        if self.mount == "table":
            return sapien.Pose()
        half = np.sqrt(0.5)  # -90 deg about y: switch +z -> root -x (towards the robot), switch +x -> up
        pose = sapien.Pose([-self.wall.standoff, 0.0, self.height], [half, 0.0, -half, 0.0])
        # the end to press is the top one: a top-down gripper's upright fingers pressing the lower end
        # would cover the pivot and block the upper end from coming out (an "off" goal: upside down)
        return pose if self.goal_on else pose * sapien.Pose(q=[0.0, 0.0, 0.0, 1.0])

    def _build(self, scene, name: str):
        g = self.geom
        bx, by, bz = g.base_half
        rx, ry, rz = g.rocker_half
        m = self.mount_pose
        ab = scene.create_articulation_builder()
        root = ab.create_link_builder()
        root.set_name("housing")
        if self.mount == "wall":
            w = self.wall
            px, py, pz = w.panel_half
            box(root, (px, 0, pz), (px, py, pz), mat(w.panel_rgba, 0.9), density=800)
            box(root, (px, 0, -w.sink / 2), (px, py, w.sink / 2), mat(w.panel_rgba, 0.9), collision=False)
            sb = (w.standoff / 2, by + 0.01, bx + 0.01)  # surface box, slightly larger than the housing
            box(root, (-w.standoff / 2, 0, self.height), sb, mat(w.box_rgba, 0.5), density=800)
        box(root, (m * sapien.Pose([0, 0, bz])).p, (bx, by, bz), mat(g.base_rgba, 0.5), density=800, q=m.q)
        lb = ab.create_link_builder(root)
        lb.set_name("rocker")
        lb.set_joint_name("rocker_joint")
        # revolute axis = joint-frame x; rotate the joint frame so that it is the switch's y axis
        q_axis = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]  # +90 deg about z: x -> y
        lb.set_joint_properties(
            "revolute", limits=[[-g.tilt, g.tilt]],
            pose_in_parent=m * sapien.Pose([0, 0, 2 * bz], q_axis), pose_in_child=sapien.Pose([0, 0, 0], q_axis),
            friction=g.joint_friction, damping=g.joint_damping,
        )
        # the rocker link's frame is the switch frame moved to the pivot
        box(lb, (0, 0, g.pivot_height), (rx, ry, rz), mat(g.rocker_rgba, 0.35), density=g.rocker_density)
        box(lb, (0, 0, (g.pivot_height - rz) / 2), (0.008, ry * 0.9, (g.pivot_height - rz) / 2), mat(g.base_rgba, 0.5), collision=False)  # pivot web
        box(lb, (rx * 0.55, 0, g.pivot_height + rz + 0.0005), (rx * 0.3, ry * 0.6, 0.0005), mat(g.on_rgba, 0.4), collision=False)
        if self.mount == "wall":
            # the plate's mass with its centre straight above the pivot: gravity's over-centre detent
            # as on the table, where the plate's own centre of mass lies above it
            up = m.to_transformation_matrix()[:3, :3].T @ np.array([0.0, 0.0, 1.0])  # world up in the rocker frame
            mass = g.rocker_density * 8 * rx * ry * rz
            inertia = [mass / 3 * (ry**2 + rz**2), mass / 3 * (rx**2 + rz**2), mass / 3 * (rx**2 + ry**2)]
            lb.set_mass_and_inertia(mass, sapien.Pose(list(g.pivot_height * up)), inertia)
        ab.initial_pose = sapien.Pose([0, 0, -2.0])
        art = ab.build(name=name, fix_root_link=True)
        # PhysX joint friction is a load-proportional coefficient (SAPIEN defaults it to 0.05): it would
        # lock the light rocker; the detent comes from gravity alone
        for j in art.active_joints:
            j.set_friction(g.joint_friction)
        return art

    # joint sign: rotating about +y by q tilts the +x end DOWN for q > 0
    def angle(self) -> torch.Tensor:
        return self.art.get_qpos()[:, 0]

    def toggled(self) -> torch.Tensor:
        """The switch has reached the task's goal state (on, or off with ``?goal=off``)."""
        a = self.angle()
        return a > self.geom.on_threshold if self.goal_on else a < -self.geom.on_threshold

    def anchor_pos(self) -> torch.Tensor:
        """Centre of the rocker plate."""
        pose = self.rocker.pose
        return pose.p + (quaternion_to_matrix(pose.q) @ self._anchor_local)

    def press_point_local(self) -> tuple[float, float, float]:
        """Where to press (in the root frame) to reach the goal: the raised end of the rocker's face."""
        g = self.geom
        x = g.rocker_half[0] * 0.7
        z = 2 * g.base_half[2] + g.pivot_height + g.rocker_half[2] + x * np.sin(g.tilt)
        return tuple(float(v) for v in (self.mount_pose * sapien.Pose([x if self.goal_on else -x, 0.0, z])).p)

    def press_direction_local(self) -> tuple[float, float, float]:
        """Which way to press (unit vector, root frame): into the switch face (down on a table, +x on a wall)."""
        return tuple(float(v) for v in self.mount_pose.to_transformation_matrix()[:3, :3] @ np.array([0.0, 0.0, -1.0]))

    def touch_entities(self) -> list:
        return [self.rocker]

    def reset_joints(self, b: int) -> None:
        q = torch.full((b, 1), self.geom.tilt if self.init_on else -self.geom.tilt, device=self.device)
        self.art.set_qpos(q)
        self.art.set_qvel(torch.zeros_like(q))
