"""How closely the simulated DROID arm answers real DROID commands: closed-loop replay and its metrics.

A real DROID episode holds the measured joints ``q`` (T, 7) and, per step, the commanded flange
pose ``cartesian_position`` (T, 6). The replay puts the simulated arm at the measured start and
sends every step's command in DROID's ``cartesian_position`` space, turned into a joint target from
the *simulated* state (``agents/droid_action_spaces.py``, as the robot did from its measured one),
on the sysid replay simulator: the benchmark's controller, robot and effects (``ReplaySimulator``).

Metrics, the simulated arm beside the real one (flange = ``panda_link8``, forward kinematics of q):

- ``flange_mm``: median over the steps of |p_sim - p_real| in mm (an episode's flange error);
  ``free_mm`` the same over the free steps only (no grasp, push or near-singular posture:
  ``interaction.detect``);
- ``lag``: the steps k (0..``MAX_LAG``) after which the flange is closest, on average over the
  episode, to where a command pointed: argmin_k mean_t |p[t + k] - c[t]|;
- ``b``: the first-order per-step response p[t+1] - p[t] = b (c[t] - p[t]), least squares over the
  episode's steps and axes (1 = the flange reaches the command in one step).

Per-lab rows are medians over the lab's episodes. The arm alone is replayed: the gripper is locked
(its mass lumped), and grasps, pushes and contacts with the scene are not modelled.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from realm_ms.sysid.data_io import read_labs

#: largest lag (control steps) searched for
MAX_LAG = 10
#: every ``HELDOUT_EVERY``-th episode of a lab (by episode index, starting at the third) is held out
HELDOUT_EVERY = 3


@dataclass
class DroidEpisode:
    """One real DROID episode: measured joints and the commanded flange poses at 15 Hz."""

    name: str
    lab: str
    q: np.ndarray  # (T, 7) rad, measured
    cartesian_cmd: np.ndarray  # (T, 6) m / rad euler "xyz", commanded flange pose of each step
    gripper: np.ndarray  # (T,) measured, 0 open .. 1 closed
    control_hz: float = 15.0
    traj: object = field(default=None, repr=False)  # the workbench Trajectory it was read as (grasp masks)

    @property
    def steps(self) -> int:
        return len(self.q)


def lab_of(name: str, labs: dict[str, str]) -> str:
    """The one lab rule: ``index.json``'s entry, else the name's last ``_`` part (``droid100_000_TRI``)."""
    return labs.get(name) or name.rsplit("_", 1)[-1]


def flange_command(tr, ik) -> np.ndarray:
    """(T, 6) the flange pose a trajectory's command points at: its ``cartesian_position`` command
    when it is replayed as one (``--command closed_loop``), else the flange pose (forward
    kinematics) of its joint target (logged or rebuilt)."""
    cmd = tr.meta.get("droid_command") or {}
    if cmd.get("space") == "cartesian_position" and len(cmd["actions"]) == len(tr.t):
        return np.asarray(cmd["actions"], float)
    return ik.pose(tr.q_cmd)


def episodes_from(trajs, labs: dict[str, str], ik=None) -> list[DroidEpisode]:
    """``DroidEpisode`` per workbench trajectory, commanded at ``flange_command``."""
    from realm_ms.agents.droid_action_spaces import DroidIK

    ik, out = ik or DroidIK(), []
    for tr in trajs:
        g = tr.gripper if tr.gripper is not None else np.zeros(len(tr.t))
        out.append(DroidEpisode(tr.name, tr.meta.get("lab") or lab_of(tr.name, labs), tr.q, flange_command(tr, ik), g,
                                float(tr.control_hz or 15.0), tr))
    return out


def read_droid_episodes(data: str | Path, command: str | None = None) -> tuple[list[DroidEpisode], list[str]]:
    """The DROID episodes of ``data`` (any format ``data_io.load_each`` reads; a directory holding
    ``episodes/`` and ``index.json``, as ``../shared/droid_real``, too) and one line per episode set
    aside. ``command``: ``--command MODE[:SPACE]`` (default ``closed_loop``: the logged Cartesian
    command itself is replayed). Labs: ``read_labs`` / ``lab_of``."""
    from realm_ms.sysid.data_io import load_each
    from realm_ms.sysid.droid_formats import ReadOptions

    root = episodes_dir(data)
    trajs, skipped = load_each(root, ReadOptions.parse(command or "closed_loop"))
    return episodes_from(trajs, read_labs(root)), skipped


def episodes_dir(data: str | Path) -> Path:
    """Where the episode files of ``data`` are: ``data/episodes`` when it holds them and no npz of its own."""
    root = Path(data)
    if root.is_dir() and (root / "episodes").is_dir() and not any(root.glob("*.npz")):
        return root / "episodes"
    return root


def heldout_split(episodes: list[DroidEpisode], labs: dict[str, str] | None = None
                  ) -> tuple[list[DroidEpisode], list[DroidEpisode]]:
    """(held in, held out): per lab, episodes sorted by name, every ``HELDOUT_EVERY``-th from the
    third on is held out (about a third of every lab with three or more episodes). ``labs`` (name ->
    lab of *every* episode of the set, ``read_labs``): positions count the episodes set aside too,
    so an unreadable episode never moves another across the split."""
    names = {e.name: e.lab for e in episodes} | (labs or {})
    rank = {}
    for lab in sorted(set(names.values())):
        for i, n in enumerate(sorted(n for n, x in names.items() if x == lab)):
            rank[n] = i
    held_in, held_out = [], []
    for e in sorted(episodes, key=lambda e: (e.lab, e.name)):
        (held_out if rank[e.name] % HELDOUT_EVERY == HELDOUT_EVERY - 1 else held_in).append(e)
    return held_in, held_out


# ---------------------------------------------------------------------------- response metrics
def response_lag(p: np.ndarray, c: np.ndarray, max_lag: int = MAX_LAG) -> int:
    """Steps after which positions ``p`` (T, 3) are closest on average to the commands ``c`` (T, 3)."""
    n = len(p) - max_lag
    if n < 1:
        max_lag, n = len(p) - 1, 1
    err = [np.linalg.norm(p[k:k + n] - c[:n], axis=1).mean() for k in range(max_lag + 1)]
    return int(np.argmin(err))


def response_b(p: np.ndarray, c: np.ndarray) -> float:
    """Least-squares b of p[t+1] - p[t] = b (c[t] - p[t]) over steps and axes."""
    dp, e = p[1:] - p[:-1], c[:-1] - p[:-1]
    den = float((e * e).sum())
    return float((dp * e).sum() / den) if den > 0 else float("nan")


@dataclass
class EpisodeAlignment:
    name: str
    lab: str
    steps: int
    flange_mm: float  # median |p_sim - p_real| over the steps
    flange_mm_mean: float
    joint_mrad: list[float]  # median |q_sim - q_real| per joint
    lag_real: int
    lag_sim: int
    b_real: float
    b_sim: float
    # median |p_sim - p_real| over the free steps (neither grasping, pushing nor near-singular:
    # ``interaction.detect``; the arm-only replay models neither contact, the IK target is ill-defined
    # near a singularity) and the share of steps left out of it
    free_mm: float = float("nan")
    masked: float = 0.0


@dataclass
class LabAlignment:
    lab: str
    episodes: int
    flange_mm: float  # median of the episodes' medians
    lag_real: float
    lag_sim: float
    b_real: float
    b_sim: float
    free_mm: float = float("nan")  # median of the episodes' free-step medians


@dataclass
class AlignmentResult:
    """Per-episode and per-lab rows and the overall medians (``overall`` is a ``LabAlignment``
    named ``all``)."""

    model: str
    episodes: list[EpisodeAlignment] = field(default_factory=list)
    labs: list[LabAlignment] = field(default_factory=list)
    overall: LabAlignment | None = None
    seconds: float = 0.0

    def to_dict(self) -> dict:
        return asdict(self)

    def table(self, per_episode: bool = False) -> str:
        head = (f"{'':<28} {'eps':>4} {'flange mm':>9} {'free mm':>7} {'lag real':>8} {'lag sim':>7} {'b real':>6} "
                f"{'b sim':>6}")
        rows = [f"robot model: {self.model}", head]
        if per_episode:
            for e in self.episodes:
                rows.append(f"{e.name:<28} {1:>4} {e.flange_mm:>9.1f} {e.free_mm:>7.1f} {e.lag_real:>8d} {e.lag_sim:>7d} "
                            f"{e.b_real:>6.2f} {e.b_sim:>6.2f}")
        for r in self.labs + ([self.overall] if self.overall else []):
            rows.append(f"{r.lab:<28} {r.episodes:>4} {r.flange_mm:>9.1f} {r.free_mm:>7.1f} {r.lag_real:>8.1f} "
                        f"{r.lag_sim:>7.1f} {r.b_real:>6.2f} {r.b_sim:>6.2f}")
        return "\n".join(rows)


def summarize(name: str, rows: list[EpisodeAlignment]) -> LabAlignment:
    def med(xs):
        xs = [x for x in xs if np.isfinite(x)]
        return float(np.median(xs)) if xs else float("nan")

    return LabAlignment(name, len(rows), med([r.flange_mm for r in rows]), med([r.lag_real for r in rows]),
                        med([r.lag_sim for r in rows]), med([r.b_real for r in rows]), med([r.b_sim for r in rows]),
                        med([r.free_mm for r in rows]))


def compare_episode(ep: DroidEpisode, q_sim: np.ndarray, ik=None) -> EpisodeAlignment:
    """The metrics of one episode from its simulated joints ``q_sim`` (T, 7)."""
    from realm_ms.agents.droid_action_spaces import DroidIK
    from realm_ms.sysid.interaction import detect

    ik = ik or DroidIK()
    masked = detect(ep.traj, ik).masked if ep.traj is not None else np.zeros(ep.steps, bool)
    return episode_metrics(ep.name, ep.lab, ep.q, q_sim, ep.cartesian_cmd[:, :3], masked, ik)


def episode_metrics(name: str, lab: str, q: np.ndarray, q_sim: np.ndarray, c: np.ndarray, masked: np.ndarray, ik,
                    stride: int = 1) -> EpisodeAlignment:
    """The metrics of measured joints ``q`` beside simulated ``q_sim`` (T, 7) under commanded flange
    positions ``c`` (T, 3); ``masked`` (T,) steps the free error leaves out; lag and b on every
    ``stride``-th sample (one per command of a log faster than its commands)."""
    p_real = ik.flange(q)[:, :3, 3]
    p_sim = ik.flange(q_sim)[:, :3, 3]
    d = np.linalg.norm(p_sim - p_real, axis=1) * 1e3
    pr, ps, cs = p_real[::stride], p_sim[::stride], c[::stride]
    return EpisodeAlignment(
        name, lab, len(q), float(np.median(d)), float(d.mean()),
        [float(x) for x in np.median(np.abs(q_sim - q), axis=0) * 1e3],
        response_lag(pr, cs), response_lag(ps, cs), response_b(pr, cs), response_b(ps, cs),
        float(np.median(d[~masked])) if (~masked).any() else float("nan"), float(masked.mean()))


# ---------------------------------------------------------------------------- beside a multiple-shooting replay
#: why torque-space data has no flange figures
TORQUE_SKIP = ("torque space: no commanded target (q_cmd) to measure lag and response against, and the "
               "inverse-dynamics residual simulates no flange")


@dataclass
class FlangeComparison:
    """The flange beside the joints for the workbench verbs: one ``AlignmentResult`` per replayed model
    (``compare``: the model; ``fit`` and ``auto``: before and after, held-out), on the same
    trajectories; ``skipped`` says why there is none."""

    runs: list[AlignmentResult] = field(default_factory=list)
    skipped: str = ""

    def to_json(self) -> dict:
        if self.skipped:
            return {"skipped": self.skipped}
        return _finite({"runs": [r.to_dict() for r in self.runs]})

    def line(self) -> str:
        """"flange: 14.2 -> 4.9 mm median (free 12.0 -> 4.1), lag 2 -> 4 (real 4), b 0.45 -> 0.21 (real 0.20)"."""
        if self.skipped:
            return f"flange: not measured ({self.skipped})"
        o = [r.overall for r in self.runs]
        chain = lambda key, fmt: " -> ".join(format(getattr(x, key), fmt) for x in o)  # noqa: E731
        return (f"flange: {chain('flange_mm', '.1f')} mm median (free {chain('free_mm', '.1f')}), lag "
                f"{chain('lag_sim', 'g')} (real {o[0].lag_real:g}), b {chain('b_sim', '.2f')} (real {o[0].b_real:.2f}) "
                f"[{', '.join(r.model for r in self.runs)}; {o[0].episodes} trajectories, "
                f"{len({e.lab for e in self.runs[0].episodes})} lab(s)]")


def no_flange() -> FlangeComparison:
    """Torque space's flange figures: none, and why (``TORQUE_SKIP``)."""
    return FlangeComparison(skipped=TORQUE_SKIP)


def _finite(x):
    """JSON-ready: NaN and inf as null."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def replay_flange(segset, runs: list[tuple[str, np.ndarray]], ik=None) -> FlangeComparison:
    """Flange metrics of multiple-shooting replays (``replay.SegmentSet``; ``runs``: (label, simulated
    q at the samples (N, L, 7)) per model), per trajectory over its scored windows (every sample
    after the first burn-in, each once; segments restart from the measured state): the commanded
    flange position is ``flange_command``'s; the free steps are the scored ones (not saturated,
    grasping, stalled or near-singular); lag and b at the command rate. Labs: ``meta["lab"]``
    (``index.json`` or the file's own, ``data_io``), else one group ``all``."""
    from realm_ms.agents.droid_action_spaces import DroidIK

    ik = ik or DroidIK()
    per_traj: dict[int, list[tuple[int, np.ndarray]]] = {}
    for i, s in enumerate(segset.segments):
        per_traj.setdefault(s.traj, []).append((i, np.arange(s.score_from - s.start, s.stop - s.start)))
    out = FlangeComparison()
    cmds = {ti: flange_command(segset.trajs[ti], ik)[:, :3] for ti in per_traj}
    for label, sim in runs:
        rows = []
        for ti, parts in per_traj.items():
            tr = segset.trajs[ti]
            idx = np.concatenate([segset.sample_idx[i, k] for i, k in parts])
            q_sim = np.concatenate([sim[i, k] for i, k in parts])
            free = np.concatenate([segset.mask[i, k] for i, k in parts])
            stride = max(1, int(round(tr.rate_hz / tr.control_hz))) if tr.control_hz else 1
            rows.append(episode_metrics(tr.name, tr.meta.get("lab") or "all", tr.q[idx], q_sim, cmds[ti][idx], ~free,
                                        ik, stride))
        out.runs.append(tabulate(rows, label, 0.0))
    return out


# ---------------------------------------------------------------------------- closed-loop replay
def replay_closed_loop(episodes: list[DroidEpisode], model=None, sim=None) -> list[np.ndarray]:
    """Simulated joints (T, 7) per episode: episodes as arms of a batch, each step's
    ``cartesian_position`` command turned into a joint target from the simulated state (DROID's
    IK, targets clipped to the joint limits; ``closed_loop.ClosedLoopCommand``), held for the
    control period. ``model``: a robot model (path, dict, ``RobotModel``; None = the nominal
    robot); an effect whose ``theta`` has a row per episode gives each episode its own values.
    Episodes of similar length share a batch (``BATCH_LENGTH_RATIO``): a batch runs as long as
    its longest episode, and a finished episode holds its last target until then."""
    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.sysid.simulator import ReplaySimulator, SimConfig

    model = load_robot_model(model)
    sim = sim or ReplaySimulator(SimConfig.from_model(model))
    lengths = np.array([e.steps for e in episodes])
    order = np.argsort(lengths, kind="stable")
    out: list[np.ndarray] = [None] * len(episodes)  # type: ignore[list-item]
    start = 0
    while start < len(order):
        stop = start + 1
        while stop < len(order) and lengths[order[stop]] <= BATCH_LENGTH_RATIO * lengths[order[start]]:
            stop += 1
        idx = order[start:stop]
        for i, q in zip(idx, _replay_batch([episodes[i] for i in idx], model, idx, sim)):
            out[i] = q
        start = stop
    return out


#: episodes replayed in one batch are within this ratio of lengths (padding costs simulation)
BATCH_LENGTH_RATIO = 1.5


def _replay_batch(episodes: list[DroidEpisode], model, rows: np.ndarray, sim) -> list[np.ndarray]:
    from realm_ms.agents.effects import make_effect
    from realm_ms.sysid.closed_loop import NEVER, ClosedLoopCommand, bind

    sub = int(round(model.physics_hz / episodes[0].control_hz))
    lengths = np.array([e.steps for e in episodes])
    steps = int(lengths.max())
    k = np.arange(steps)[None]
    switch = np.where(k < lengths[:, None], k * sub, NEVER)
    cmds = np.stack([np.concatenate([e.cartesian_cmd, np.repeat(e.cartesian_cmd[-1:], steps - e.steps, 0)]) for e in episodes])
    q0 = np.stack([e.q[0] for e in episodes])
    effects = []
    for fx in model.arm_effects:  # this batch's rows of per-episode parameters (the arm's: its gripper is locked)
        th = fx.theta.cpu().numpy()
        part = make_effect(fx.name, fx.values(), fx.config_dict())
        part.set_theta(th[rows] if th.shape[0] > 1 else th)
        effects.append(part)
    closed = ClosedLoopCommand("cartesian_position", switch, cmds)  # every arm switches at step 0
    out = sim.rollout(q0, np.zeros_like(q0), bind(closed, q0[:, None]), effects, steps=(steps - 1) * sub)
    return [out[i, : e.steps * sub : sub] for i, e in enumerate(episodes)]


def align_grid(episodes: list[DroidEpisode], model, grid: dict[str, list[float]]) -> list[tuple[dict[str, float], AlignmentResult]]:
    """Every combination of the ``grid`` values (``{"target_filter.tau": [0.06, 0.08], ...}``, keys
    ``effect.param``, per-joint names set all joints) on top of ``model``, each replayed on every
    episode in one batch (a row per episode and candidate): ``[(values, its AlignmentResult), ...]``."""
    import itertools
    import time

    from realm_ms.agents.effects import make_effect
    from realm_ms.agents.robot_model import load_robot_model

    t0 = time.perf_counter()
    base = load_robot_model(model).copy()
    keys = list(grid)
    combos = [dict(zip(keys, c)) for c in itertools.product(*(grid[k] for k in keys))]
    for name in dict.fromkeys(k.split(".")[0] for k in keys):
        if base.effect(name) is None:
            base.effects.append(make_effect(name))
    rows_per = len(episodes)
    for fx in base.effects:
        theta = []
        for c in combos:
            fx_c = make_effect(fx.name, fx.values(), fx.config_dict())
            fx_c.set_values({k.split(".")[1]: v for k, v in c.items() if k.split(".")[0] == fx.name})
            theta += [fx_c.theta[0].numpy()] * rows_per
        fx.set_theta(np.stack(theta))
    sims = replay_closed_loop(episodes * len(combos), base)
    from realm_ms.agents.droid_action_spaces import DroidIK

    ik = DroidIK()
    seconds = time.perf_counter() - t0
    return [(c, tabulate([compare_episode(e, s, ik) for e, s in zip(episodes, sims[i * rows_per:(i + 1) * rows_per])],
                         ", ".join(f"{k}={v:g}" for k, v in c.items()), seconds))
            for i, c in enumerate(combos)]


def leave_one_lab_out(found: list[tuple[dict[str, float], AlignmentResult]]) -> list[tuple[str, dict[str, float], float]]:
    """What a lab outside the data should expect from choosing on the others: for each lab of a grid's
    results (``align_grid``), the candidate with the smallest median flange error over the *other*
    labs' episodes, and this lab's median under it: ``[(lab, values, flange_mm), ...]``."""
    def med(res: AlignmentResult, keep) -> float:
        return float(np.median([e.flange_mm for e in res.episodes if keep(e.lab)]))

    out = []
    for lab in sorted({e.lab for e in found[0][1].episodes}):
        values, res = min(found, key=lambda cr: med(cr[1], lambda x: x != lab))
        out.append((lab, values, med(res, lambda x: x == lab)))
    return out


def align(episodes: list[DroidEpisode], model=None, model_name: str | None = None) -> AlignmentResult:
    """Replay ``episodes`` closed loop under ``model`` and tabulate the metrics per episode and lab."""
    import time

    from realm_ms.agents.droid_action_spaces import DroidIK

    t0 = time.perf_counter()
    sims = replay_closed_loop(episodes, model)
    ik = DroidIK()
    rows = [compare_episode(e, s, ik) for e, s in zip(episodes, sims)]
    name = model_name or (str(model) if model is not None and not isinstance(model, dict) else "nominal")
    return tabulate(rows, name, time.perf_counter() - t0)


def tabulate(rows: list[EpisodeAlignment], model_name: str, seconds: float) -> AlignmentResult:
    """Per-episode rows, per-lab medians and the overall medians of one model."""
    labs = [summarize(lab, [r for r in rows if r.lab == lab]) for lab in sorted({r.lab for r in rows})]
    return AlignmentResult(model_name, rows, labs, summarize("all", rows), seconds)


# ---------------------------------------------------------------------------- the workbench's npz
def rebuilt_joint_targets(ep: DroidEpisode, ik=None) -> np.ndarray:
    """(T, 7) the joint targets DROID streamed, rebuilt from the *measured* state: each step's
    ``cartesian_position`` command through DROID's conversion at ``q[t]`` (up to its IK's
    null-space choice), clipped to the joint limits."""
    from realm_ms.sysid.droid_formats import rebuild_targets

    return rebuild_targets("cartesian_position", ep.cartesian_cmd, ep.q, None, ik=ik)


def write_workbench_npz(episodes: list[DroidEpisode], out_dir: str | Path) -> list[Path]:
    """One ``realm sysid`` npz per episode (``t``, ``q``, ``q_cmd`` from ``rebuilt_joint_targets``,
    ``gripper``, ``control_hz``)."""
    from realm_ms.agents.droid_action_spaces import DroidIK
    from realm_ms.sysid.data_io import write_npz
    from realm_ms.sysid.timeseries import Trajectory

    ik, paths = DroidIK(), []
    for ep in episodes:
        p = Path(out_dir) / f"{ep.name}.npz"
        write_npz(p, Trajectory(ep.name, np.arange(ep.steps) / ep.control_hz, ep.q, rebuilt_joint_targets(ep, ik),
                                gripper=ep.gripper, control_hz=ep.control_hz, meta={"lab": ep.lab}))
        paths.append(p)
    return paths
