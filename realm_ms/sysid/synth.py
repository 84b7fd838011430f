"""Measured-like data with hidden effects, from the replay simulator itself.

``synth("coulomb_friction:fc=0.3", out, seed=0)`` simulates excitation trajectories (``excite.py``)
with the hidden effect(s) added to the default robot, samples the joint positions at ``rate_hz``
(``control_hz`` targets held in between), adds Gaussian sensor noise, and writes ``train/`` and
``heldout/`` npz directories plus ``truth.yaml`` (the hidden model) and ``synth.json``.
A hidden ``gripper_response`` adds a gripper channel (``gripper``, ``gripper_cmd``: ``gripper.synth_gripper``).
``engine="mujoco"`` simulates the truth with the independent MuJoCo reference instead
(``reference_mujoco.py``: same URDF and law, 1 kHz controller on a converged plant).
Each trajectory starts with 1 s of settling at its first target that is cut off.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from realm_ms.errors import InputError
from realm_ms.sysid.excite import ExciteConfig, excite
from realm_ms.agents.robot_model import RobotModel
from realm_ms.sysid.effect_spec import parse_effects
from realm_ms.sysid.gripper import synth_gripper
from realm_ms.sysid.timeseries import Trajectory


@dataclass
class SynthConfig:
    hidden: str = "none"
    seed: int = 0
    noise_rad: float = 2e-4
    rate_hz: float = 15.0
    control_hz: float = 15.0
    n_train: int = 7
    n_heldout: int = 3
    duration_s: float = 10.0
    physics_hz: float = 120.0
    gains: str = "polymetis"
    engine: str = "physx"  # "physx" (the replay simulator) or "mujoco" (the independent reference)
    excite: ExciteConfig = field(default_factory=ExciteConfig)


def hidden_model(hidden: str, cfg: SynthConfig) -> RobotModel:
    effects = parse_effects(hidden, default_values="nominal")
    return RobotModel(effects, gains=cfg.gains, joint_physics="none", physics_hz=cfg.physics_hz,
                      provenance={"hidden": hidden, "seed": cfg.seed})


def simulate_trajectories(model: RobotModel, commands: list[np.ndarray], control_hz: float, rate_hz: float,
                          evaluator=None, settle_s: float = 1.0) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Run full command trajectories (no shooting) with ``model``; return (t, q, q_cmd) per trajectory
    sampled at ``rate_hz``."""
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.simulator import SimConfig

    from realm_ms.sysid.replay import held_commands

    ev = evaluator or Evaluator(SimConfig.from_model(model), workers=1, device="cpu")
    dt = 1.0 / getattr(ev, "physics_hz", model.physics_hz)  # the MuJoCo reference runs at its law rate
    logs = []
    for c in commands:
        duration = (len(c) - 1) / control_hz
        t = np.arange(int(np.floor(duration * rate_hz + 1e-9)) + 1) / rate_hz
        q_cmd = c[np.minimum((t * control_hz + 1e-9).astype(int), len(c) - 1)]
        logs.append((t, q_cmd))
    # the truth is simulated from the *logged* command (held from t[i] to t[i+1]), exactly the
    # convention the replay uses, after ``settle_s`` of holding the first target
    steps = max(int(np.ceil((t[-1] + settle_s) / dt)) for t, _ in logs) + 1
    cmd_steps = np.stack([held_commands(np.r_[0.0, t + settle_s], np.vstack([q[:1], q]), steps, dt) for t, q in logs])
    q0 = np.stack([q[0] for _, q in logs])
    hist = ev.rollout(q0, np.zeros_like(q0), cmd_steps, model.actuation().stages)
    out = []
    for i, (t, q_cmd) in enumerate(logs):
        pos = (t + settle_s) / dt
        lo = np.clip(np.floor(pos).astype(int), 0, steps - 1)
        hi = np.clip(lo + 1, 0, steps)
        w = (pos - lo)[:, None]
        q = hist[i, lo] * (1 - w) + hist[i, hi] * w
        out.append((t, q, q_cmd))
    return out


def reference_engine(model: RobotModel):
    """The MuJoCo reference for ``model``: the independent law when no effect is hidden, else
    realm-ms's driver (the hidden effects are its actuation stages) on the MuJoCo plant."""
    try:
        from realm_ms.sysid.reference_mujoco import MujocoConfig, MujocoReference
        import mujoco  # noqa: F401
    except ImportError as e:  # pragma: no cover - depends on the install
        from realm_ms.validate import InputError

        raise InputError("engine 'mujoco' needs the mujoco package: pip install mujoco") from e
    law = "driver" if model.actuation().stages else "mujoco"
    return MujocoReference(MujocoConfig(gains=model.gains, joint_physics=model.joint_physics, law=law))


def synth(hidden: str, out_dir: str | Path, cfg: SynthConfig | None = None, evaluator=None) -> dict:
    cfg = cfg or SynthConfig()
    cfg.hidden = hidden
    model = hidden_model(hidden, cfg)
    ecfg = ExciteConfig(**{**asdict(cfg.excite), "duration_s": cfg.duration_s, "control_hz": cfg.control_hz})
    n = cfg.n_train + cfg.n_heldout
    commands = excite(n, cfg.seed, ecfg)
    if cfg.engine not in ("physx", "mujoco"):
        raise InputError(f"engine must be 'physx' or 'mujoco', got {cfg.engine!r}")
    if cfg.engine == "mujoco" and evaluator is None:
        evaluator = reference_engine(model)
    sims = simulate_trajectories(model, commands, cfg.control_hz, cfg.rate_hz, evaluator)
    rng = np.random.default_rng(cfg.seed + 1_000_003)
    out = Path(out_dir)
    from realm_ms.sysid.data_io import write_npz

    grip = model.effect("gripper_response")  # hidden in the gripper: the data gets a gripper channel
    for i, (t, q, q_cmd) in enumerate(sims):
        if not np.all(np.isfinite(q)):
            raise RuntimeError(f"hidden model {hidden!r} diverged in the simulator; lower its parameters")
        noisy = q + rng.normal(0.0, cfg.noise_rad, size=q.shape)
        split = "train" if i < cfg.n_train else "heldout"
        g, g_cmd = synth_gripper(t, rng, grip.values()) if grip is not None else (None, None)
        write_npz(out / split / f"traj_{i:03d}.npz", Trajectory(f"traj_{i:03d}", t, noisy, q_cmd, gripper=g, gripper_cmd=g_cmd,
                                                                control_hz=cfg.control_hz))
    model.save(out / "truth.yaml")
    info = {"hidden": hidden, "engine": cfg.engine, "truth": model.params(), "config": asdict(cfg)}
    (out / "synth.json").write_text(json.dumps(info, indent=2, default=float))
    return info


def simulate_droid(model: RobotModel, references: list[np.ndarray], action_space: str, control_hz: float,
                   evaluator=None, settle_s: float = 1.0) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """A synthetic DROID robot run closed loop: at each 15 Hz step a teleoperator picks the action in
    ``action_space`` that asks for the step's joint reference from the arm's state, and DROID's
    conversion turns it into the joint target the controller tracks (``closed_loop.py``, reference
    mode). Returns (t, q, actions, joint targets) per trajectory, one sample per command."""
    from realm_ms.sysid.closed_loop import NEVER, ClosedLoopCommand, bind
    from realm_ms.sysid.engine import Evaluator
    from realm_ms.sysid.replay import held_commands
    from realm_ms.sysid.simulator import SimConfig

    ev = evaluator or Evaluator(SimConfig.from_model(model), workers=1, device="cpu")
    dt = 1.0 / getattr(ev, "physics_hz", model.physics_hz)
    ts = [np.arange(len(r)) / control_hz for r in references]
    steps = max(int(np.ceil((t[-1] + 1.0 / control_hz + settle_s) / dt)) for t in ts) + 1
    k = max(len(r) for r in references)
    switch = np.full((len(references), k), NEVER, dtype=np.int64)
    refs = np.zeros((len(references), k, 7))
    for i, (t, r) in enumerate(zip(ts, references)):
        switch[i, :len(r)] = np.ceil((t + settle_s) / dt - 1e-6).astype(np.int64)
        refs[i, :len(r)] = r
    closed = ClosedLoopCommand(action_space, switch, refs, reference=True)
    # before the first command the arm settles at the first reference (held_commands pads it)
    cmd = np.stack([held_commands(np.r_[0.0, t + settle_s], np.vstack([r[:1], r]), steps, dt) for t, r in zip(ts, references)])
    q0 = np.stack([r[0] for r in references])
    sim = getattr(ev, "sim", ev)  # the simulator itself: the closed loop records what it sent
    hist = sim.rollout(q0, np.zeros_like(q0), bind(closed, cmd), model.actuation().stages, steps=cmd.shape[1])
    out = []
    for i, (t, r) in enumerate(zip(ts, references)):
        pos = (t + settle_s) / dt  # the state each command was computed from: the sample at its switch
        q = hist[i, np.ceil(pos - 1e-6).astype(int)]
        out.append((t, q, closed.sent[i, :len(r)], closed.targets[i, :len(r)]))
    return out


def synth_droid(hidden: str, out_dir: str | Path, cfg: SynthConfig | None = None, action_space: str = "cartesian_position",
                formats: tuple[str, ...] = ("npz",), log_joint_target: bool = False, evaluator=None) -> dict:
    """DROID-format episodes of a robot with ``hidden`` effects, commanded in ``action_space``
    (``simulate_droid``), written in every format of ``formats`` (``droid_formats.FORMATS``) under
    ``OUT/<format>/{train,heldout}/``, plus ``truth.yaml`` and ``synth.json``. ``log_joint_target``
    also logs the joint target DROID sent (as DROID's own logs do); without it readers rebuild it."""
    from realm_ms.agents.droid_action_spaces import check_action_space
    from realm_ms.sysid.droid_formats import FORMATS, DroidLog, write_lerobot, write_log

    cfg = cfg or SynthConfig()
    cfg.hidden = hidden
    check_action_space(action_space, None)
    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise InputError(f"unknown format(s) {unknown}; known: {', '.join(FORMATS)}")
    model = hidden_model(hidden, cfg)
    ecfg = ExciteConfig(**{**asdict(cfg.excite), "duration_s": cfg.duration_s, "control_hz": cfg.control_hz})
    refs = excite(cfg.n_train + cfg.n_heldout, cfg.seed, ecfg)
    if cfg.engine == "mujoco" and evaluator is None:
        evaluator = reference_engine(model)
    sims = simulate_droid(model, refs, action_space, cfg.control_hz, evaluator)
    rng = np.random.default_rng(cfg.seed + 1_000_003)
    logs = {"train": [], "heldout": []}
    for i, (t, q, actions, targets) in enumerate(sims):
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(targets))):
            raise RuntimeError(f"hidden model {hidden!r} diverged in the simulator; lower its parameters")
        # float32 values (LeRobot's storage), so that every format holds the same numbers
        f32 = lambda a: np.asarray(a, dtype=np.float32).astype(np.float64)  # noqa: E731
        commands = {action_space: f32(actions)} | ({"joint_position": f32(targets)} if log_joint_target else {})
        noisy = f32(q + rng.normal(0.0, cfg.noise_rad, size=q.shape))
        logs["train" if i < cfg.n_train else "heldout"].append(
            DroidLog(f"ep_{i:03d}", t, noisy, commands, np.zeros(len(t)), {"position": np.zeros(len(t))}))
    out = Path(out_dir)
    for fmt in formats:
        for split, group in logs.items():
            if fmt == "lerobot":
                write_lerobot(out / fmt / split, group, cfg.control_hz)
            else:
                for log in group:
                    write_log(out / fmt / split, log, fmt)
    model.save(out / "truth.yaml")
    info = {"hidden": hidden, "engine": cfg.engine, "action_space": action_space, "formats": list(formats),
            "joint_target_logged": log_joint_target, "truth": model.params(), "config": asdict(cfg)}
    (out / "synth.json").write_text(json.dumps(info, indent=2, default=float))
    return info
