"""Per-episode trajectory quality, as REALM's later per-rollout columns (realm-spec.md section 6).

Joint velocity / acceleration variance, joint jerk (RMS), joint and Cartesian (TCP) path length,
Cartesian jerk, self- and environment collisions (rising edges of "any such contact"), and object
drops (a two-pad grasp that ends with the object neither in nor on the target). Derivatives are
finite differences at the control rate. Contact-based counts walk the CPU contact list once per
step; under GPU simulation they are reported as ``None``.
"""

from __future__ import annotations

import numpy as np

CONTROL_HZ = 15.0


def _entities(objs) -> set:
    out = set()
    for o in objs:
        for b in getattr(o, "_bodies", []):
            out.add(b.entity)
    return out


class TrajectoryQuality:
    def __init__(self, env, impulse_threshold: float = 1e-3):
        u = env.unwrapped
        self.u = u
        self.q: list[np.ndarray] = []
        self.tcp: list[np.ndarray] = []
        self.contacts = not u.scene.gpu_sim_enabled
        self.collisions_self = self.collisions_env = self.object_drops = 0
        self._prev_self = self._prev_env = self._prev_grasp = False
        self._baseline_self: set | None = None
        if self.contacts:
            agent = u.agent
            self.robot = _entities(agent.robot.links)
            self.gripper = _entities(agent.gripper_links)
            self.pads = [_entities([p]) for p in agent.pads]
            self.main = _entities(u.main.touch_entities()) | _entities([u.main]) if not u.main.is_articulated else _entities(u.main.touch_entities())
            self.target = _entities([u.target]) if u.target is not None else set()
            self.threshold = impulse_threshold * u.scene.px.timestep

    def update(self) -> None:
        u = self.u
        self.q.append(u.agent.arm_qpos[0].detach().cpu().numpy().astype(np.float64))
        self.tcp.append(u.agent.tcp_pose.p[0].detach().cpu().numpy().astype(np.float64))
        if not self.contacts:
            return
        self_pairs, env_hit, pad_hit = set(), False, [False, False]
        for c in u.scene.px.get_contacts():
            if not c.points:
                continue
            e0, e1 = c.bodies[0].entity, c.bodies[1].entity
            r0, r1 = e0 in self.robot, e1 in self.robot
            if not (r0 or r1):
                continue
            if np.abs(np.sum([p.impulse for p in c.points], axis=0)).sum() <= self.threshold:
                continue
            if r0 and r1:
                if not (e0 in self.gripper and e1 in self.gripper):  # gripper linkage touches by design
                    self_pairs.add(frozenset((e0, e1)))
                continue
            other = e1 if r0 else e0
            mine = e0 if r0 else e1
            if other in self.main:
                for k, pad in enumerate(self.pads):
                    pad_hit[k] |= mine in pad
            elif other not in self.target:
                env_hit = True
        if self._baseline_self is None:  # contacts present at the start are the robot's own geometry
            self._baseline_self = self_pairs
        self_hit = bool(self_pairs - self._baseline_self)
        self.collisions_self += int(self_hit and not self._prev_self)
        self.collisions_env += int(env_hit and not self._prev_env)
        self._prev_self, self._prev_env = self_hit, env_hit
        grasp = all(pad_hit) and not u.main.is_articulated
        if self._prev_grasp and not grasp and not self._placed():
            self.object_drops += 1
        self._prev_grasp = grasp

    def _placed(self) -> bool:
        u = self.u
        if u.target is None:
            return False
        return bool(u.target.holds(u.main, u.scene)[0]) or bool(u.target.supports(u.main, u.scene)[0])

    def summary(self) -> dict:
        q = np.asarray(self.q)
        p = np.asarray(self.tcp)
        out: dict = {}
        if len(q) >= 2:
            v = np.diff(q, axis=0) * CONTROL_HZ
            out["joint_vel_var"] = float(v.var(axis=0).mean())
            out["joint_path_length"] = float(np.linalg.norm(np.diff(q, axis=0), axis=1).sum())
            out["cart_path_length"] = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        if len(q) >= 3:
            a = np.diff(q, 2, axis=0) * CONTROL_HZ**2
            out["joint_acc_var"] = float(a.var(axis=0).mean())
        if len(q) >= 4:
            out["joint_jerk"] = float(np.sqrt(np.mean((np.diff(q, 3, axis=0) * CONTROL_HZ**3) ** 2)))  # RMS
            out["cart_jerk"] = float(np.linalg.norm(np.diff(p, 3, axis=0) * CONTROL_HZ**3, axis=1).mean())
        for k in ("collisions_self", "collisions_env", "object_drops"):
            out[k] = getattr(self, k) if self.contacts else None
        return out
