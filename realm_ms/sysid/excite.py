"""Identification command trajectories: 15 Hz joint targets a user can run on the real robot.

Each trajectory mixes the pieces that separate the effects (``sysid-notes.md`` §6.5): holds in
several configurations (gravity vs bias vs backlash), smooth random motion (general fit), chirps
(armature, latency, gains), slow ramps with reversals (friction, stiction, backlash). Targets stay
``margin`` inside the joint limits, under ``max_velocity`` and move at most ``max_step`` rad per
15 Hz step (DROID's IK cap is 0.2 rad).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from realm_ms.agents.urdf import DROID_RESET_QPOS

HOME = np.array(DROID_RESET_QPOS)
# workspace for random hold configurations (rad), wide enough that gravity torques change sign
CONFIG_LO = np.array([-1.2, -0.9, -1.0, -2.7, -1.2, 1.0, -1.5])
CONFIG_HI = np.array([1.2, 0.6, 1.0, -1.0, 1.2, 3.0, 1.5])


@dataclass
class ExciteConfig:
    duration_s: float = 10.0
    control_hz: float = 15.0
    max_velocity: float = 1.0  # rad/s
    max_step: float = 0.2  # rad per control step
    margin: float = 0.15  # rad from the joint limits
    amplitude: float = 0.35  # rad, random-motion / chirp amplitude

    def __post_init__(self) -> None:
        from realm_ms.validate import InputError, check_non_negative, check_positive

        self.duration_s = check_positive(self.duration_s, "duration_s (--duration)", "s")
        if self.duration_s <= 1.0:
            raise InputError(f"duration_s (--duration): must be > 1 s, got {self.duration_s:g}")
        self.control_hz = check_positive(self.control_hz, "control_hz (--control-hz)", "Hz")
        self.max_velocity = check_positive(self.max_velocity, "max_velocity (--max-velocity)", "rad/s")
        self.max_step = check_positive(self.max_step, "max_step", "rad")
        self.margin = check_non_negative(self.margin, "margin", "rad")
        self.amplitude = check_non_negative(self.amplitude, "amplitude", "rad")


def _smooth_random(rng, n, hz, amp):
    """Band-limited random motion: sum of sines 0.1-1.2 Hz with random phases."""
    t = np.arange(n) / hz
    out = np.zeros((n, 7))
    for f in rng.uniform(0.1, 1.2, size=4):
        out += rng.uniform(0.3, 1.0, size=7) * np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 2 * np.pi, size=7))
    return amp * out / 2.0


def _chirp(rng, n, hz, amp):
    t = np.arange(n) / hz
    f0, f1 = 0.3, 2.5
    phase = 2 * np.pi * (f0 * t + (f1 - f0) * t**2 / (2 * t[-1] + 1e-9))
    joints = rng.random(7) < 0.6
    joints[rng.integers(7)] = True
    return amp * 0.5 * np.sin(phase)[:, None] * joints[None] * rng.uniform(0.5, 1.0, size=7)


def _ramp_reversal(rng, n, hz, amp):
    """Slow triangle: up, back down past the start, up again (reversals at low speed)."""
    x = np.linspace(0, 1, n)
    tri = 2 * np.abs(((x * 2) % 1.0) - 0.5) - 0.5  # two slow reversal cycles
    return amp * tri[:, None] * rng.uniform(-1.0, 1.0, size=7)


def trajectory(rng: np.random.Generator, cfg: ExciteConfig, q_limits: np.ndarray) -> np.ndarray:
    """One command trajectory (T, 7) at ``cfg.control_hz``."""
    hz = cfg.control_hz
    n = int(round(cfg.duration_s * hz)) + 1
    lo = np.maximum(q_limits[:, 0] + cfg.margin, CONFIG_LO)
    hi = np.minimum(q_limits[:, 1] - cfg.margin, CONFIG_HI)
    parts = [("hold", 0.10), ("random", 0.35), ("chirp", 0.2), ("ramp", 0.2), ("hold", 0.15)]
    sizes = [max(2, int(round(f * n))) for _, f in parts]
    sizes[1] += n - sum(sizes)
    base = rng.uniform(lo, hi)
    out = []
    for (kind, _), m in zip(parts, sizes):
        if kind == "hold":
            target = rng.uniform(lo, hi) if out else base
            piece = np.repeat(target[None], m, 0)
            if out:  # move there smoothly first (cosine blend over up to 1.2 s)
                k = min(m, int(1.2 * hz))
                w = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, k))[:, None]
                piece[:k] = out[-1][-1] + w * (target - out[-1][-1])
        else:
            gen = {"random": _smooth_random, "chirp": _chirp, "ramp": _ramp_reversal}[kind]
            offs = gen(rng, m, hz, cfg.amplitude)
            start = out[-1][-1] if out else base
            piece = start + offs - offs[0]
        out.append(piece)
    q = np.concatenate(out, axis=0)[:n]
    # enforce limits, velocity and per-step caps by construction
    q = np.clip(q, lo, hi)
    step = min(cfg.max_step, cfg.max_velocity / hz)
    for i in range(1, n):
        q[i] = q[i - 1] + np.clip(q[i] - q[i - 1], -step, step)
    return np.clip(q, lo, hi)


def excite(n: int, seed: int = 0, config: ExciteConfig | None = None, q_limits: np.ndarray | None = None) -> list[np.ndarray]:
    from realm_ms.sysid.data_io import joint_limits

    cfg = config or ExciteConfig()
    q_limits = joint_limits() if q_limits is None else q_limits
    rng = np.random.default_rng(seed)
    return [trajectory(rng, cfg, q_limits) for _ in range(n)]


def write_excitation(out_dir, n: int = 10, seed: int = 0, config: ExciteConfig | None = None) -> list:
    """Write ``excite_XXX.npz`` files with ``t``, ``q_cmd`` and ``control_hz``: commands only. Run
    them on the robot (stream ``q_cmd[i]`` at ``t[i]``), log the measured ``q`` at the same or a
    higher rate, and save the result in the npz data format (``docs/sysid.md``)."""
    from pathlib import Path

    cfg = config or ExciteConfig()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, q in enumerate(excite(n, seed, cfg)):
        t = np.arange(len(q)) / cfg.control_hz
        p = out / f"excite_{i:03d}.npz"
        np.savez(p, t=t, q_cmd=q, control_hz=np.float64(cfg.control_hz))
        paths.append(p)
    return paths
