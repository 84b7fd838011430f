"""MuJoCo reference plants with effects written in MuJoCo's own terms, not realm-ms's effect models.

``reference_mujoco.py`` with ``law="driver"`` runs realm-ms's *own* effect stages inside MuJoCo: its
friction is our smooth law, its payload sits where ours does. Here every effect is MuJoCo-native:

| field | MuJoCo | what it is |
|---|---|---|
| ``frictionloss`` | ``dof_frictionloss`` | dry friction as a constraint (exact stiction, not a smooth law) |
| ``damping`` | ``dof_damping`` | viscous joint damping (implicit in the integrator) |
| ``armature`` | ``dof_armature`` | rotor inertia |
| ``stiffness`` | ``jnt_stiffness`` + ``qpos_spring`` | joint springs to the trajectory's start pose (no library effect) |
| ``payload_mass``, ``payload_com`` | a child body of ``panda_link7`` | payload with its own centre of mass (flange frame) and inertia |
| ``link_scale`` | ``body_mass``, ``body_inertia`` | link k's mass and inertia x (1 + s) (library: ``link_mass`` s_k) |
| ``link_dcx/y/z`` | ``body_ipos`` | link k's centre of mass shifted (m, link frame; library: ``link_mass`` with ``fit_com``) |
| ``gaz`` | ``qfrc_applied`` | Gaz et al. 2019's identified Panda friction (sigmoid law, ``GAZ_PHI``) x ``gaz`` |
| ``lugre_*`` | ``qfrc_applied`` | LuGre friction: a bristle state z per joint, integrated at the plant rate |

The last two are friction laws written independently of realm-ms's effect models
(``reference_friction.py``), applied as a torque each plant substep from the substep's velocity.

The controller is the independent Polymetis law of ``MujocoReference`` (from MuJoCo's own model,
1 kHz, 4 plant substeps), evaluated on the *nominal* MuJoCo model at the plant's state: like the
real controller it does not know the payload or a link's true mass. ``rollout_torque`` also returns the joint-torque sensor output: the
motor torque the law applied during each tick (what a Franka's τ_J would read minus the
friction the sensor sits behind, i.e. the torque that drives the rigid body and the joint
effects).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from realm_ms.errors import InputError
from realm_ms.sysid.reference_friction import PlantFriction
from realm_ms.sysid.reference_mujoco import URDF_COMPILER, MujocoConfig, MujocoReference


@dataclass
class NativeEffects:
    frictionloss: tuple[float, ...] = (0.0,) * 7  # N·m
    damping: tuple[float, ...] = (0.0,) * 7  # N·m·s/rad
    armature: tuple[float, ...] = (0.0,) * 7  # kg·m²
    stiffness: tuple[float, ...] = (0.0,) * 7  # N·m/rad, spring to the start pose
    payload_mass: float = 0.0  # kg
    payload_com: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m, flange frame
    payload_inertia: float = 0.0  # kg·m², about its CoM (diagonal)
    link_scale: tuple[float, ...] = (0.0,) * 7  # relative mass/inertia change of links 1..7
    link_dcx: tuple[float, ...] = (0.0,) * 7  # m, CoM shift of links 1..7 along their x axis
    link_dcy: tuple[float, ...] = (0.0,) * 7
    link_dcz: tuple[float, ...] = (0.0,) * 7
    gaz: float = 0.0  # scale of Gaz et al.'s identified sigmoid friction (1: the paper's values)
    lugre_fc: tuple[float, ...] = (0.0,) * 7  # N·m, LuGre Coulomb level (0: no LuGre on that joint)
    lugre_fs_ratio: float = 1.5  # breakaway level / Coulomb level
    lugre_vs: float = 0.05  # rad/s, Stribeck velocity
    lugre_sigma0: float = 1000.0  # N·m/rad, bristle stiffness
    lugre_sigma1: float = 1.0  # N·m·s/rad, bristle damping
    lugre_sigma2: tuple[float, ...] = (0.0,) * 7  # N·m·s/rad, viscous part of LuGre

    @classmethod
    def parse(cls, text: str) -> "NativeEffects":
        """``key=value`` items separated by commas; a per-joint key takes one value (all joints) or
        ``key4=value`` (joint 4); ``payload_com_x/y/z``. ``none`` or empty: no effect."""
        out = cls()
        if text.strip().lower() in ("", "none"):
            return out
        names = {f.name for f in fields(cls)}
        for item in [s.strip() for s in text.split(",") if s.strip()]:
            if "=" not in item:
                raise InputError(f"{item!r}: expected key=value (keys: {', '.join(sorted(names))})")
            k, v = (x.strip() for x in item.split("=", 1))
            try:
                x = float(v)
            except ValueError:
                raise InputError(f"{k}={v!r}: expected a number") from None
            if k.startswith("payload_com_") and k[-1] in "xyz":
                com = list(out.payload_com)
                com["xyz".index(k[-1])] = x
                out.payload_com = tuple(com)
            elif k in names and k not in ("payload_com",):
                cur = getattr(out, k)
                setattr(out, k, tuple([x] * 7) if isinstance(cur, tuple) else x)
            elif k[:-1] in names and k[-1].isdigit() and 1 <= int(k[-1]) <= 7:
                cur = list(getattr(out, k[:-1]))
                cur[int(k[-1]) - 1] = x
                setattr(out, k[:-1], tuple(cur))
            else:
                raise InputError(f"unknown native effect key {k!r}; known: {', '.join(sorted(names))}, payload_com_x/y/z, "
                                 "per-joint keys with a joint number 1-7")
        return out


#: the variants of the sweep (docs/sysid.md, "MuJoCo-native reference")
VARIANTS = {
    "none": "",
    "frictionloss": "frictionloss=0.3",
    "damping": "damping=0.5",
    "armature": "armature=0.2",
    "payload_com": "payload_mass=0.8,payload_com_x=0.12,payload_com_z=0.05,payload_inertia=0.002",
    "link4_mass": "link_scale4=0.3",
    "link4_inertial": "link_scale4=0.3,link_dcx4=0.04,link_dcy4=-0.03",
    "springs": "stiffness=2.0",
    "frictionloss+payload_com": "frictionloss=0.3,payload_mass=0.8,payload_com_x=0.12,payload_com_z=0.05",
    "gaz": "gaz=1",
    "lugre": "lugre_fc=0.3,lugre_fc4=0.5,lugre_fc7=0.2,lugre_sigma2=0.2",
}


def build_native_model(fx: NativeEffects, config: MujocoConfig):
    import mujoco

    from realm_ms.sysid.locked_urdf import flange_offset_in_link7, locked_arm_urdf_path

    text = open(locked_arm_urdf_path()).read().replace("</robot>", URDF_COMPILER + "</robot>", 1)
    spec = mujoco.MjSpec.from_string(text)
    if fx.payload_mass > 0:
        link7 = spec.body("panda_link7")
        pos = flange_offset_in_link7() + np.asarray(fx.payload_com, dtype=float)
        i = max(fx.payload_inertia, 1e-9)
        # ipos explicitly at the body origin: left out, MjSpec copies ``pos`` into it (CoM twice as far)
        link7.add_body(name="payload", pos=list(pos), ipos=[0.0, 0.0, 0.0], mass=float(fx.payload_mass),
                       inertia=[i, i, i], explicitinertial=True)
    m = spec.compile()
    m.opt.timestep = 1.0 / (config.law_hz * config.substeps)
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    m.jnt_limited[:] = 0
    m.dof_frictionloss[:] = fx.frictionloss
    m.dof_damping[:] = fx.damping
    m.dof_armature[:] = fx.armature
    m.jnt_stiffness[:] = fx.stiffness
    for k, s in enumerate(fx.link_scale):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"panda_link{k + 1}")
        m.body_mass[b] *= 1 + s
        m.body_inertia[b] *= 1 + s
        m.body_ipos[b] += (fx.link_dcx[k], fx.link_dcy[k], fx.link_dcz[k])
    return m


class NativeReference(MujocoReference):
    """The independent law on a MuJoCo-native plant; ``rollout_torque`` adds the torque sensor."""

    def __init__(self, effects: NativeEffects | None = None, config: MujocoConfig | None = None):
        super().__init__(config or MujocoConfig())
        self.native = effects or NativeEffects()
        self._native_model = build_native_model(self.native, self.config)
        # the controller believes the nominal robot: its Jacobian and C q̇ + g come from the nominal
        # model at the plant's state (a payload or heavier link is *not* compensated)
        import mujoco

        self._nominal = build_native_model(NativeEffects(), self.config)
        self._nominal_data = mujoco.MjData(self._nominal)

    def _law(self, m, d, q_target, jacp, jacr):
        import mujoco

        nd = self._nominal_data
        nd.qpos[:], nd.qvel[:] = d.qpos, d.qvel
        mujoco.mj_forward(self._nominal, nd)
        return super()._law(self._nominal, nd, q_target, jacp, jacr)

    def _model(self, i: int):
        import copy

        from realm_ms.sysid.reference_mujoco import MujocoBuildTarget

        while len(self._models) <= i:
            m = copy.deepcopy(self._native_model)
            self._models.append((m, MujocoBuildTarget(m, self.flange_offset)))
        return self._models[i]

    def rollout_torque(self, q0: np.ndarray, cmd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One arm from rest at ``q0`` tracking ``cmd`` (S, 7), one target per law tick.

        Returns (q, qd, tau), each (S + 1, 7): the state at every tick and the motor torque applied
        from that tick on (the last row repeats the previous torque)."""
        import mujoco

        m, _ = self._model(0)
        d = mujoco.MjData(m)
        d.qpos[:] = q0
        m.qpos_spring[:] = q0  # springs pull to the start pose
        steps = cmd.shape[0]
        law = PlantFriction.of(self.native, m.opt.timestep)
        q, qd, tau = (np.empty((steps + 1, 7)) for _ in range(3))
        q[0], qd[0] = d.qpos, d.qvel
        jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        for k in range(steps):
            mujoco.mj_step1(m, d)
            u = self._law(m, d, np.asarray(cmd[k], float), jacp, jacr)
            tau[k] = u
            for s in range(self.config.substeps):
                if s:
                    mujoco.mj_step1(m, d)
                d.qfrc_applied[:] = u if law is None else u - law.step(np.asarray(d.qvel))
                mujoco.mj_step2(m, d)
            q[k + 1], qd[k + 1] = d.qpos, d.qvel
        tau[-1] = tau[-2]
        return q, qd, tau


def synth_native(effects: str, out, seed: int = 0, n_train: int = 7, n_heldout: int = 3, duration_s: float = 10.0,
                 rate_hz: float = 1000.0, noise_rad: float = 1e-4, noise_nm: float = 0.02, control_hz: float = 15.0,
                 with_cmd: bool = True, noise_qd: float = 1e-3) -> dict:
    """Write ``train/`` + ``heldout/`` npz trajectories (t, q, tau, qd and, if ``with_cmd``, q_cmd)
    from the native plant; ``effects``: a ``NativeEffects.parse`` spec or a ``VARIANTS`` name.
    Noise: Gaussian, ``noise_rad`` on q, ``noise_qd`` [rad/s] on the measured velocity (a robot's
    filtered estimate), ``noise_nm`` on the torque sensor."""
    import json
    from pathlib import Path

    from realm_ms.sysid.data_io import write_npz
    from realm_ms.sysid.excite import ExciteConfig, excite
    from realm_ms.sysid.timeseries import Trajectory

    spec = VARIANTS.get(effects, effects)
    fx = NativeEffects.parse(spec)
    ref = NativeReference(fx)
    n = n_train + n_heldout
    cmds = excite(n, seed=seed, config=ExciteConfig(duration_s=duration_s, control_hz=control_hz))
    rng = np.random.default_rng(seed + 1000)
    law_hz = ref.config.law_hz
    out = Path(out)
    for i, c in enumerate(cmds):
        ticks = int(round((len(c) - 1) / control_hz * law_hz))
        # command j takes over at the tick nearest j / control_hz, the tick its log sample falls on:
        # a switch one tick after the sample would log the previous command held for a whole period
        switch = np.round(np.arange(len(c)) * law_hz / control_hz).astype(int)
        k = np.searchsorted(switch, np.arange(ticks), side="right") - 1
        q, qd, tau = ref.rollout_torque(c[0], c[k])
        t = np.arange(ticks + 1) / law_hz
        q_cmd = c[np.minimum(k.tolist() + [k[-1]], len(c) - 1)]
        # samples at the ticks nearest to k / rate_hz: jitter <= half a tick, no drift off the command grid
        sl = np.unique(np.round(np.arange(0, t[-1] + 1e-9, 1.0 / rate_hz) * law_hz).astype(int))
        split = "train" if i < n_train else "heldout"
        write_npz(out / split / f"traj_{i:03d}.npz", Trajectory(
            f"traj_{i:03d}", t[sl], q[sl] + rng.normal(0, noise_rad, q[sl].shape),
            q_cmd[sl] if with_cmd else None, qd[sl] + rng.normal(0, noise_qd, qd[sl].shape),
            tau[sl] + rng.normal(0, noise_nm, tau[sl].shape), control_hz=control_hz if with_cmd else None))
    info = {"engine": "mujoco-native", "effects": spec, "native": {f.name: getattr(fx, f.name) for f in fields(fx)},
            "seed": seed, "rate_hz": rate_hz, "noise_rad": noise_rad, "noise_nm": noise_nm, "with_cmd": with_cmd}
    (out / "synth.json").write_text(json.dumps(info, indent=2))
    return info
