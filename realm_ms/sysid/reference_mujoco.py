"""An independent reference plant: the ``panda_droid`` arm in MuJoCo with the Polymetis law at 1 kHz.

The replay simulator and the benchmark run the arm in PhysX at 120 Hz. To check that plant against
something it did not make, this module simulates the *same* locked-gripper URDF
(``locked_urdf.py``: gripper welded, arm joints only, inertials verbatim) in MuJoCo, with the
Polymetis ``HybridJointImpedanceControl`` law evaluated at ``law_hz`` (1 kHz, as Polymetis/libfranka)
and held (zero-order hold) over ``substeps`` plant integration steps, i.e. a converged continuous
plant under a 1 kHz digital controller, as on the real robot.

Two ways to compute the law:

- ``law="mujoco"`` (default): from MuJoCo's own model only (``mj_jac`` at the flange, ``qfrc_bias``
  for Coriolis + gravity), nothing from realm-ms's ``ArmModel`` or ``DroidArmDriver``: the
  independent cross-check. Joint friction/armature presets are applied as MuJoCo armature and an
  explicit smooth Coulomb torque per plant step.
- ``law="driver"``: realm-ms's ``DroidArmDriver`` (same law, purely explicit) with actuation stages,
  so hidden effects (``synth --engine mujoco --hidden ...``) act exactly as they are defined;
  build-time effects (armature, payload) change the MuJoCo model (``MujocoBuildTarget``).

``MujocoReference.rollout`` has the replay simulator's signature (targets given per law tick), so
``synth`` can use it in place of the PhysX ``Evaluator``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

URDF_COMPILER = '<mujoco><compiler fusestatic="false" discardvisual="true" balanceinertia="false"/></mujoco>'


@dataclass
class MujocoConfig:
    law_hz: float = 1000.0  # controller rate (Polymetis / libfranka: 1 kHz)
    substeps: int = 4  # plant integration steps per law tick (semi-implicit Euler)
    gains: object = "polymetis"  # preset name or ImpedanceGains
    joint_physics: object = "none"  # preset name or JointPhysics (armature + smooth Coulomb, in N.m)
    law: str = "mujoco"  # "mujoco" (independent) or "driver" (realm's DroidArmDriver + effect stages)
    gravity: bool = True  # plant gravity (the law compensates it with the model)
    coriolis_feedforward: bool = True
    free_joints: tuple[int, ...] | None = None  # None: all 7; else the others are locked (analytic tests)

    def __post_init__(self):
        if self.law not in ("mujoco", "driver"):
            raise ValueError(f"law must be 'mujoco' or 'driver', got {self.law!r}")
        if self.substeps < 1 or self.law_hz <= 0:
            raise ValueError("substeps must be >= 1 and law_hz > 0")


def inverse_dynamics(model, q, qd, qdd):
    """MuJoCo's joint torques for (q, qd, qdd) on ``model`` (``mj_inverse``): the oracle the effects'
    inverse-dynamics terms are checked against."""
    import mujoco

    d = mujoco.MjData(model)
    d.qpos[:], d.qvel[:], d.qacc[:] = q, qd, qdd
    mujoco.mj_inverse(model, d)
    return d.qfrc_inverse.copy()


def build_model(config: MujocoConfig | None = None, urdf: str | None = None):
    """MjModel of the locked arm (7 hinge joints, no geometry, no joint damping or friction)."""
    import mujoco

    from realm_ms.sysid.locked_urdf import locked_arm_urdf_path

    config = config or MujocoConfig()
    text = open(urdf or locked_arm_urdf_path()).read()
    text = text.replace("</robot>", URDF_COMPILER + "</robot>", 1)
    spec = mujoco.MjSpec.from_string(text)
    if config.free_joints is not None:
        for k, j in enumerate(list(spec.joints)):
            if k not in config.free_joints:
                spec.delete(j)
    m = spec.compile()
    m.opt.timestep = 1.0 / (config.law_hz * config.substeps)
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    if not config.gravity:
        m.opt.gravity[:] = 0.0
    # URDF <dynamics damping/friction> are not part of the realm-ms plant (its joints carry only the
    # controller's torques): remove them so both engines simulate the same rigid body
    m.dof_damping[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    m.jnt_limited[:] = 0
    return m


class MujocoBuildTarget:
    """Build-time effects (armature, payload, link_mass) on one MuJoCo model; same interface as
    ``BuildTarget`` (inertial changes apply on top of the body's current inertial, ``reset`` first)."""

    def __init__(self, model, flange_offset: np.ndarray):
        import mujoco

        self.m = model
        self.flange_offset = np.asarray(flange_offset, dtype=float)
        self.body = model.nbody - 1  # panda_link7 (+ flange and welded gripper)
        self._bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"panda_link{k + 1}") for k in range(7)]
        self._armature = model.dof_armature.copy()
        self._inertials = {b: self._get(b) for b in self._bodies}

    def _get(self, b: int):
        import mujoco

        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, self.m.body_iquat[b])
        rot = rot.reshape(3, 3)
        return float(self.m.body_mass[b]), self.m.body_ipos[b].copy(), rot @ np.diag(self.m.body_inertia[b]) @ rot.T

    def _set(self, b: int, mass: float, com: np.ndarray, inertia: np.ndarray) -> None:
        import mujoco

        w, v = np.linalg.eigh(np.asarray(inertia, dtype=float))
        if np.linalg.det(v) < 0:
            v[:, 0] = -v[:, 0]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, v.reshape(-1))
        self.m.body_mass[b], self.m.body_ipos[b] = mass, com
        self.m.body_iquat[b], self.m.body_inertia[b] = quat, np.maximum(w, 1e-10)

    def reset(self) -> None:
        self.m.dof_armature[:] = self._armature
        for b, v in self._inertials.items():
            self._set(b, *v)

    def add_armature(self, values: np.ndarray) -> None:
        self.m.dof_armature[:] = self._armature + np.asarray(values, dtype=float)[: self.m.nv]

    def add_point_mass(self, mass: float, offset_in_flange: np.ndarray) -> None:
        self.add_body(mass, offset_in_flange, np.zeros((3, 3)))

    def add_body(self, mass: float, offset_in_flange: np.ndarray, inertia: np.ndarray) -> None:
        from realm_ms.agents.arm_model import _Inertial

        if mass <= 0:
            return
        body = _Inertial(*self._get(self.body))
        part = _Inertial(float(mass), self.flange_offset + np.asarray(offset_in_flange, dtype=float), np.asarray(inertia, dtype=float))
        merged = _Inertial.merge([body, part])
        self._set(self.body, merged.mass, merged.com, merged.inertia)

    def map_link_inertial(self, body: int, fn) -> None:
        b = self._bodies[body]
        self._set(b, *fn(*self._get(b)))


class MujocoReference:
    """E independent MuJoCo arms; ``rollout`` has the replay simulator's signature."""

    def __init__(self, config: MujocoConfig | None = None):
        from realm_ms.agents.control import GAIN_PRESETS, JOINT_PHYSICS_PRESETS, resolve
        from realm_ms.sysid.locked_urdf import flange_offset_in_link7

        self.config = config or MujocoConfig()
        self.gains = resolve(self.config.gains, GAIN_PRESETS, "gain")
        self.joint_physics = resolve(self.config.joint_physics, JOINT_PHYSICS_PRESETS, "joint physics")
        self.flange_offset = flange_offset_in_link7()
        self.dt = 1.0 / self.config.law_hz  # one rollout step = one law tick
        self.physics_hz = self.config.law_hz
        self._template = build_model(self.config)
        self.nv = self._template.nv
        self.joints = list(range(7)) if self.config.free_joints is None else sorted(self.config.free_joints)
        self._models: list = []

    # ------------------------------------------------------------------ models
    def _model(self, i: int):
        import copy

        while len(self._models) <= i:
            m = copy.deepcopy(self._template)
            m.dof_armature[:] = np.asarray(self.joint_physics.armature, dtype=float)[self.joints]
            self._models.append((m, MujocoBuildTarget(m, self.flange_offset)))
        return self._models[i]

    # ------------------------------------------------------------------ the independent law
    def _law(self, m, d, q_target: np.ndarray, jacp: np.ndarray, jacr: np.ndarray) -> np.ndarray:
        """Polymetis HybridJointImpedanceControl from MuJoCo's model (after ``mj_step1``)."""
        import mujoco

        g, j = self.gains, self.joints
        kq, kqd = np.asarray(g.kq, float)[j], np.asarray(g.kqd, float)[j]
        kx, kxd = np.asarray(g.kx, float), np.asarray(g.kxd, float)
        b = m.nbody - 1
        point = d.xpos[b] + d.xmat[b].reshape(3, 3) @ self.flange_offset
        mujoco.mj_jac(m, d, jacp, jacr, point, b)
        jac = np.vstack([jacp, jacr])
        kp = np.diag(kq) + jac.T @ (kx[:, None] * jac)
        kd = np.diag(kqd) + jac.T @ (kxd[:, None] * jac)
        q, qd = d.qpos.copy(), d.qvel.copy()
        tau = kp @ (q_target - q) - kd @ qd
        if self.config.coriolis_feedforward:
            tau += d.qfrc_bias  # C(q, qd) qd + g(q): MuJoCo's RNEA with zero acceleration
        elif self.config.gravity:
            d2 = mujoco.MjData(m)
            d2.qpos[:] = q
            mujoco.mj_forward(m, d2)
            tau += d2.qfrc_bias
        lim = np.asarray((87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0))[j]
        return np.clip(tau, -lim, lim)

    def _friction(self, qd: np.ndarray) -> np.ndarray:
        f = np.asarray(self.joint_physics.friction, dtype=float)[self.joints]
        return -f * np.tanh(qd / self.joint_physics.friction_velocity)

    # ------------------------------------------------------------------ rollout
    def rollout(self, q0: np.ndarray, qd0: np.ndarray, cmd, effects: list | None = None,
                record_every: int = 1, steps: int | None = None) -> np.ndarray:
        """Simulate E arms from (q0, qd0) tracking ``cmd`` (E, S, 7), one target per law tick.

        ``effects`` (``law="driver"`` only): actuation stages with theta of E rows or 1.
        ``cmd`` may instead be a function ``cmd(k, q) -> (E, 7)`` of the tick and the arms' joints,
        with ``steps`` = S (a closed-loop command; the replay simulator's convention).
        Returns joint positions (E, S + 1, 7) after 0..S ticks (float64).
        """
        import mujoco

        effects = list(effects or [])
        if effects and self.config.law != "driver":
            raise ValueError("hidden effects need MujocoConfig(law='driver') (they are realm-ms actuation stages)")
        closed_loop = callable(cmd)
        if closed_loop and steps is None:
            raise ValueError("a closed-loop command needs steps=")
        e_count, steps = (q0.shape[0], steps) if closed_loop else (cmd.shape[0], cmd.shape[1])
        j = self.joints
        datas = []
        for i in range(e_count):
            m, target = self._model(i)
            target.reset()
            for fx in effects:
                if fx.build_time:
                    fx.build_target(target, min(i, fx.theta.shape[0] - 1))
            d = mujoco.MjData(m)
            d.qpos[:], d.qvel[:] = np.asarray(q0[i], float)[j], np.asarray(qd0[i], float)[j]
            datas.append((m, d))
        out = np.empty((e_count, steps + 1, 7), dtype=np.float64)
        out[:] = np.asarray(q0, dtype=np.float64)[:, None]
        driver = self._driver(e_count, effects, q0) if self.config.law == "driver" else None
        jacp, jacr = np.zeros((3, self.nv)), np.zeros((3, self.nv))
        sub = self.config.substeps
        friction_in_driver = driver is not None
        for k in range(steps):
            target = np.asarray(cmd(k, out[:, k]), dtype=np.float64) if closed_loop else cmd[:, k]
            if driver is not None:
                tau_all = self._driver_torque(driver, datas, target)
            for i, (m, d) in enumerate(datas):
                mujoco.mj_step1(m, d)
                tau = tau_all[i] if driver is not None else self._law(m, d, np.asarray(target[i], float)[j], jacp, jacr)
                for s in range(sub):
                    if s:
                        mujoco.mj_step1(m, d)
                    d.qfrc_applied[:] = tau if friction_in_driver else tau + self._friction(d.qvel)
                    mujoco.mj_step2(m, d)
                out[i, k + 1, j] = d.qpos
            if not np.all(np.isfinite(out[:, k + 1])):
                bad = ~np.isfinite(out[:, k + 1]).all(axis=1)
                out[bad, k + 1:] = np.nan
                if bad.all():
                    break
        return out

    # ------------------------------------------------------------------ realm's driver as the law
    def _driver(self, e_count: int, effects: list, q0: np.ndarray):
        import torch

        from realm_ms.agents.actuation import ActuationModel
        from realm_ms.agents.arm_model import ArmModel
        from realm_ms.agents.control import DroidArmDriver, DroidControlConfig
        from realm_ms.sysid.locked_urdf import BASE_LINK, TIP_LINK, source_urdf_path

        if self.config.free_joints is not None:
            raise ValueError("law='driver' needs all 7 joints free")
        cfg = DroidControlConfig(gains=self.gains, coriolis_feedforward=self.config.coriolis_feedforward,
                                 gravity_compensation=self.config.gravity, integrator="explicit",
                                 joint_physics=self.joint_physics)
        model = ArmModel.from_urdf(source_urdf_path()[0], BASE_LINK, TIP_LINK)
        act = ActuationModel(sorted(effects, key=lambda fx: fx.order))
        driver = DroidArmDriver(model, cfg, e_count, "cpu", act)
        driver.reset(torch.as_tensor(np.asarray(q0), dtype=torch.float32))
        return driver

    def _driver_torque(self, driver, datas, targets: np.ndarray) -> np.ndarray:
        import torch

        q = torch.as_tensor(np.stack([d.qpos for _, d in datas]), dtype=torch.float32)
        qd = torch.as_tensor(np.stack([d.qvel for _, d in datas]), dtype=torch.float32)
        with torch.inference_mode():
            driver.set_target(torch.as_tensor(np.asarray(targets), dtype=torch.float32))
            return driver.torque(q, qd, self.dt).double().numpy()
