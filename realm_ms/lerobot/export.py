"""Write REALM episodes to a LeRobot v3.0 dataset through LeRobot's own writer API.

``export_dataset(ExportConfig(...))`` plans episodes as tasks x perturbations x seeds, runs each
with the chosen policy (``rollout.record_episode``) and writes the frames with
``LeRobotDataset.create`` / ``add_frame`` / ``save_episode`` / ``finalize`` (DROID features, see
``features.py``); the language instruction is the LeRobot ``task``.

Per-episode metadata LeRobot's schema has no place for (task id, perturbation and its drawn
parameters, seed, policy, best progression, success, kept or not) goes to
``meta/realm_episodes.jsonl``, one JSON line per attempted episode. That file is also the resume
state: every ``commit_every`` episodes the dataset is finalized (parquet footers written) and
re-opened with ``LeRobotDataset.resume``, so an interrupted export keeps every committed episode
and a rerun skips them. A dataset card (``README.md``) is written at the end.
"""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

from realm_ms.atomic import write_text
from realm_ms.errors import InputError
from realm_ms.lerobot.features import DEFAULT_SIZE, FPS, ROBOT_TYPE, dataset_features, dataset_frame
from realm_ms.lerobot.rollout import DEFAULT_PERTURBATION

SIDECAR = "meta/realm_episodes.jsonl"
#: ``action[7]`` conventions: the command the policy sent, or DROID's binary close intent
GRIPPER_LABELS = ("command", "binary")
BINARY_GRIPPER_THRESHOLD = 0.01  # a command above this is a close intent (the expert's gentle pinch starts at 0.03)
VIDEO_BACKEND = "pyav"  # decoding backend recorded on the writer; also skips torchcodec's noisy probe


class ExportError(InputError):
    """Bad export input (unknown task, mismatching existing dataset, ...): one clear message."""


@dataclass
class ExportConfig:
    out: Path
    tasks: list[str]
    episodes: int = 1  # episodes written per (task, perturbation)
    perturbations: list[str] = field(default_factory=lambda: [DEFAULT_PERTURBATION])
    seed: int = 0  # episode k of a (task, perturbation) cell runs with seed + k
    policy: str = "expert"
    repo_id: str | None = None  # default: realm/<out dir name>
    success_only: bool = False  # drop failed episodes and try further seeds (at most 2N + 10 per cell)
    width: int = DEFAULT_SIZE[0]
    height: int = DEFAULT_SIZE[1]
    max_steps: int | None = None  # per episode; default: the task horizon (800)
    shader: str = "default"
    commit_every: int = 1  # finalize + re-open every N episodes (crash-safe resume granularity)
    progress: bool = True
    # "binary": action[7] = 1 wherever the policy commanded any closing, else 0 (DROID's teleoperated
    # trigger and REALM's binary gripper); "command": the gripper command as sent
    gripper_labels: str = "command"
    robot_model: str | None = None  # a named robot model or a MODEL.yaml; None = the nominal robot

    def __post_init__(self):
        from realm_ms.validate import check_seed

        self.out = Path(self.out)
        if self.repo_id is None:
            self.repo_id = f"realm/{_repo_name(self.out.resolve().name)}"
        check_repo_id(self.repo_id)
        for name, flag in (("episodes", "--episodes"), ("commit_every", "--commit-every")):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ExportError(f"{flag} must be >= 1 (got {v!r})")
        if self.episodes > 100_000:  # the plan lists every seed to try: a huge count would never start
            raise ExportError(f"--episodes {self.episodes}: at most 100000 per (task, perturbation)")
        if self.max_steps is not None and (isinstance(self.max_steps, bool) or not isinstance(self.max_steps, int) or self.max_steps < 1):
            raise ExportError(f"--max-steps must be >= 1 (got {self.max_steps!r}); leave it out for the task horizon")
        if self.gripper_labels not in GRIPPER_LABELS:
            raise ExportError(f"--gripper-labels {self.gripper_labels!r}: choose one of {', '.join(GRIPPER_LABELS)}")
        if self.width < 16 or self.height < 16:
            raise ExportError(f"image size {self.width}x{self.height} is too small (>= 16x16)")
        if self.width > 4096 or self.height > 4096:
            raise ExportError(f"image size {self.width}x{self.height} is too large (<= 4096x4096)")
        try:
            check_seed(self.seed, "--seed", self.max_attempts())
        except InputError as e:
            raise ExportError(str(e)) from None

    def max_attempts(self) -> int:
        return 2 * self.episodes + 10 if self.success_only else self.episodes


@dataclass
class EpisodeRecord:
    task: str
    perturbation: str
    seed: int
    policy: str
    instruction: str
    steps: int
    progression: float
    success: bool
    kept: bool
    episode_index: int | None = None  # index in the dataset when kept
    params: list | None = None  # the drawn perturbation parameters per sub-env (info["perturbation"]["params"])
    config: dict | None = None  # the env's RealmEnvConfig.to_dict(): RealmEnvConfig.from_dict re-creates it
    gripper_labels: str = "command"  # convention of action[7] (ExportConfig.gripper_labels)


# Hugging Face Hub repo ids: OWNER/NAME, letters, digits, '-', '_', '.'; no '--' or '..'; <= 96 chars
_REPO_PART = re.compile(r"^[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?$")


def check_repo_id(repo_id: str) -> str:
    """A Hub repo id ``OWNER/NAME`` (it goes into the dataset card and ``push_to_hub``)."""
    parts = repo_id.split("/") if isinstance(repo_id, str) else []
    ok = (len(parts) == 2 and all(_REPO_PART.match(p) for p in parts) and "--" not in repo_id and ".." not in repo_id
          and len(repo_id) <= 96)
    if not ok:
        raise ExportError(f"--repo-id {repo_id!r} is not a Hub repo id: OWNER/NAME of letters, digits, '-', '_', '.' "
                          "(no '--' or '..', at most 96 characters), e.g. realm/pick_apple_demos")
    return repo_id


def _repo_name(name: str) -> str:
    """The default NAME of ``realm/NAME`` from the output directory's name, made a valid repo name."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", name)
    name = re.sub(r"([-.])\1+", r"\1", name).strip("._-")[:90]
    return name or "dataset"


def check_out(cfg: ExportConfig) -> None:
    """``--out`` can hold the dataset: checked before any episode runs."""
    from realm_ms.validate import check_output_path

    check_output_path(cfg.out, "--out", "dir")
    info = cfg.out / "meta" / "info.json"
    if cfg.out.is_dir() and any(cfg.out.iterdir()) and not info.is_file():
        raise ExportError(f"{cfg.out} exists and is not a LeRobot dataset (no meta/info.json); choose an empty or new --out")


def read_sidecar(root: Path) -> list[dict]:
    path = Path(root) / SIDECAR
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _append_sidecar(root: Path, rec: EpisodeRecord) -> None:
    with open(Path(root) / SIDECAR, "a") as f:
        f.write(json.dumps(asdict(rec)) + "\n")


def _rewrite_sidecar(root: Path, recs: list[dict]) -> None:
    write_text(Path(root) / SIDECAR, "".join(json.dumps(r) + "\n" for r in recs))


def validate_tasks(tasks: list[str], perturbations: list[str]) -> list[str]:
    """Check the names; returns the perturbations in their registered spelling."""
    import realm_ms  # noqa: F401
    from realm_ms.tasks import TASKS

    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise ExportError(f"unknown task(s) {unknown}; available: {sorted(TASKS)}")
    out = []
    for p in perturbations:
        if p in (DEFAULT_PERTURBATION, "0") or p.lower() == "default":
            out.append(DEFAULT_PERTURBATION)
            continue
        from realm_ms.perturbations import PerturbationSet

        try:
            out.append(PerturbationSet.resolve(p).name)
        except ValueError as e:
            raise ExportError(str(e)) from None
    return out


class _Writer:
    """A LeRobotDataset opened for writing (created or resumed) with periodic commits."""

    def __init__(self, cfg: ExportConfig):
        import os

        from lerobot.datasets.lerobot_dataset import LeRobotDataset

        os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 prints its whole config per video otherwise

        self.cfg = cfg
        self._cls = LeRobotDataset
        self.root = cfg.out
        info = self.root / "meta" / "info.json"
        if info.exists():
            self._check_compatible(json.loads(info.read_text()))
            self.ds = LeRobotDataset.resume(cfg.repo_id, root=self.root, video_backend=VIDEO_BACKEND)
            self.ds.clear_episode_buffer(delete_images=True)  # leftovers of an interrupted episode
        else:
            if self.root.exists():
                if any(self.root.iterdir()):
                    raise ExportError(f"{self.root} exists and is not a LeRobot dataset (no meta/info.json); choose an empty or new --out")
                self.root.rmdir()  # LeRobot creates the root itself
            self.ds = LeRobotDataset.create(
                cfg.repo_id, fps=FPS, features=dataset_features(cfg.width, cfg.height), root=self.root,
                robot_type=ROBOT_TYPE, use_videos=True, video_backend=VIDEO_BACKEND,
            )
        self.pending = 0

    def _check_compatible(self, info: dict) -> None:
        want = dataset_features(self.cfg.width, self.cfg.height)
        have = info.get("features", {})
        bad = [k for k, f in want.items() if k not in have or list(have[k]["shape"]) != list(f["shape"])]
        if bad or info.get("fps") != FPS:
            raise ExportError(
                f"{self.root} holds a dataset with other features/fps ({bad or 'fps ' + str(info.get('fps'))}); "
                "export to a new --out or use the same --width/--height"
            )

    @property
    def num_episodes(self) -> int:
        return int(self.ds.meta.total_episodes)

    def add(self, frame: dict) -> None:
        self.ds.add_frame(frame)

    def discard(self) -> None:
        self.ds.clear_episode_buffer(delete_images=True)

    def save(self) -> None:
        self.ds.save_episode()
        self.pending += 1
        if self.pending >= self.cfg.commit_every:
            self.commit()

    def commit(self) -> None:
        if self.pending == 0:
            return
        self.ds.finalize()
        self.ds = self._cls.resume(self.cfg.repo_id, root=self.root, video_backend=VIDEO_BACKEND)
        self.pending = 0

    def close(self) -> None:
        if self.ds.has_pending_frames():
            self.discard()
        self.ds.finalize()


@dataclass
class Job:
    """One episode to (re-)simulate."""

    task: str
    perturbation: str
    seed: int
    policy: str
    replan_every: int = 8
    perturbation_params: list | None = None  # recorded draws to replay (eval records)
    max_steps: int | None = None


@dataclass
class Cell:
    """Jobs of one (task, perturbation): the env is built once; stop after ``want`` kept episodes."""

    task: str
    perturbation: str
    jobs: list[Job]
    want: int


def _key(task: str, perturbation: str, seed: int, policy: str) -> str:
    return f"{task}|{perturbation}|{seed}|{policy}"


def plan(cfg: ExportConfig, done: list[dict]) -> list[Cell]:
    """Per (task, perturbation): the seeds not tried yet and how many episodes are still wanted."""
    tried = {_key(r["task"], r["perturbation"], r["seed"], r["policy"]) for r in done}
    cells = []
    for task in cfg.tasks:
        for pert in cfg.perturbations:
            kept = sum(bool(r["kept"]) for r in done if r["task"] == task and r["perturbation"] == pert and r["policy"] == cfg.policy)
            seeds = [cfg.seed + k for k in range(cfg.max_attempts())]
            jobs = [Job(task, pert, s, cfg.policy, max_steps=cfg.max_steps) for s in seeds if _key(task, pert, s, cfg.policy) not in tried]
            cells.append(Cell(task, pert, jobs, max(0, cfg.episodes - kept)))
    return cells


def plan_from_records(records: list[dict], done: list[dict], max_steps: int | None = None) -> list[Cell]:
    """One job per finished ``realm eval`` record (not yet exported), grouped by (task, perturbation)."""
    tried = {_key(r["task"], r["perturbation"], r["seed"], r["policy"]) for r in done}
    cells: dict[tuple[str, str], Cell] = {}
    for r in records:
        if r.get("status", "ok") != "ok" or _key(r["task"], r["perturbation"], r["seed"], r["policy"]) in tried:
            continue
        params = (r.get("perturbation_params") or {}).get("params")
        job = Job(r["task"], r["perturbation"], int(r["seed"]), r["policy"], int(r.get("replan_every") or 8), params or None,
                  max_steps or r.get("max_steps"))
        cell = cells.setdefault((job.task, job.perturbation), Cell(job.task, job.perturbation, [], 0))
        cell.jobs.append(job)
        cell.want += 1
    return list(cells.values())


def gripper_label(action, labels: str):
    """``action`` with its gripper entry in the ``labels`` convention (``GRIPPER_LABELS``).

    Why "binary": the expert pinches gently (it commands the measured width + 0.02, ~20 N per pad),
    so its gripper commands on a grasp are 0.03-0.3 and depend on the object's width to 0.02: a
    learned policy's regression error is larger than that margin, and it ends up holding the pads at
    the object's surface without force. Binary labels carry what the demo means, close or open."""
    if labels != "binary":
        return action
    import numpy as np

    a = np.array(action, dtype=np.float32).reshape(8)
    a[7] = 1.0 if a[7] > BINARY_GRIPPER_THRESHOLD else 0.0
    return a


def _open(cfg: ExportConfig) -> tuple[_Writer, list[dict]]:
    recs = read_sidecar(cfg.out)
    other = sorted({r.get("gripper_labels", "command") for r in recs if r["kept"]} - {cfg.gripper_labels})
    if other:
        raise ExportError(f"{cfg.out} holds episodes with --gripper-labels {other[0]}; resume with the same "
                          f"--gripper-labels or export to a new --out")
    writer = _Writer(cfg)
    # episodes whose sidecar line was written but whose save/commit never completed are forgotten
    done = [r for r in recs if not r["kept"] or (r["episode_index"] is not None and r["episode_index"] < writer.num_episodes)]
    _rewrite_sidecar(writer.root, done)
    return writer, done


def _run(cfg: ExportConfig, writer: _Writer, done: list[dict], cells: list[Cell]) -> dict:
    from realm_ms.lerobot.rollout import make_export_policy, record_episode, rollout_config
    from realm_ms.tasks.config import make_env

    root = writer.root
    total = sum(c.want for c in cells)
    summary = dict(root=str(root), repo_id=cfg.repo_id, written=0, dropped=0, already=sum(bool(r["kept"]) for r in done), episodes=[])
    bar = _progress(total, cfg.progress)
    try:
        for cell in cells:
            if cell.want == 0 or not cell.jobs:
                continue
            env_config, rest = rollout_config(cell.task, cfg.width, cfg.height, None, cfg.shader, perturbation=cell.perturbation,
                                              **({"robot_model": cfg.robot_model} if cfg.robot_model else {}))
            env = make_env(env_config, **rest)
            policies: dict[str, object] = {}
            want = cell.want
            try:
                for job in cell.jobs:
                    if want == 0:
                        break
                    if job.policy not in policies:
                        env.reset(seed=job.seed)
                        policies[job.policy] = make_export_policy(job.policy, env, job.replan_every)
                        _check_joint_position(job.policy, policies[job.policy])

                    def on_frame(np_obs, action, progression, success, is_done, instruction):
                        writer.add(dataset_frame(np_obs, gripper_label(action, cfg.gripper_labels), progression, success,
                                                 is_done, instruction))

                    res = record_episode(env, policies[job.policy], job.seed, on_frame, max_steps=job.max_steps,
                                         perturbation_params=job.perturbation_params)
                    keep = res.success or not cfg.success_only
                    rec = EpisodeRecord(job.task, job.perturbation, job.seed, job.policy, res.instruction, res.steps,
                                        res.progression, res.success, keep, writer.num_episodes if keep else None,
                                        (res.perturbation or {}).get("params"), env_config.to_dict(), cfg.gripper_labels)
                    _append_sidecar(root, rec)  # before the save: a crash mid-save is filtered on resume
                    if keep:
                        writer.save()
                        want -= 1
                        summary["written"] += 1
                        bar.advance()
                    else:
                        writer.discard()
                        summary["dropped"] += 1
                    summary["episodes"].append(asdict(rec))
                    bar.note(f"{job.task} {job.perturbation} seed {job.seed}: progression {res.progression:.2f} "
                             f"success {res.success} ({res.steps} steps){'' if keep else ' dropped'}")
                if want:
                    bar.note(f"{cell.task} {cell.perturbation}: {want} episode(s) short (only failures in the seeds tried)")
            finally:
                env.close()
    finally:
        writer.close()
        bar.close()
    write_card(cfg, root)
    summary["total_episodes"] = writer.num_episodes
    return summary


def _check_joint_position(spec: str, actor) -> None:
    """The dataset's ``action`` is absolute joint targets (``droid_joint_pos``) and the export's env
    runs in that space: a policy (server) that declares another action space is refused, never
    written as if its velocities were joint targets."""
    from realm_ms.errors import UserError
    from realm_ms.eval.policies import policy_action_space

    policy = getattr(actor, "policy", None)  # a ChunkedPolicy's realm eval policy
    if policy is None or not hasattr(policy, "env_action_space"):
        return
    kw = policy_action_space(policy)
    if kw:
        from realm_ms.agents.droid_action_spaces import action_space_name

        policy.close()
        raise UserError(f"realm export --policy {spec}: the policy acts in {action_space_name(kw)} (its server declares it); "
                        "a dataset stores absolute joint targets (joint_position), so export takes joint_position policies only; "
                        "evaluate this one with `realm eval`")


def export_dataset(cfg: ExportConfig) -> dict:
    """Export policy episodes for tasks x perturbations x seeds; returns a summary
    (``root``, ``repo_id``, ``written``, ``dropped``, ``already``, ``total_episodes``, ``episodes``)."""
    if not cfg.tasks:
        raise ExportError("no tasks given")
    check_out(cfg)
    cfg.perturbations = validate_tasks(cfg.tasks, cfg.perturbations)
    writer, done = _open(cfg)
    return _run(cfg, writer, done, plan(cfg, done))


def export_eval_run(run_dir: Path, cfg: ExportConfig) -> dict:
    """Export the episodes of a ``realm eval`` run, re-simulated from its ``records.jsonl``: same task,
    perturbation, recorded perturbation draws, seed, policy spec and re-planning interval (faithful
    for deterministic policies: the scripted expert, LeRobot policies without sampling)."""
    from realm_ms.eval.records import read_records

    check_out(cfg)
    path = Path(run_dir) / "records.jsonl" if Path(run_dir).is_dir() else Path(run_dir)
    if not path.exists():
        raise ExportError(f"--from-eval: {path} does not exist; give the run directory of `realm eval --out RUN`")
    records = [r for r in read_records(path) if isinstance(r.get("policy"), str)]
    if not records:
        raise ExportError(f"{path}: no realm eval records found")
    cfg.tasks = sorted({r["task"] for r in records})
    validate_tasks(cfg.tasks, sorted({r["perturbation"] for r in records}))
    cfg.policy = ",".join(sorted({r["policy"] for r in records}))
    writer, done = _open(cfg)
    return _run(cfg, writer, done, plan_from_records(records, done, cfg.max_steps))


def write_card(cfg: ExportConfig, root: Path) -> Path:
    """``README.md`` in the dataset root: LeRobot's card template filled with what this dataset holds."""
    from lerobot.datasets.dataset_metadata import LeRobotDatasetMetadata
    from lerobot.datasets.utils import create_lerobot_dataset_card

    meta = LeRobotDatasetMetadata(cfg.repo_id, root=root)
    recs = read_sidecar(root)
    kept = [r for r in recs if r["kept"]]
    rows = {}
    for r in kept:
        k = (r["task"], r["perturbation"])
        n, s, p = rows.get(k, (0, 0, 0.0))
        rows[k] = (n + 1, s + int(r["success"]), p + float(r["progression"]))
    table = ["| task | perturbation | episodes | success | mean progression |", "|---|---|---|---|---|"]
    table += [f"| {t} | {p} | {n} | {s}/{n} | {pr / n:.2f} |" for (t, p), (n, s, pr) in sorted(rows.items())]
    description = "\n".join([
        "REALM generalization-benchmark episodes (realm-ms: ManiSkill3/SAPIEN, DROID Panda + Robotiq 2F-85,",
        f"15 Hz `droid_joint_pos` absolute joint-position control), written by `realm export` with policy `{cfg.policy}`.",
        "",
        "DROID feature names: `observation.images.{exterior_1_left, exterior_2_left, wrist_left}` "
        f"({cfg.width}x{cfg.height} video, {FPS} fps), `observation.state` (7 joint positions + gripper position in [0, 1]), "
        "`action` (7 absolute joint-position targets + gripper command in [0, 1], 1 = closed"
        + ("; binary: 1 wherever the policy closed the gripper at all" if cfg.gripper_labels == "binary" else "")
        + "); the language "
        "instruction is the LeRobot task. Extras: `progression` and `success` after the frame's action, `next.done`.",
        "Per-episode metadata (env id, perturbation and its parameters, seed, policy, success, kept): "
        f"`{SIDECAR}`. Failed episodes are {'dropped' if cfg.success_only else 'kept'}.",
        "",
        *table,
        "",
        "Evaluate a policy trained on it in the same envs with `lerobot-eval --env.type=realm --env.task=<env id>` "
        "(the `lerobot_env_realm` plugin of realm-ms) or `realm eval`.",
    ])
    card = create_lerobot_dataset_card(
        tags=["REALM", "realm-ms", "DROID", "ManiSkill3", "simulation"], dataset_info=meta.info, license="mit",
        repo_id=cfg.repo_id, dataset_description=description,
    )
    path = root / "README.md"
    card.save(str(path))
    return path


class _progress:
    """A rich progress bar over episodes (or plain prints when disabled)."""

    def __init__(self, total: int, enabled: bool):
        self.p = None
        if enabled and total:
            from rich.progress import Progress

            self.p = Progress(transient=False)
            self.p.start()
            self.t = self.p.add_task("export episodes", total=total)

    def advance(self) -> None:
        if self.p:
            self.p.advance(self.t)

    def note(self, msg: str) -> None:
        (self.p.console.print if self.p else print)(msg)

    def close(self) -> None:
        if self.p:
            self.p.stop()
