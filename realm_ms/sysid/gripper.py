"""The gripper channel: the measured gripper against the simulated gripper's answer, and the
``gripper_response`` effect fitted from it.

The arm replay locks the gripper (``locked_urdf.py``), so the gripper is judged on its own, 1-D, at
the log's rate:

- **strokes** (:func:`strokes`): runs of samples in which the measured position (0 open .. 1 closed)
  moves by more than ``MOVING`` units/s in one direction and by ``STROKE_MIN`` in all; each has a speed
  (median over its samples, units/s), a duration and where it stops (a grasp stops a closing stroke short).
- **the simulated answer** (:func:`simulate`): the gripper controller's own law
  (``agents/effects/gripper_response.GripperLaw``) run at the physics rate on the request, sampled at
  the log's times. The simulated drive tracks that target within a physics step
  (``tests/sysid/test_gripper_channel.py`` checks it against the env), so the law is the simulated
  gripper without a scene.
- **with the request** (``gripper_cmd``): every measured stroke's window is simulated under a grid of
  (delay, speed) and the pair with the smallest error wins; the simulated answer is clamped to the
  window's measured range (an object stops real fingers; the law has no object).
- **without it** (the public DROID exports): only the stroke speed is seen, against the simulated
  answer to a step request over the same stroke; the delay from request to motion cannot be seen.

:func:`check_gripper` returns a :class:`GripperCheck` (``to_json``, ``line``): the ``gripper`` row of
``realm sysid compare`` and ``realm sysid align``, and the effect ``realm sysid auto`` adds to its model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import torch

from realm_ms.agents.effects.gripper_response import GripperLaw, GripperResponse
from realm_ms.agents.robotiq_2f85 import DRIVER_CLOSED, GRIPPER_MAX_SPEED

#: the simulated gripper's stroke speed, units of the 0..1 stroke per second (full stroke in 0.6 s)
SIM_SPEED = GRIPPER_MAX_SPEED / DRIVER_CLOSED
#: slower samples are at rest (sensor noise, creep under grip), units/s
MOVING = 0.15
#: smallest stroke counted, units
STROKE_MIN = 0.1
#: the simulated gripper matches when its speed is within this fraction of the measured one and the
#: fitted delay within half a 15 Hz period
SPEED_TOL, DELAY_TOL_S = 0.1, 0.034
PHYSICS_HZ = 120.0
_SPEC = {s.name: s for s in GripperResponse.param_specs(None)}


@dataclass
class Stroke:
    name: str
    direction: str  # "close" | "open"
    start: int  # index of the sample the stroke leaves from
    steps: int  # samples it moves over
    begin: float  # position, 0 open .. 1 closed
    end: float
    speed: float  # median |velocity| over the stroke, units/s
    peak: float  # largest |velocity|, units/s
    duration: float  # s


def strokes(g: np.ndarray, t: np.ndarray, name: str = "") -> list[Stroke]:
    """The strokes of one measured gripper trace (see the module doc)."""
    g, t = np.asarray(g, float), np.asarray(t, float)
    v = np.diff(g) / np.diff(t)
    moving = np.abs(v) > MOVING
    out, i = [], 0
    while i < len(v):
        if not moving[i]:
            i += 1
            continue
        sign, j = np.sign(v[i]), i
        while j < len(v) and moving[j] and np.sign(v[j]) == sign:
            j += 1
        if abs(g[j] - g[i]) >= STROKE_MIN:
            s = np.abs(v[i:j])
            out.append(Stroke(name, "close" if sign > 0 else "open", i, j - i, float(g[i]), float(g[j]),
                              float(np.median(s)), float(s.max()), float(t[j] - t[i])))
        i = j
    return out


def simulate(cmd: np.ndarray, t: np.ndarray, g0: np.ndarray, delay=0.0, speed=1.0, tau=0.0,
             target0: np.ndarray | None = None) -> np.ndarray:
    """The simulated gripper's positions (B, T) answering requests ``cmd`` (B, T) held from ``t[i]`` to
    ``t[i+1]``, measured at ``g0`` (B,) with its drive target at ``target0`` (default: at rest on the
    request ``cmd[:, 0]``, reached or held by an object); ``delay``, ``speed``, ``tau``: numbers or (B,)
    arrays (one candidate per row)."""
    cmd = torch.as_tensor(np.atleast_2d(cmd), dtype=torch.float64)
    b = cmd.shape[0]

    def col(x):
        x = torch.as_tensor(np.broadcast_to(np.asarray(x, float), (b,)).copy(), dtype=torch.float64)
        return x[:, None]

    law = GripperLaw(col(delay), col(speed), col(tau))
    law.reset(cmd[:, :1] if target0 is None else torch.as_tensor(np.asarray(target0, float).reshape(b, 1)))
    out = torch.empty_like(cmd)
    out[:, 0] = torch.as_tensor(np.asarray(g0, float).reshape(b))
    dts = np.diff(np.asarray(t, float))
    for i, dt_log in enumerate(dts):
        n = max(1, int(round(dt_log * PHYSICS_HZ)))
        for _ in range(n):
            y = law.step(cmd[:, i:i + 1], dt_log / n, SIM_SPEED)
        out[:, i + 1] = y[:, 0]
    return out.numpy()


def synth_gripper(t: np.ndarray, rng: np.random.Generator, values: dict, noise: float = 0.002
                  ) -> tuple[np.ndarray, np.ndarray]:
    """A gripper channel for synthetic data (``realm sysid synth``): full open/close requests, each
    held 1.5-3 s, answered by the simulated gripper under ``gripper_response`` ``values``; (measured,
    request). Full strokes only: a stop short of closed would read as a grasp (``interaction.py``)."""
    cmd, state, i = np.zeros(len(t)), 0.0, 0
    rate = (len(t) - 1) / max(float(t[-1] - t[0]), 1e-9)
    while i < len(t):
        n = int(rng.uniform(1.5, 3.0) * rate)
        cmd[i:i + n] = state
        state, i = 1.0 - state, i + n
    g = simulate(cmd[None], t, cmd[:1], values.get("delay", 0.0), values.get("speed", 1.0), values.get("tau", 0.0))[0]
    return np.clip(g + rng.normal(0.0, noise, len(t)), 0.0, 1.0), cmd


@dataclass
class GripperCheck:
    """The gripper row: measured strokes against the simulated gripper's answer, and the fitted effect."""

    strokes: int  # measured strokes counted
    closing: int
    speed_real: float | None  # median stroke speed, units/s (None: no strokes)
    speed_sim: float  # the same over the simulated answer, units/s
    speed: float  # the factor on the checked model's stroke speed that matches the measured strokes
    delay: float | None  # s to add to the checked model's request delay (< 0: earlier); None without the request
    with_command: bool
    rmse_before: float | None = None  # over the stroke windows, units; with the request only
    rmse_after: float | None = None
    grasp_stops: list[float] = field(default_factory=list)  # where closing strokes stopped short of 0.95
    model_values: dict | None = None  # the checked model's gripper_response values (None: the nominal gripper)

    @property
    def matches(self) -> bool:
        return abs(self.speed - 1.0) <= SPEED_TOL and (self.delay is None or abs(self.delay) <= DELAY_TOL_S)

    @property
    def verdict(self) -> str:
        if self.matches:
            return "matches"
        what = "slower" if self.speed < 1.0 - SPEED_TOL else ("faster" if self.speed > 1.0 + SPEED_TOL else "as fast")
        if self.delay is None or abs(self.delay) <= DELAY_TOL_S:
            return f"real gripper {what}"
        return f"real gripper {what} and {'later' if self.delay > 0 else 'earlier'}"

    def effect(self) -> GripperResponse:
        """The ``gripper_response`` that makes the checked model's gripper answer like the measured one."""
        base = dict(self.model_values or {})
        speed = float(np.clip(base.get("speed", 1.0) * self.speed, _SPEC["speed"].lo, _SPEC["speed"].hi))
        values = {**base, "speed": round(speed, 3)}
        if self.delay is not None:
            values["delay"] = round(float(np.clip(base.get("delay", 0.0) + self.delay, 0.0, _SPEC["delay"].hi)), 3)
        return GripperResponse(values=values)

    def to_json(self) -> dict:
        return {"strokes": self.strokes, "closing": self.closing, "speed_real_per_s": self.speed_real,
                "speed_sim_per_s": self.speed_sim, "fitted": {"speed": self.speed, "delay_s": self.delay},
                "with_command": self.with_command, "rmse_before": self.rmse_before, "rmse_after": self.rmse_after,
                "grasp_stops": self.grasp_stops, "verdict": self.verdict, "line": self.line()}

    def line(self) -> str:
        """One line for the verbs' terminal output."""
        if not self.strokes:
            return "gripper: no strokes in the data (no gripper channel, or it never moves by 0.1)"
        s = (f"gripper: {self.strokes} strokes, real {self.speed_real:.2f}/s, sim {self.speed_sim:.2f}/s "
             f"(speed ×{self.speed:.2f}")
        if self.delay is None:
            s += "; no gripper_cmd: the delay from request to motion cannot be seen"
        else:
            s += f", delay {1e3 * self.delay:+.0f} ms; stroke RMSE {self.rmse_before:.3f} -> {self.rmse_after:.3f}"
        return s + f"): {self.verdict}"


def check_gripper(trajs, model=None) -> GripperCheck:
    """The gripper row of ``trajs`` (workbench ``Trajectory``s with ``gripper``, and ``gripper_cmd``
    when logged) against the simulated gripper under ``model`` (a ``RobotModel``; its
    ``gripper_response``, if any, is the starting point). With the request in every trajectory that
    has strokes: (delay, speed) fitted on the stroke windows; else the speed alone."""
    fx = model.effect("gripper_response") if model is not None else None
    base = fx.values() if fx is not None else {"delay": 0.0, "speed": 1.0, "tau": 0.0}
    values = base if fx is not None else None
    found = [(tr, strokes(tr.gripper, tr.t, tr.name)) for tr in trajs if tr.gripper is not None]
    found = [(tr, ss) for tr, ss in found if ss]
    all_strokes = [s for _, ss in found for s in ss]
    closing = [s for s in all_strokes if s.direction == "close"]
    stops = sorted(round(s.end, 3) for s in closing if s.end < 0.95)
    if not all_strokes:
        return GripperCheck(0, 0, None, SIM_SPEED * base["speed"], 1.0, None, False, model_values=values)
    speed_real = float(np.median([s.speed for s in all_strokes]))
    with_cmd = all(tr.gripper_cmd is not None for tr, _ in found)
    if not with_cmd:
        speed_sim = _step_answer_speed(all_strokes, base, float(np.median([tr.rate_hz for tr, _ in found])))
        return GripperCheck(len(all_strokes), len(closing), speed_real, speed_sim, speed_real / speed_sim, None, False,
                            grasp_stops=stops, model_values=values)
    windows = _windows(found)
    before = _window_rmse(windows, [base["delay"]], [base["speed"]], base["tau"])[0]
    delay, speed, after = _fit_windows(windows, base)
    if before <= after:  # the grid's nearest point is no better than the model as it is
        delay, speed, after = base["delay"], base["speed"], before
    sim = [s for w in _answers(windows, base["delay"], base["speed"], base["tau"]) for s in w]
    speed_sim = float(np.median([s.speed for s in sim])) if sim else SIM_SPEED * base["speed"]
    return GripperCheck(len(all_strokes), len(closing), speed_real, speed_sim, speed / base["speed"],
                        delay - base["delay"], True, before, after, stops, values)


def _step_answer_speed(found: list[Stroke], base: dict, rate_hz: float) -> float:
    """Median stroke speed of the simulated answer to a step request over each measured stroke,
    sampled at the log's rate."""
    n = max(s.steps for s in found) + 4
    t = np.arange(n) / rate_hz
    cmd = np.array([[s.begin] + [s.end] * (n - 1) for s in found])
    y = simulate(cmd, t, cmd[:, 0], 0.0, base["speed"], base["tau"])
    return float(np.median([x.speed for row in y for x in strokes(row, t)]))


@dataclass
class _Window:
    t: np.ndarray
    g: np.ndarray
    cmd: np.ndarray


def _windows(found) -> list[_Window]:
    """Each measured stroke from ``pre`` samples before it (the longest delay) to 2 after it."""
    out = []
    for tr, ss in found:
        hz = tr.rate_hz
        pre = int(math.ceil(_SPEC["delay"].hi * hz)) + 2
        for s in ss:
            a, b = max(0, s.start - pre), min(len(tr.t), s.start + s.steps + 3)
            out.append(_Window(tr.t[a:b] - tr.t[a], tr.gripper[a:b], np.clip(tr.gripper_cmd[a:b], 0.0, 1.0)))
    return out


def _batch(windows: list[_Window], delays, speeds, tau):
    """Every window under every (delay, speed) pair: positions (P, W, n) clamped to each window's measured range."""
    n = max(len(w.t) for w in windows)
    cmd = np.stack([np.pad(w.cmd, (0, n - len(w.cmd)), mode="edge") for w in windows])
    g = np.stack([np.pad(w.g, (0, n - len(w.g)), mode="edge") for w in windows])
    dt = float(np.median(np.concatenate([np.diff(w.t) for w in windows])))
    t = np.arange(n) * dt
    p, nw = len(delays), len(windows)
    # a window that starts in motion (the previous stroke turned back) starts with the target on the fingers
    target0 = np.where(np.abs(g[:, 1] - g[:, 0]) / dt > MOVING, g[:, 0], cmd[:, 0])
    y = simulate(np.tile(cmd, (p, 1)), t, np.tile(g[:, 0], p), np.repeat(delays, nw), np.repeat(speeds, nw), tau,
                 np.tile(target0, p))
    y = np.clip(y.reshape(p, nw, n), g.min(1)[None, :, None], g.max(1)[None, :, None])
    valid = np.arange(n)[None, :] < np.array([len(w.t) for w in windows])[:, None]
    return y, g, valid, t


def _window_rmse(windows, delays, speeds, tau) -> np.ndarray:
    y, g, valid, _ = _batch(windows, np.asarray(delays, float), np.asarray(speeds, float), tau)
    err = (y - g[None]) ** 2 * valid[None]
    return np.sqrt(err.sum((1, 2)) / valid.sum())


def _fit_windows(windows, base) -> tuple[float, float, float]:
    """(delay, speed, RMSE): a coarse grid over the effect's bounds, then a finer one around its best."""
    d_lo, d_hi, s_lo, s_hi = _SPEC["delay"].lo, _SPEC["delay"].hi, _SPEC["speed"].lo, _SPEC["speed"].hi
    delays, speeds = np.linspace(d_lo, d_hi, 16), np.geomspace(s_lo, s_hi, 24)
    for _ in range(2):
        dd, ss = (a.reshape(-1) for a in np.meshgrid(delays, speeds, indexing="ij"))
        r = _window_rmse(windows, dd, ss, base["tau"])
        best = int(np.argmin(r))
        d, s = float(dd[best]), float(ss[best])
        step_d, step_s = delays[1] - delays[0], speeds[1] / speeds[0]
        delays = np.clip(np.linspace(d - step_d, d + step_d, 11), d_lo, d_hi)
        speeds = np.clip(s * np.geomspace(1 / step_s, step_s, 11), s_lo, s_hi)
    return d, s, float(r[best])


def _answers(windows, delay, speed, tau) -> list[list[Stroke]]:
    """The strokes of the simulated answer in every window (unclamped: its own speed)."""
    out = []
    for w in windows:
        y = simulate(w.cmd[None], w.t, w.g[:1], delay, speed, tau)[0]
        out.append(strokes(y, w.t))
    return out


def gripper_json(check: GripperCheck | None) -> dict:
    """The ``gripper`` key of a verb's JSON (none when the data has no gripper channel)."""
    return {} if check is None else {"gripper": check.to_json()}


def gripper_lines(check: GripperCheck | None) -> list[str]:
    """The ``gripper`` row of a verb's terminal summary."""
    return [] if check is None else [check.line()]
