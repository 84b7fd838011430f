"""DROID commands converted at the simulated state, inside a rollout (``--command closed_loop``).

DROID's robot turned each step's command (a flange pose, a Cartesian or joint velocity) into a
joint target from its *measured* state (``droid_action_spaces``). Replaying the rebuilt targets
(``--command rebuild``) hands the simulated arm the real arm's corrections; replaying the command
itself, converted from the *simulated* state at every command switch, lets a simulated arm that
lags or leads get its own corrections, as a robot with that dynamics would have: drift compounds
as on the robot, and the conversion (IK) runs on the simulated joints.

One :class:`ClosedLoopCommand` holds every arm's commands (E arms, K commands each, the physics
step at which each starts); called at every physics step with the arms' joint positions it gives
the rows whose command switched and their new joint targets. ``bind`` turns it into the
``cmd(k, q)`` function the rollouts (``ReplaySimulator``, ``MujocoReference``) track; arms before
their first switch track the ordinary per-step ``cmd``.

``reference=True`` is the synthetic teleoperator (``synth_droid``): the commands are joint
*references*, and at each switch the action in ``action_space`` that asks for the reference from
the current state is chosen (``from_joint_target``) and then converted (``to_joint_target``),
as DROID's teleoperation closes the loop through its operator; the actions sent are recorded.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

NEVER = np.iinfo(np.int64).max // 2  # padding of ``switch`` for arms with fewer commands


@dataclass
class ClosedLoopCommand:
    action_space: str
    switch: np.ndarray  # (E, K) int64, physics step at which command j takes over (NEVER = padding)
    actions: np.ndarray  # (E, K, D) arm actions (or joint references with ``reference``)
    reference: bool = False
    sent: np.ndarray | None = field(default=None, repr=False)  # (E, K, D) actions sent (reference mode)
    targets: np.ndarray | None = field(default=None, repr=False)  # (E, K, 7) joint targets produced

    def __post_init__(self):
        self._space = None
        self._ik = None
        self._next = None

    def __getstate__(self):  # pickled to worker processes: the IK rebuilds there
        return {k: v for k, v in self.__dict__.items() if k not in ("_space", "_ik", "_next")}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.__post_init__()

    @property
    def space(self):
        if self._space is None:
            from realm_ms.agents.droid_action_spaces import DroidIK, make_action_space

            self._space = make_action_space(self.action_space, "position")
            self._ik = DroidIK() if self.action_space.startswith("cartesian") else None
        return self._space

    def rows(self, idx) -> "ClosedLoopCommand":
        idx = np.asarray(idx)
        return ClosedLoopCommand(self.action_space, self.switch[idx], self.actions[idx], self.reference)

    def key(self, i: int) -> bytes:
        """What distinguishes arm i's command stream (joined to the rollout cache's arm key)."""
        return self.action_space.encode() + self.switch[i].tobytes() + np.ascontiguousarray(self.actions[i]).tobytes()

    def reset(self) -> None:
        e, k = self.switch.shape
        d = 6 if self.action_space.startswith("cartesian") else 7  # the sent action, not the reference
        self._next = np.zeros(e, dtype=np.int64)
        self.sent = np.full((e, k, d), np.nan)
        self.targets = np.full((e, k, 7), np.nan)

    def __call__(self, step: int, q: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Rows whose command switches at ``step`` and their (R, 7) joint targets from joints ``q`` (E, 7)."""
        if self._next is None:
            self.reset()
        e, k = self.switch.shape
        ptr = self._next
        due = (ptr < k) & (self.switch[np.arange(e), np.minimum(ptr, k - 1)] <= step)
        if not due.any():
            return None
        rows = np.flatnonzero(due)
        # the newest command due (a log coarser than the physics step may have passed several)
        j = np.array([ptr[r] + int(np.searchsorted(self.switch[r, ptr[r]:], step, side="right")) - 1 for r in rows])
        self._next[rows] = j + 1
        sp = self.space
        qr = np.asarray(q, dtype=np.float64)[rows]
        g = np.zeros(len(rows))
        a = self.actions[rows, j]
        if self.reference:
            ref = np.concatenate([a, g[:, None]], 1)
            a = sp.from_joint_target(ref, qr, g, self._ik)[:, :-1]
        tgt = sp.to_joint_target(np.concatenate([a, g[:, None]], 1), qr, g, self._ik)[:, :7]
        from realm_ms.agents.droid_action_spaces import Q_LIMITS

        tgt = np.clip(tgt, Q_LIMITS[:, 0], Q_LIMITS[:, 1])  # as the benchmark env clips a converted action
        self.sent[rows, j] = a
        self.targets[rows, j] = tgt
        return rows, tgt


def bind(closed: ClosedLoopCommand | None, cmd: np.ndarray):
    """What a rollout tracks: ``cmd`` (E, S, 7) itself, or with ``closed`` a function
    ``(k, q) -> (E, 7)`` (the rollouts' closed-loop form) giving ``cmd``'s target until an arm's
    first command switch and the closed-loop target from then on (a shorter ``cmd`` holds its last
    target: (E, 1, 7) for arms that all switch at step 0)."""
    if closed is None:
        return cmd
    active = np.zeros(cmd.shape[0], bool)
    over = np.zeros((cmd.shape[0], 7))

    def target(k: int, q: np.ndarray) -> np.ndarray:
        hit = closed(k, q)
        if hit is not None:
            active[hit[0]] = True
            over[hit[0]] = hit[1]
        return np.where(active[:, None], over, cmd[:, min(k, cmd.shape[1] - 1)])

    return target


def from_segments(trajs, segments, dt: float) -> ClosedLoopCommand | None:
    """The closed-loop commands of multiple-shooting segments (``replay.SegmentSet``), or None when no
    trajectory asks for them (``meta["droid_command"]``, set by ``--command closed_loop``)."""
    if not any("droid_command" in tr.meta for tr in trajs):
        return None
    spaces = {tr.meta["droid_command"]["space"] for tr in trajs if "droid_command" in tr.meta}
    missing = [tr.name for tr in trajs if "droid_command" not in tr.meta]
    if len(spaces) > 1 or missing:
        from realm_ms.sysid.timeseries import DataError

        raise DataError("closed-loop replay needs every trajectory's command in one action space; got "
                        + (f"{sorted(spaces)}" if len(spaces) > 1 else f"none in {missing[0]}")
                        + ": pick one with --command closed_loop:SPACE")
    cut = [tr.name for tr in trajs if len(tr.meta["droid_command"]["actions"]) != len(tr.t)]
    if cut:
        from realm_ms.sysid.timeseries import DataError

        raise DataError(f"{cut[0]}: a single log cut into time blocks cannot be replayed closed loop; pass --heldout DIR "
                        "(another log) or use --command rebuild")
    space = spaces.pop()
    k = max(s.stop - s.start for s in segments)
    d = trajs[0].meta["droid_command"]["actions"].shape[1]
    switch = np.full((len(segments), k), NEVER, dtype=np.int64)
    actions = np.zeros((len(segments), k, d))
    for i, s in enumerate(segments):
        tr = trajs[s.traj]
        tt = tr.t[s.start:s.stop] - tr.t[s.start]
        n = s.stop - s.start
        # command i takes over at the first physics step at or after its sample time
        switch[i, :n] = np.ceil(tt / dt - 1e-6).astype(np.int64)
        actions[i, :n] = tr.meta["droid_command"]["actions"][s.start:s.stop]
    return ClosedLoopCommand(space, switch, actions)
