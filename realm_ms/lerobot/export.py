"""Write REALM episodes to a LeRobot v3.0 dataset through LeRobot's own writer API.

``export_dataset(ExportConfig(...))`` plans episodes as (task, perturbation, seed) keys, runs them
through ``realm eval``'s driver (``eval.runner.run_plan``) on its backends (in process, or
``workers`` processes) with the chosen policy from ``realm eval``'s registry, and writes the frames
that its record hook (``FrameHook``: one DROID frame per control step, ``features.py``) hands back
with each finished episode, through ``LeRobotDataset.create`` / ``add_frame`` / ``save_episode`` /
``finalize``; the language instruction is the LeRobot ``task``. An episode that ends in an error
(e.g. a policy's bad reply) or whose cell is unsupported is reported and not written.

Per-episode metadata LeRobot's schema has no place for (task id, perturbation and its drawn
parameters, seed, policy, robot model, best progression, success, kept or not) goes to
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
from realm_ms.eval.protocol import DEFAULT, EpisodeKey
from realm_ms.eval.protocol import plan as protocol_plan
from realm_ms.lerobot.features import DEFAULT_SIZE, FPS, ROBOT_TYPE, dataset_features, dataset_frame, obs_to_numpy

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
    perturbations: list[str] = field(default_factory=lambda: [DEFAULT])
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
    workers: int = 1  # env processes (``realm eval``'s process backend); 1 runs in this process
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
        for name, flag in (("episodes", "--episodes"), ("commit_every", "--commit-every"), ("workers", "--workers")):
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
    robot_model: str = "nominal"  # the robot the episode ran, named as realm eval's records name it


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
    """Check the names; returns the perturbations in their registered spelling, each once."""
    import realm_ms  # noqa: F401
    from realm_ms.eval.protocol import canonical_perturbation
    from realm_ms.tasks import TASKS

    unknown = [t for t in tasks if t not in TASKS]
    if unknown:
        raise ExportError(f"unknown task(s) {unknown}; available: {sorted(TASKS)}")
    try:
        return list(dict.fromkeys(canonical_perturbation(p) for p in perturbations))  # "0" and "Default": one cell
    except ValueError as e:
        raise ExportError(str(e)) from None


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
class Plan:
    """Episodes that run as one ``run_plan`` of ``realm eval``'s driver: one policy and its settings."""

    policy: str
    keys: list[EpisodeKey]
    replan_every: int = 8
    max_steps: int | None = None  # None: the task horizon
    want: dict[tuple[str, str], int] | None = None  # kept episodes still wanted per cell (None: every key)
    replay: dict[EpisodeKey, list] = field(default_factory=dict)  # recorded perturbation draws to replay


def _tried(done: list[dict]) -> set[tuple[EpisodeKey, str]]:
    from realm_ms.eval.records import key_of

    return {(key_of(r), r["policy"]) for r in done}


def plan(cfg: ExportConfig, done: list[dict]) -> list[Plan]:
    """Per (task, perturbation): the seeds not tried yet and how many episodes are still wanted."""
    tried = _tried(done)
    keys, want = [], {}
    for task in cfg.tasks:
        for pert in cfg.perturbations:
            kept = sum(bool(r["kept"]) for r in done if r["task"] == task and r["perturbation"] == pert and r["policy"] == cfg.policy)
            want[(task, pert)] = max(0, cfg.episodes - kept)
            if want[(task, pert)]:
                keys += [k for k in protocol_plan([task], [pert], cfg.max_attempts(), cfg.seed) if (k, cfg.policy) not in tried]
    return [Plan(cfg.policy, keys, max_steps=cfg.max_steps, want=want)]


def plan_from_records(records: list[dict], done: list[dict], max_steps: int | None = None) -> list[Plan]:
    """One key per finished ``realm eval`` record (not yet exported), cell by cell in the records'
    order; one ``Plan`` per (policy, re-planning interval, episode length) among them."""
    from realm_ms.eval.records import key_of

    tried = _tried(done)
    plans: dict[tuple, Plan] = {}
    for r in records:
        key = key_of(r)
        if r.get("status", "ok") != "ok" or (key, r["policy"]) in tried:
            continue
        run = (r["policy"], int(r.get("replan_every") or 8), max_steps or r.get("max_steps"))
        p = plans.setdefault(run, Plan(*run[:1], [], *run[1:]))
        p.keys.append(key)
        params = (r.get("perturbation_params") or {}).get("params")
        if params:
            p.replay[key] = params
    for p in plans.values():  # cell-major: a cell's env is built once
        cells = list(dict.fromkeys(k.cell() for k in p.keys))
        p.keys.sort(key=lambda k: cells.index(k.cell()))
    return list(plans.values())


@dataclass
class FrameHook:
    """The record hook of an export (``eval.runner.EpisodeHook``): a dataset frame per control step,
    frame t the observation *before* action t with the progression / success *after* it; runs where
    the env steps, in a worker process too."""

    gripper_labels: str = "command"
    replay: dict[EpisodeKey, list] = field(default_factory=dict)  # recorded perturbation draws to replay

    def reset_options(self, key: EpisodeKey) -> dict | None:
        params = self.replay.get(key)
        return None if params is None else {"perturbation_params": params}

    def observe(self, obs: dict, row: int) -> dict:
        return obs_to_numpy(obs, row)

    def frame(self, seen: dict, action, ep) -> dict:
        return dataset_frame(seen, gripper_label(action, self.gripper_labels), ep.progression, ep.success, ep.done, ep.instruction)

    def finish(self, ep, frames: list) -> dict:
        return dict(frames=frames, best=ep.best)


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


def _robots(recs: list[dict]) -> list:
    """The distinct robot models the records ran (``records.robot_model_of``; None = nominal), in order."""
    from realm_ms.eval.records import robot_model_of

    return list({json.dumps(m, sort_keys=True): m for m in map(robot_model_of, recs)}.values())


def same_robot(a, b) -> bool:
    """Two robot model values (a name, a MODEL.yaml path, an inline dict; None = nominal) are the same
    robot: equal, or equal once loaded (``droid-aligned`` and the path of its file)."""
    if a == b:
        return True
    if a is None or b is None:
        return False
    from realm_ms.agents.robot_model import load_robot_model

    try:
        return load_robot_model(a).to_dict() == load_robot_model(b).to_dict()
    except (ValueError, FileNotFoundError):
        return False


def _open(cfg: ExportConfig) -> tuple[_Writer, list[dict]]:
    from realm_ms.eval.runner import robot_model_name

    recs = read_sidecar(cfg.out)
    kept = [r for r in recs if r["kept"]]
    other = sorted({r.get("gripper_labels", "command") for r in kept} - {cfg.gripper_labels})
    if other:
        raise ExportError(f"{cfg.out} holds episodes with --gripper-labels {other[0]}; resume with the same "
                          f"--gripper-labels or export to a new --out")
    others = [m for m in _robots(kept) if not same_robot(m, cfg.robot_model)]
    if others:  # the card names one robot; resume is keyed without it
        raise ExportError(f"{cfg.out} holds episodes of robot model {robot_model_name(others[0])}, not "
                          f"{robot_model_name(cfg.robot_model)}; export to a new --out")
    writer = _Writer(cfg)
    # episodes whose sidecar line was written but whose save/commit never completed are forgotten
    done = [r for r in recs if not r["kept"] or (r["episode_index"] is not None and r["episode_index"] < writer.num_episodes)]
    _rewrite_sidecar(writer.root, done)
    return writer, done


def _run(cfg: ExportConfig, writer: _Writer, done: list[dict], plans: list[Plan]) -> dict:
    """Run the plans on ``realm eval``'s driver and backends (``cfg.workers`` processes, or in
    process); each finished episode's frames are written (or dropped) in this process, in the order
    the episodes end."""
    from tqdm import tqdm

    summary = dict(root=str(writer.root), repo_id=cfg.repo_id, written=0, dropped=0, already=sum(bool(r["kept"]) for r in done),
                   errors=0, episodes=[])
    try:
        for p in plans:
            if p.keys:
                _run_plan(cfg, writer, p, summary)
            for (task, pert), short in (p.want or {}).items():
                if short:
                    tqdm.write(f"{task} {pert}: {short} episode(s) short (only failures in the seeds tried)")
    finally:
        writer.close()
    write_card(cfg, writer.root)
    summary["total_episodes"] = writer.num_episodes
    return summary


def _run_plan(cfg: ExportConfig, writer: _Writer, p: Plan, summary: dict) -> None:
    from tqdm import tqdm

    from realm_ms.eval.backends.choose import choose_backend
    from realm_ms.eval.policies import make_policy
    from realm_ms.eval.records import key_of
    from realm_ms.eval.runner import HOOKED, RunConfig, run_plan

    policy = make_policy(p.policy)
    try:
        _check_joint_position(p.policy, policy)
        req = policy.obs_request()
        req.width, req.height = cfg.width, cfg.height
        run_cfg = RunConfig(policy=policy.spec(), env_side=policy.env_side, max_steps=p.max_steps, replan_every=p.replan_every,
                            obs=req, quality=False, shader=cfg.shader, hook=FrameHook(cfg.gripper_labels, p.replay),
                            env_kwargs={"robot_model": cfg.robot_model} if cfg.robot_model else {})

        def full(key: EpisodeKey) -> bool:
            """The cell has its successful episodes (``--success-only``): the driver skips its later keys."""
            return p.want is not None and p.want[key.cell()] == 0

        def on_record(rec: dict) -> None:
            hooked, key = rec.pop(HOOKED, None), key_of(rec)
            if rec.get("status") != "ok":  # not in the sidecar: a rerun tries an error's episode again
                summary["errors"] += rec.get("status") == "error"
                tqdm.write(f"{key.task} {key.perturbation} seed {key.seed}: {rec.get('status')}: {rec.get('error', '')}")
                return
            if full(key):  # ran beside the episode that completed its cell
                return
            keep = rec["success"] or not cfg.success_only
            for frame in hooked["frames"]:
                writer.add(frame)
            er = EpisodeRecord(key.task, key.perturbation, key.seed, p.policy, rec["instruction"], rec["steps"], hooked["best"],
                               rec["success"], keep, writer.num_episodes if keep else None, rec["perturbation_params"].get("params"),
                               rec["config"], cfg.gripper_labels, rec["robot_model"])
            _append_sidecar(writer.root, er)  # before the save: a crash mid-save is filtered on resume
            if keep:
                writer.save()
                summary["written"] += 1
                if p.want is not None:
                    p.want[key.cell()] -= 1
            else:
                writer.discard()
                summary["dropped"] += 1
            summary["episodes"].append(asdict(er))
            tqdm.write(f"{key.task} {key.perturbation} seed {key.seed}: progression {er.progression:.2f} "
                       f"success {er.success} ({er.steps} steps){'' if keep else ' dropped'}")

        backend = choose_backend("cpu", run_cfg, min(cfg.workers, len(p.keys)))
        try:
            run_plan(p.keys, policy, backend, on_record, progress_bar=cfg.progress, replan_every=p.replan_every,
                     env_kwargs=run_cfg.env_kwargs, skip=full, desc="export episodes")
        finally:
            backend.close()
    finally:
        policy.close()


def _check_joint_position(spec: str, policy) -> None:
    """The dataset's ``action`` is absolute joint targets (``droid_joint_pos``) and the export's env
    runs in that space: a policy (server) that declares another action space is refused, never
    written as if its velocities were joint targets."""
    from realm_ms.errors import UserError
    from realm_ms.eval.policies import policy_action_space

    if not hasattr(policy, "env_action_space"):
        return
    kw = policy_action_space(policy)
    if kw:
        from realm_ms.agents.droid_action_spaces import action_space_name

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
    perturbation, recorded perturbation draws, seed, policy spec, re-planning interval and robot model
    (faithful for deterministic policies: the scripted expert, LeRobot policies without sampling).

    The robot is the one the records name (``records.robot_model_of``: records older than
    ``--robot-model`` ran the nominal robot); ``cfg.robot_model`` may only name that same robot.
    Records of several robots are refused: a dataset holds one robot."""
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
    cfg.robot_model = _run_robot(path, records, cfg.robot_model)
    writer, done = _open(cfg)
    return _run(cfg, writer, done, plan_from_records(records, done, cfg.max_steps))


def _run_robot(path: Path, records: list[dict], flag):
    """The one robot model of a run's records, which loads here; ``flag`` (``--robot-model``) may only repeat it."""
    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.eval.runner import robot_model_name

    robots = _robots(records)
    if len(robots) > 1:
        raise ExportError(f"{path}: its records ran {len(robots)} robot models ({', '.join(map(robot_model_name, robots))}) and a "
                          "dataset holds one; split records.jsonl by robot_model and export each file (--from-eval FILE) to its own --out")
    (robot,) = robots
    if flag is not None and not same_robot(flag, robot):
        raise ExportError(f"--robot-model {robot_model_name(flag)} contradicts {path}, whose episodes ran robot model "
                          f"{robot_model_name(robot)}; drop --robot-model: --from-eval re-simulates on the run's robot")
    try:
        load_robot_model(robot)
    except (ValueError, FileNotFoundError) as e:
        raise ExportError(f"{path}: the run's robot model {robot_model_name(robot)} does not load here ({e}); "
                          "run the export where the eval ran (a relative MODEL.yaml path is read from there)") from None
    return robot


def write_card(cfg: ExportConfig, root: Path) -> Path:
    """``README.md`` in the dataset root: LeRobot's card template filled with what this dataset holds,
    the robot model it ran and the credits its CC-BY 4.0 licence asks to keep (the robot model's
    provenance credit, the scanned object meshes')."""
    from lerobot.datasets.dataset_metadata import LeRobotDatasetMetadata
    from lerobot.datasets.utils import create_lerobot_dataset_card

    from realm_ms.agents.robot_model import load_robot_model
    from realm_ms.assets.real_objects import REAL_OBJECTS
    from realm_ms.eval.runner import robot_model_name

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
    robot = robot_model_name(cfg.robot_model)
    credit = load_robot_model(cfg.robot_model).provenance.get("credit") if cfg.robot_model is not None else None
    credits = [f"- robot model `{robot}`: {credit}."] if credit else []
    meshes: dict[str, list[str]] = {}
    for o in REAL_OBJECTS.values():
        if o.licence == "CC-BY-4.0":
            meshes.setdefault(o.credit, []).append(o.name)
    credits += [f"- object meshes in the scenes ({', '.join(names)}): {source}, CC-BY 4.0." for source, names in meshes.items()]
    description = "\n".join([
        "REALM generalization-benchmark episodes (realm-ms: ManiSkill3/SAPIEN, DROID Panda + Robotiq 2F-85,",
        f"15 Hz `droid_joint_pos` absolute joint-position control), written by `realm export` with policy `{cfg.policy}`.",
        f"Robot model: `{robot}`" + (" (the DROID robot as REALM builds it)." if cfg.robot_model is None
                                     else f" (`--robot-model`; each episode's env config in `{SIDECAR}` names it)."),
        "",
        "DROID feature names: `observation.images.{exterior_1_left, exterior_2_left, wrist_left}` "
        f"({cfg.width}x{cfg.height} video, {FPS} fps), `observation.state` (7 joint positions + gripper position in [0, 1]), "
        "`action` (7 absolute joint-position targets + gripper command in [0, 1], 1 = closed"
        + ("; binary: 1 wherever the policy closed the gripper at all" if cfg.gripper_labels == "binary" else "")
        + "); the language "
        "instruction is the LeRobot task. Extras: `progression` and `success` after the frame's action, `next.done`.",
        "Per-episode metadata (env id, perturbation and its parameters, seed, policy, robot model, success, kept): "
        f"`{SIDECAR}`. Failed episodes are {'dropped' if cfg.success_only else 'kept'}.",
        "",
        *table,
        "",
        "Evaluate a policy trained on it in the same envs with `lerobot-eval --env.type=realm --env.task=<env id>` "
        "(the `lerobot_env_realm` plugin of realm-ms) or `realm eval`.",
        "",
        "Licence CC-BY 4.0 (https://creativecommons.org/licenses/by/4.0/): the episodes are made with CC-BY 4.0 "
        "material; reuse keeps these credits:",
        *credits,
    ])
    card = create_lerobot_dataset_card(
        tags=["REALM", "realm-ms", "DROID", "ManiSkill3", "simulation"], dataset_info=meta.info, license="cc-by-4.0",
        repo_id=cfg.repo_id, dataset_description=description,
    )
    path = root / "README.md"
    card.save(str(path))
    return path
