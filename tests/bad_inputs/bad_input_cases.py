"""The bad-input corpus: what a new user might type or feed, and what realm-ms must answer.

Every case is data: a command line (``argv``, run as ``realm ARGV``; ``{root}`` is the directory
of generated files, see ``bad_input_files.py``) or a Python call (``call(root)``), and either

* ``error``: a regex the one-line error must match (CLI: the last stderr line, exit code 2;
  Python: the exception message, a ``ValueError``/``InputError``), naming the file, field or flag; or
* ``accepted``: the documented meaning of an input that is valid (``check`` asserts it).

Env cases (``env=True``) create REALM envs; ``warn_ok`` lets a documented warning stand in for an
error (actions that are clipped: the env warns once, see docs/validation.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable


@dataclass
class Case:
    id: str
    argv: list[str] | None = None
    call: Callable[[Path], Any] | None = None
    error: str | None = None
    accepted: str | None = None
    check: Callable[[Any], None] | None = None
    env: bool = False
    warn_ok: bool = False
    needs_no_cuda: bool = False
    subprocess: bool = False
    marks: list = field(default_factory=list)


def cli(id: str, argv: str, error: str | None = None, accepted: str | None = None, **kw) -> Case:
    return Case(id, argv=argv.split(), error=error, accepted=accepted, **kw)


CPU = "--device cpu --workers 1"

# ---------------------------------------------------------------------------- realm sysid: flags
CASES: list[Case] = [
    cli("compare-segment-0", f"sysid compare {{root}}/good --segment 0 {CPU}", r"argument --segment: must be > 0 s"),
    cli("compare-segment-neg", f"sysid compare {{root}}/good --segment -1 {CPU}", r"argument --segment: must be > 0 s"),
    cli("compare-segment-nan", f"sysid compare {{root}}/good --segment nan {CPU}", r"argument --segment: must be a finite"),
    cli("compare-segment-inf", f"sysid compare {{root}}/good --segment inf {CPU}", r"argument --segment: must be a finite"),
    cli("compare-segment-text", f"sysid compare {{root}}/good --segment long {CPU}", r"argument --segment: expected a single number"),
    cli("compare-workers-0", "sysid compare {root}/good --workers 0", r"argument --workers: must be >= 1"),
    cli("compare-workers-neg", "sysid compare {root}/good --workers -3", r"argument --workers: must be >= 1"),
    cli("compare-workers-frac", "sysid compare {root}/good --workers 1.5", r"argument --workers: expected an integer"),
    cli("compare-device-cuda-without-gpu", "sysid compare {root}/good --device cuda --workers 1",
        r"--device cuda: no CUDA GPU", needs_no_cuda=True),
    cli("compare-device-unknown", "sysid compare {root}/good --device tpu", r"argument --device: invalid choice"),
    cli("compare-missing-data", f"sysid compare {{root}}/nowhere {CPU}", r"DATA .*nowhere.* does not exist"),
    cli("compare-json-is-dir", f"sysid compare {{root}}/good --json {{root}}/out_dir {CPU}", r"--json: .*out_dir is a directory"),
    # ------------------------------------------------------------------------ npz data
    cli("npz-frame-index-timestamps", f"sysid compare {{root}}/frames {CPU}", r"frames/traj_000\.npz: `t` looks like frame indices"),
    cli("npz-millisecond-timestamps", f"sysid compare {{root}}/millis {CPU}", r"millis/traj_000\.npz: median time step .* must be in seconds"),
    cli("npz-3600s-gap", f"sysid compare {{root}}/gap {CPU}", r"gap/traj_000\.npz: `t` jumps by 3600(\.\d+)? s at sample 20"),
    cli("npz-time-backwards", f"sysid compare {{root}}/backwards {CPU}", r"backwards/traj_000\.npz: time is not strictly increasing"),
    cli("npz-control-hz-0", f"sysid compare {{root}}/ctrl_zero {CPU}", r"ctrl_zero/traj_000\.npz: `control_hz` = 0; expected a positive"),
    cli("npz-control-hz-neg", f"sysid compare {{root}}/ctrl_neg {CPU}", r"ctrl_neg/traj_000\.npz: `control_hz` = -15; expected a positive"),
    cli("npz-control-hz-nan", f"sysid compare {{root}}/ctrl_nan {CPU}", r"ctrl_nan/traj_000\.npz: `control_hz` = nan"),
    cli("npz-control-hz-shape-3", f"sysid compare {{root}}/ctrl_vec {CPU}", r"ctrl_vec/traj_000\.npz: `control_hz` has shape \(3,\)"),
    cli("npz-logged-slower-than-control", f"sysid compare {{root}}/ctrl_slow {CPU}", r"below its control rate control_hz = 60 Hz"),
    cli("npz-nan-gripper", f"sysid compare {{root}}/nan_gripper {CPU}", r"nan_gripper/traj_000\.npz: `gripper` contains NaN/inf \(first at sample 7\)"),
    cli("npz-gripper-2d", f"sysid compare {{root}}/gripper_2d {CPU}", r"`gripper` has shape \(45, 2\), expected \(T,\)"),
    cli("npz-nan-q", f"sysid compare {{root}}/nan_q {CPU}", r"`q` contains NaN/inf \(first at sample 5\)"),
    cli("npz-degrees", f"sysid compare {{root}}/degrees {CPU}", r"look like degrees"),
    cli("npz-q-six-joints", f"sysid compare {{root}}/q_six {CPU}", r"`q` has shape \(45, 6\), expected \(T, 7\)"),
    cli("npz-q-fewer-rows", f"sysid compare {{root}}/q_short {CPU}", r"`q` has 42 samples but `t` has 45"),
    cli("npz-missing-q-cmd", f"sysid compare {{root}}/no_qcmd {CPU}", r"no_qcmd/traj_000\.npz: missing key\(s\) \['q_cmd'\]"),
    cli("npz-too-few-samples", f"sysid compare {{root}}/few_samples {CPU}", r"only 10 samples; need at least 20"),
    cli("npz-target-beyond-limits", f"sysid compare {{root}}/beyond_limits {CPU}", r"commanded target of joint 4 .* outside the joint limits"),
    cli("npz-t-scalar", f"sysid compare {{root}}/t_scalar {CPU}", r"`t` is a single number"),
    cli("npz-t-text", f"sysid compare {{root}}/t_text {CPU}", r"`t` is not numeric"),
    cli("npz-text-file-renamed", f"sysid compare {{root}}/text_npz {CPU}", r"text_npz/traj\.npz: not an \.npz archive \(a text file\)"),
    cli("npz-empty-file", f"sysid compare {{root}}/empty_npz {CPU}", r"empty_npz/traj\.npz: not an \.npz archive \(empty\)"),
    cli("npz-binary-garbage", f"sysid compare {{root}}/not_zip_npz {CPU}", r"not_zip_npz/traj\.npz: not an \.npz archive \(not a zip archive\)"),
    cli("npz-npy-renamed", f"sysid compare {{root}}/npy_as_npz.npz {CPU}", r"npy_as_npz\.npz: not an \.npz archive"),
    cli("data-dir-without-data", f"sysid compare {{root}}/no_data {CPU}", r"no_data: no \.npz trajectories \(nor \.json, \.csv, trajectory\.h5\) and no LeRobot dataset"),
    cli("data-is-a-text-file", f"sysid compare {{root}}/a_file.txt {CPU}", r"a_file\.txt: expected a directory of \.npz files"),
    # ------------------------------------------------------------------------ LeRobot data
    cli("lerobot-info-list", f"sysid compare {{root}}/lr_list {CPU}", r"lr_list/meta/info\.json: expected a JSON object .* got list"),
    cli("lerobot-info-empty", f"sysid compare {{root}}/lr_empty {CPU}", r"lr_empty/meta/info\.json: expected a JSON object .* got an empty object"),
    cli("lerobot-info-not-json", f"sysid compare {{root}}/lr_badjson {CPU}", r"lr_badjson/meta/info\.json: not valid JSON"),
    cli("lerobot-v2", f"sysid compare {{root}}/lr_v2 {CPU}", r"LeRobot dataset version v2\.1; only v3\.0"),
    cli("lerobot-feature-shape-empty", f"sysid compare {{root}}/lr_shape_empty {CPU}", r"features\.observation\.state\.shape is \[\]"),
    cli("lerobot-feature-shape-6", f"sysid compare {{root}}/lr_shape_6 {CPU}", r"features\.action\.shape is \[6\]"),
    cli("lerobot-features-list", f"sysid compare {{root}}/lr_features_list {CPU}", r"info\.json: `features` must be an object"),
    cli("lerobot-fps-0", f"sysid compare {{root}}/lr_fps0 {CPU}", r"info\.json: fps = 0; expected a positive"),
    cli("lerobot-corrupt-parquet", f"sysid compare {{root}}/lr_corrupt {CPU}", r"file-000\.parquet: not a readable parquet file"),
    cli("lerobot-missing-episode-index", f"sysid compare {{root}}/lr_no_episode {CPU}", r"no `episode_index` column"),
    # ------------------------------------------------------------------------ MODEL.yaml
    cli("model-physics-hz-neg", f"sysid compare {{root}}/good --model {{root}}/models/physics_neg.yaml {CPU}",
        r"--model: .*physics_neg\.yaml: physics_hz: must be a positive number of Hz, got -120"),
    cli("model-physics-hz-0", f"sysid compare {{root}}/good --model {{root}}/models/physics_zero.yaml {CPU}",
        r"physics_zero\.yaml: physics_hz: must be a positive"),
    cli("model-physics-hz-100", f"sysid compare {{root}}/good --model {{root}}/models/physics_100.yaml {CPU}",
        r"physics_hz: 100 Hz is not a whole multiple of the 15 Hz control rate"),
    cli("model-physics-hz-text", f"sysid compare {{root}}/good --model {{root}}/models/physics_text.yaml {CPU}",
        r"physics_hz: expected a number in Hz, got 'fast'"),
    cli("model-physics-hz-nan", f"sysid compare {{root}}/good --model {{root}}/models/physics_nan.yaml {CPU}",
        r"physics_hz: must be a positive number of Hz, got nan"),
    cli("model-effects-string", f"sysid compare {{root}}/good --model {{root}}/models/effects_string.yaml {CPU}",
        r"effects: expected a list of effects .* got str 'coulomb_friction'"),
    cli("model-effect-unknown", f"sysid compare {{root}}/good --model {{root}}/models/effects_unknown.yaml {CPU}",
        r"effects\[0\]: unknown effect 'magic_friction'; known: coulomb_friction"),
    cli("model-effect-without-name", f"sysid compare {{root}}/good --model {{root}}/models/effects_no_name.yaml {CPU}",
        r"effects\[0\]: expected a name or a mapping with 'name'"),
    cli("model-param-out-of-bounds", f"sysid compare {{root}}/good --model {{root}}/models/param_bounds.yaml {CPU}",
        r"effects\[0\]: coulomb_friction\.fc4 = 99 N·m is outside its bounds"),
    cli("model-param-unknown", f"sysid compare {{root}}/good --model {{root}}/models/param_unknown.yaml {CPU}",
        r"effects\[0\]: effect 'coulomb_friction' has no parameter 'friction'"),
    cli("model-params-list", f"sysid compare {{root}}/good --model {{root}}/models/params_list.yaml {CPU}",
        r"effects\[0\]\.params: expected a mapping"),
    cli("model-config-unknown", f"sysid compare {{root}}/good --model {{root}}/models/config_unknown.yaml {CPU}",
        r"effects\[0\]: unknown setting\(s\) \['wobbly'\]"),
    cli("model-bad-yaml", f"sysid compare {{root}}/good --model {{root}}/models/bad_yaml.yaml {CPU}", r"bad_yaml\.yaml: not valid YAML"),
    cli("model-top-level-list", f"sysid compare {{root}}/good --model {{root}}/models/top_list.yaml {CPU}",
        r"top_list\.yaml: expected a mapping at the top level, got list"),
    cli("model-gains-unknown", f"sysid compare {{root}}/good --model {{root}}/models/gains_unknown.yaml {CPU}",
        r"gains_unknown\.yaml: gains: unknown preset 'stiff'; choose one of .*polymetis"),
    cli("model-joint-physics-unknown", f"sysid compare {{root}}/good --model {{root}}/models/joint_physics_unknown.yaml {CPU}",
        r"joint_physics: unknown preset 'sticky'; choose one of none, realm"),
    cli("model-version-9", f"sysid compare {{root}}/good --model {{root}}/models/version_9.yaml {CPU}", r"format version 9 not supported"),
    cli("model-binary-file", f"sysid compare {{root}}/good --model {{root}}/models/binary.yaml {CPU}", r"binary\.yaml: not a text \(YAML\) file"),
    cli("model-missing", f"sysid compare {{root}}/good --model {{root}}/models/nope.yaml {CPU}", r"--model: robot model .*nope\.yaml not found"),
    cli("model-is-directory", f"sysid compare {{root}}/good --model {{root}}/models {CPU}", r"--model: robot model .*models not found \(it is a directory\)"),
    # ------------------------------------------------------------------------ synth
    cli("synth-duration-half-second", "sysid synth --hidden none --out {root}/s1 --duration 0.5", r"duration_s \(--duration\): 0\.5 s is too short"),
    cli("synth-duration-neg", "sysid synth --hidden none --out {root}/s2 --duration -3", r"argument --duration: must be > 0 s, got -3"),
    cli("synth-duration-nan", "sysid synth --hidden none --out {root}/s3 --duration nan", r"argument --duration: must be a finite"),
    cli("synth-hidden-unknown", "sysid synth --hidden magic --out {root}/s4", r"--hidden: unknown effect 'magic'"),
    cli("synth-hidden-value-text", "sysid synth --hidden coulomb_friction:fc=abc --out {root}/s5", r"--hidden: fc='abc': expected a number"),
    cli("synth-hidden-value-nan", "sysid synth --hidden coulomb_friction:fc=nan --out {root}/s5", r"--hidden: fc='nan': expected a finite number"),
    cli("synth-hidden-out-of-bounds", "sysid synth --hidden coulomb_friction:fc=99 --out {root}/s6", r"--hidden: coulomb_friction\.fc1 = 99 N·m is outside its bounds"),
    cli("synth-hidden-twice", "sysid synth --hidden latency,latency --out {root}/s6", r"--hidden: effect 'latency' given twice"),
    cli("synth-rate-below-control", "sysid synth --hidden none --out {root}/s7 --rate 10", r"--rate 10 Hz is below the control rate --control-hz 15 Hz"),
    cli("synth-noise-neg", "sysid synth --hidden none --out {root}/s8 --noise -1", r"argument --noise: must be >= 0 rad"),
    cli("synth-n-train-0", "sysid synth --hidden none --out {root}/s9 --n-train 0", r"argument --n-train: must be >= 1"),
    cli("synth-seed-neg", "sysid synth --hidden none --out {root}/s9 --seed -1", r"argument --seed: must be >= 0"),
    cli("synth-out-is-file", "sysid synth --hidden none --out {root}/a_file.txt", r"--out: .*a_file\.txt exists and is a file"),
    # ------------------------------------------------------------------------ excite
    cli("excite-max-velocity-neg", "sysid excite --out {root}/e1 --max-velocity -1", r"argument --max-velocity: must be > 0 rad/s"),
    cli("excite-max-velocity-0", "sysid excite --out {root}/e1 --max-velocity 0", r"argument --max-velocity: must be > 0 rad/s"),
    cli("excite-control-hz-0", "sysid excite --out {root}/e1 --control-hz 0", r"argument --control-hz: must be > 0 Hz"),
    cli("excite-duration-short", "sysid excite --out {root}/e1 --duration 0.5", r"--duration must be > 1 s, got 0\.5"),
    cli("excite-n-0", "sysid excite --out {root}/e1 --n 0", r"argument --n: must be >= 1"),
    cli("excite-out-under-file", "sysid excite --out {root}/a_file.txt/sub", r"--out: cannot create .*a_file\.txt is a file"),
    # ------------------------------------------------------------------------ fit / diagnose / report
    cli("fit-popsize-1", "sysid fit {root}/good --add latency --out {root}/m.yaml --popsize 1", r"argument --popsize: must be >= 2"),
    cli("fit-generations-0", "sysid fit {root}/good --add latency --out {root}/m.yaml --generations 0", r"argument --generations: must be >= 1"),
    cli("auto-search-negative", "sysid auto {root}/good --search-s -5", r"argument --search-s: .*>= 0"),
    cli("fit-out-is-directory", f"sysid fit {{root}}/good --add latency --out {{root}}/out_dir {CPU}", r"--out: .*out_dir is a directory; give a file path"),
    cli("fit-json-is-directory", f"sysid fit {{root}}/good --add latency --out {{root}}/m.yaml --json {{root}}/out_dir {CPU}", r"--json: .*out_dir is a directory"),
    cli("fit-add-unknown", f"sysid fit {{root}}/good --add magic --out {{root}}/m.yaml {CPU}", r"--add: unknown effect 'magic'"),
    cli("fit-add-param-without-effect", f"sysid fit {{root}}/good --add fc=0.3 --out {{root}}/m.yaml {CPU}", r"--add: 'fc=0\.3': a parameter needs an effect before it"),
    cli("fit-add-gripper-effect", f"sysid fit {{root}}/good --add gripper_response --out {{root}}/m.yaml {CPU}",
        r"--add\): gripper_response acts on the gripper, which the arm replay does not simulate"),
    cli("diagnose-gripper-candidate", f"sysid diagnose {{root}}/good --candidates latency,gripper_response {CPU}",
        r"--candidates\): gripper_response acts on the gripper"),
    cli("diagnose-top-0", "sysid diagnose {root}/good --top 0", r"argument --top: must be >= 1"),
    cli("diagnose-seed-neg", "sysid diagnose {root}/good --seed -2", r"argument --seed: must be >= 0"),
    cli("diagnose-unknown-candidate", f"sysid diagnose {{root}}/good --candidates latency,magic {CPU}",
        r"--candidates: unknown effect 'magic'; known: coulomb_friction"),
    cli("diagnose-npy-file", f"sysid diagnose {{root}}/npy_as_npz.npz {CPU}", r"not an \.npz archive"),
    cli("diagnose-one-trajectory", f"sysid diagnose {{root}}/one {CPU}", r"one trajectory of .* s; a single log is cut into blocks of >= 10 s .* needs >= 20 s.* --heldout DIR"),
    cli("report-out-is-directory", f"sysid report {{root}}/good --out {{root}}/out_dir {CPU}", r"--out: .*out_dir is a directory"),
    cli("report-diagnosis-not-json", f"sysid report {{root}}/good --out {{root}}/r.html --diagnosis {{root}}/diag_bad.json {CPU}", r"diag_bad\.json: not valid JSON"),
    cli("report-fit-wrong-json", f"sysid report {{root}}/good --out {{root}}/r.html --fit {{root}}/diag_other.json {CPU}", r"diag_other\.json: not a `fit --json` output"),
    # ------------------------------------------------------------------------ realm assets
    cli("assets-timeout-0", "assets build --source procedural --timeout 0 --out {root}/cat", r"argument --timeout: must be > 0 s"),
    cli("assets-timeout-neg", "assets build --source procedural --timeout -5 --out {root}/cat", r"argument --timeout: must be > 0 s"),
    cli("assets-workers-0", "assets build --source procedural --workers 0 --out {root}/cat", r"argument --workers: must be >= 1"),
    cli("assets-variants-0", "assets build --source procedural --variants 0 --out {root}/cat", r"argument --variants: must be >= 1"),
    cli("assets-coacd-budget-nan", "assets build --source procedural --coacd-budget nan --out {root}/cat", r"argument --coacd-budget: must be a finite"),
    cli("assets-unknown-source", "assets build --source nonsense --out {root}/cat", r"unknown source 'nonsense'; known: .*maniskill"),
    cli("assets-no-source", "assets build --out {root}/cat", r"give --source SRC \(repeatable\) or --all"),
    cli("assets-out-is-file", "assets build --source procedural --out {root}/a_file.txt", r"--out: .*a_file\.txt exists and is a file"),
    cli("assets-stats-no-catalog", "assets stats {root}/no_data --no-sheet", r"no catalog at .*no_data"),
    # ------------------------------------------------------------------------ top level
    cli("unknown-command", "nope", r"argument COMMAND: invalid choice: 'nope'"),
    cli("export-gripper-labels-nope", "export --tasks all --episodes 1 --out {root}/ex --gripper-labels intent",
        r"argument --gripper-labels: invalid choice: 'intent'"),
    cli("export-shader-nope", "export --tasks all --episodes 1 --out {root}/ex --shader nope", r"argument --shader: invalid choice: 'nope'"),
    cli("demo-max-steps-0", "demo --max-steps 0 --tasks REALM-PickApple-v1 --out {root}/demo --no-video", r"argument --max-steps: must be >= 1"),
    cli("demo-episodes-0", "demo --episodes 0 --out {root}/demo --no-video", r"argument --episodes: must be >= 1"),
    cli("eval-episodes-0", "eval --policy zero --episodes 0 --tasks REALM-PickApple-v1 --perturbations Default --out {root}/ev --workers 1",
        r"--episodes must be >= 1"),
    cli("eval-max-steps-neg", "eval --policy zero --episodes 1 --max-steps -5 --tasks REALM-PickApple-v1 --perturbations Default --out {root}/ev --workers 1",
        r"--max-steps must be >= 1"),
    cli("eval-workers-0", "eval --policy zero --episodes 1 --workers 0 --tasks REALM-PickApple-v1 --out {root}/ev", r"argument --workers: must be >= 1"),
    cli("eval-unknown-policy", "eval --policy nope --episodes 1 --out {root}/ev", r"unknown policy 'nope'; known: .*zero"),
    cli("eval-camera-size-text", "eval --policy zero --camera-size big --out {root}/ev", r"--camera-size must be WxH"),
    cli("validate-missing-csv", "validate {root}/nope.csv", r"no such file: .*nope\.csv"),
    cli("export-episodes-neg", "export --tasks all --episodes -1 --out {root}/ex", r"--episodes must be >= 1"),
    cli("render-seed-neg", "render sheet --out {root}/r.png --seed -1", r"argument --seed: must be >= 0"),
    cli("version", "--version", accepted="prints `realm-ms VERSION`, exit code 0"),
    cli("sysid-effects-json", "sysid effects --json", accepted="the effect library as JSON, exit code 0"),
    cli("compare-segment-0-subprocess", f"sysid compare {{root}}/good --segment 0 {CPU}", r"argument --segment: must be > 0 s", subprocess=True),
    cli("compare-missing-data-subprocess", f"sysid compare {{root}}/nowhere {CPU}", r"DATA .*nowhere.* does not exist", subprocess=True),
    cli("assets-timeout-0-subprocess", "assets build --source procedural --timeout 0", r"argument --timeout: must be > 0 s", subprocess=True),
]


# ---------------------------------------------------------------------------- Python API / files
def _load_dir(name):
    def call(root):
        from realm_ms.sysid.data_io import load_dir

        return load_dir(root / name)

    return call


def _robot_model(data):
    def call(root):
        from realm_ms.agents.robot_model import RobotModel

        return RobotModel.from_dict(data, "MODEL.yaml")

    return call


def _check_synth_layout(trajs):
    assert len(trajs) == 3


def _check_no_timestamp(trajs):
    import numpy as np

    assert len(trajs) == 2 and np.allclose(trajs[0].t[:3], [0, 1 / 15, 2 / 15])


def _check_names_only(model):
    assert model.names == ["coulomb_friction"] and model.effects[0].is_off()


def _check_gripper(trajs):
    assert len(trajs) == 2 and trajs[0].gripper is not None and trajs[0].control_hz == 15.0


def _duplicate_mesh_ids(root):
    import shutil

    from asset_pipeline.build import enumerate_items
    from asset_pipeline.config import BuildConfig

    d = root / "meshes_same_id"
    d.mkdir(exist_ok=True)
    import trimesh

    box = trimesh.creation.box((0.05, 0.05, 0.05))
    box.export(d / "a b.obj")
    shutil.copy(d / "a b.obj", d / "a_b.obj")
    items, _ = enumerate_items([str(d), str(d)], BuildConfig())  # the folder twice: duplicates are one
    return items


def _check_duplicate_ids(items):
    ids = sorted(i.id for i in items)
    assert len(ids) == 2 and len(set(ids)) == 2 and ids[0] == "user/a_b", ids


def _api(fn_name, **kw):
    def call(root):
        from realm_ms.sysid import api

        kw2 = {k: (str(v).format(root=root) if isinstance(v, str) else v) for k, v in kw.items()}
        return getattr(api, fn_name)(**kw2)

    return call


def _segment_set(**kw):
    def call(root):
        from realm_ms.sysid.data_io import load_dir
        from realm_ms.sysid.replay import SegmentSet

        return SegmentSet.build(load_dir(root / "good"), **kw)

    return call


def _excite_config(**kw):
    def call(root):
        from realm_ms.sysid.excite import ExciteConfig

        return ExciteConfig(**kw)

    return call


def _build_config(**kw):
    def call(root):
        from asset_pipeline.config import BuildConfig

        return BuildConfig(**kw)

    return call


def _robot_model_ctor(**kw):
    def call(root):
        from realm_ms.agents.robot_model import RobotModel

        return RobotModel(**kw)

    return call


CASES += [
    Case("api-compare-accepts-synth-layout", call=_load_dir("synth_layout"), check=_check_synth_layout,
         accepted="DATA with train/ + heldout/ (synth's layout) is read whole by compare"),
    Case("api-lerobot-without-timestamp", call=_load_dir("lr_no_timestamp"), check=_check_no_timestamp,
         accepted="no `timestamp` column: t = frame_index / fps"),
    Case("api-lerobot-good", call=_load_dir("lr_good"), check=_check_gripper,
         accepted="8-dim state/action: 7 joints + gripper; control_hz = fps"),
    Case("api-model-effect-names-only", call=_robot_model({"effects": ["coulomb_friction"]}), check=_check_names_only,
         accepted="an effect given by name only is added switched off (parameters at their off-values)"),
    Case("api-model-physics-hz-neg", call=_robot_model({"physics_hz": -120}), error=r"MODEL\.yaml: physics_hz: must be a positive"),
    Case("api-model-effects-string", call=_robot_model({"effects": "coulomb_friction"}), error=r"MODEL\.yaml: effects: expected a list"),
    Case("api-model-misspelt-effects-key", call=_robot_model({"effect": ["latency"]}),
         error=r"MODEL\.yaml: unknown key 'effect' \(did you mean 'effects'\?\)"),
    Case("api-model-misspelt-params-key", call=_robot_model({"effects": [{"name": "latency", "parms": {"delay": 0.1}}]}),
         error=r"MODEL\.yaml: effects\[0\]: unknown key 'parms' \(did you mean 'params'\?\)"),
    Case("api-robot-model-physics-hz-0", call=_robot_model_ctor(physics_hz=0), error=r"physics_hz: must be a positive"),
    Case("api-synth-duration-short", call=_api("synth", hidden="none", out="{root}/api_s", duration_s=0.5),
         error=r"duration_s \(--duration\): 0\.5 s is too short"),
    Case("api-synth-rate-nan", call=_api("synth", hidden="none", out="{root}/api_s", rate_hz=float("nan")),
         error=r"rate_hz \(--rate\): must be a finite number"),
    Case("api-fit-popsize-1", call=_api("fit", data="{root}/good", add="latency", popsize=1), error=r"popsize \(--popsize\): must be >= 2"),
    Case("api-fit-out-dir", call=_api("fit", data="{root}/good", add="latency", out="{root}/out_dir"), error=r"out \(--out\): .*out_dir is a directory"),
    Case("api-compare-workers-0", call=_api("compare", data="{root}/good", workers=0, device="cpu"), error=r"workers \(--workers\): must be >= 1"),
    Case("api-compare-segment-0", call=_api("compare", data="{root}/good", segment_s=0, device="cpu", workers=1),
         error=r"segment_s \(--segment\): must be > 0 s"),
    Case("api-segments-length-0-no-hang", call=_segment_set(length_s=0.0), error=r"segment length \(--segment\): must be > 0 s"),
    Case("api-segments-length-nan", call=_segment_set(length_s=float("nan")), error=r"segment length \(--segment\): must be a finite"),
    Case("api-segments-physics-hz-neg", call=_segment_set(physics_hz=-120.0), error=r"physics_hz: must be > 0 Hz"),
    Case("api-excite-max-velocity-neg", call=_excite_config(max_velocity=-1.0), error=r"max_velocity \(--max-velocity\): must be > 0 rad/s"),
    Case("api-excite-control-hz-0", call=_excite_config(control_hz=0.0), error=r"control_hz \(--control-hz\): must be > 0 Hz"),
    Case("assets-timeout-0-config", call=_build_config(object_timeout_s=0), error=r"object_timeout_s must be a positive number of seconds"),
    Case("assets-two-meshes-same-id", call=_duplicate_mesh_ids, check=_check_duplicate_ids,
         accepted="`a b.obj` and `a_b.obj` both slug to user/a_b: the second gets the id plus a short hash of its path"),
]


# ---------------------------------------------------------------------------- REALM envs (lead's side)
def _env_id() -> str:
    import gymnasium as gym

    import realm_ms  # noqa: F401

    return sorted(k for k in gym.registry if k.startswith("REALM-PickApple-v"))[-1]


def _make(**kw):
    def call(root):
        import gymnasium as gym

        import realm_ms  # noqa: F401

        env = gym.make(_env_id(), obs_mode="state", **kw)
        env.close()
        return env

    return call


def _step(action_fn):
    def call(root):
        import gymnasium as gym

        import realm_ms  # noqa: F401

        env = gym.make(_env_id(), obs_mode="state")
        try:
            env.reset(seed=0)
            return env.step(action_fn())
        finally:
            env.close()

    return call


def _home_action(**changes):
    import numpy as np

    a = np.array([0.0, -np.pi / 5, 0.0, -4 * np.pi / 5, 0.0, 3 * np.pi / 5, 0.0, 0.0], dtype=np.float32)
    for i, v in changes.items():
        a[int(i[1:])] = v
    return a


CASES += [
    Case("env-camera-width-0", call=_make(camera_width=0), error=r"camera_width", env=True),
    Case("env-camera-width-neg", call=_make(camera_width=-64), error=r"camera_width", env=True),
    Case("env-robot-model-physics-hz-0", call=_make(robot_model={"physics_hz": 0}), error=r"physics_hz: must be a positive", env=True),
    Case("env-robot-model-effects-string", call=_make(robot_model={"effects": "latency"}), error=r"effects: expected a list", env=True),
    Case("env-unknown-perturbation", call=_make(perturbation="NoSuchPerturbation"), error=r"unknown perturbation 'NoSuchPerturbation'", env=True),
    Case("env-action-inf", call=_step(lambda: _home_action(j0=float("inf"))), error=r"action", env=True, warn_ok=True),
    Case("env-action-100-rad", call=_step(lambda: _home_action(j3=100.0)), error=r"action|joint|limit", env=True, warn_ok=True),
    Case("env-action-gripper-5", call=_step(lambda: _home_action(j7=5.0)), error=r"gripper", env=True, warn_ok=True),
    Case("env-action-python-list", call=_step(lambda: _home_action().tolist()), env=True,
         accepted="a Python list of 8 numbers is an action like the same numpy array"),
    Case("env-action-wrong-shape", call=_step(lambda: _home_action()[:7]), error=r"action.*(shape|8)", env=True),
]
