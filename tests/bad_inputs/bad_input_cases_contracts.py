"""Bad-input corpus, contracts between parts: DROID action spaces x policies x control modes, robot
model files (settings, duplicates, units, physics rate) as the loader and `fit` see them, sysid data
at the wrong rate or with nothing to identify, and the train-eval recipe's flags.

``make_files(root)`` writes the files these cases name (``{root}/contracts/...``). Cases follow
``bad_input_cases.py``: an ``error`` regex for the one line, or ``accepted`` with its meaning.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np

from bad_input_cases import Case, cli
from bad_input_cases_runs import _make
from bad_input_files import HOME, npz_dir

CPU = "--device cpu --workers 1"
C = "{root}/contracts"
TASK = "REALM-PickApple-v1"
BAD = "contracts"


# ---------------------------------------------------------------------------- files
def _torque_dir(root: Path, name: str, rate: float, change=None, n: int = 3) -> None:
    d = root / BAD / name
    d.mkdir(parents=True, exist_ok=True)
    t = np.arange(int(3 * rate)) / rate
    for i in range(n):
        q = HOME + 0.15 * np.sin(2 * np.pi * 0.4 * t[:, None] + i)
        tau = np.random.default_rng(i).normal(0.0, 0.5, size=(len(t), 7)) + 3.0
        if change:
            tau = change(tau)
        np.savez(d / f"traj_{i}.npz", t=t, q=q, tau=tau)


def make_files(root: Path) -> None:
    (root / BAD).mkdir(exist_ok=True)
    npz_dir(root / BAD, "still", q=lambda a: HOME[None].repeat(len(a["t"]), 0),
            q_cmd=lambda a: HOME[None].repeat(len(a["t"]), 0))
    for i in (1, 2):  # every trajectory still, not only the first
        a = dict(np.load(root / BAD / "still" / "traj_000.npz"))
        np.savez(root / BAD / "still" / f"traj_{i:03d}.npz", **a)
    _torque_dir(root, "tau_1khz", 1000.0)
    _torque_dir(root, "tau_15hz", 15.0)
    _torque_dir(root, "tau_60hz", 60.0)

    def zero_col(tau):
        tau[:, 5] = 0.0
        return tau

    _torque_dir(root, "tau_zero_col", 1000.0, zero_col)
    _torque_dir(root, "tau_const", 1000.0, lambda tau: np.full_like(tau, 2.5))
    models = {
        "hz_1500000.yaml": "physics_hz: 1500000\n",  # a multiple of 15: used to hang
        "hz_30.yaml": "physics_hz: 30\n",
        "hz_2010.yaml": "physics_hz: 2010\n",
        "twice.yaml": "effects: [latency, {name: latency, params: {delay: 0.01}}]\n",
        "units_mnm.yaml": "effects: [{name: coulomb_friction, params: {fc: 250, fc3: 400}, units: {fc: mN·m}}]\n",
        "units_deg.yaml": "effects: [{name: encoder_bias, params: {bias: 0.2}, units: {bias: deg}}]\n",
        "units_unknown.yaml": "effects: [{name: coulomb_friction, params: {fc: 0.2}, units: {fc: lbf·ft}}]\n",
        "units_other_dim.yaml": "effects: [{name: coulomb_friction, params: {fc: 0.2}, units: {fc: rad}}]\n",
        "units_no_param.yaml": "effects: [{name: latency, units: {lag: s}}]\n",
        "units_list.yaml": "effects: [{name: latency, units: [s]}]\n",
        "per_joint_3.yaml": "effects: [{name: viscous_damping, params: {b: [0.1, 0.2, 0.3]}}]\n",
        "per_joint_nested.yaml": "effects: [{name: coulomb_friction, params: {fc: [[0.1, 0.2]]}}]\n",
        "scalar_list.yaml": "effects: [{name: latency, params: {delay: [0.01, 0.02]}}]\n",
        "width_list_zero.yaml": "effects: [{name: backlash, config: {torque_width: [1, 1, 1, 0, 1, 1, 1]}}]\n",
        "asym_number.yaml": "effects: [{name: coulomb_friction, config: {asymmetric: 2.5}}]\n",
    }
    for name, text in models.items():
        (root / BAD / name).write_text(text)


# ---------------------------------------------------------------------------- helpers
def _config(**kw):
    def call(root):
        from realm_ms.tasks import RealmEnvConfig

        return RealmEnvConfig(task=TASK, **kw)

    return call


def _policy_chunk(spec: str, **options):
    """One chunk of a baseline from the DROID home state, in the space ``options`` name."""
    def call(root):
        from realm_ms.eval.policies import PolicyInput, make_policy

        state = np.concatenate([HOME, [0.3]])[None].astype(np.float32)
        return make_policy(spec, **options).act(PolicyInput(state, ["pick"])).actions

    return call


def _check_chunk(dim: int, lo: float, hi: float, zero_arm: bool = False):
    def check(actions):
        assert actions.shape == (1, 8, dim), actions.shape
        assert np.all(np.isfinite(actions)) and actions.min() >= lo - 1e-6 and actions.max() <= hi + 1e-6
        if zero_arm:
            assert np.all(actions[..., :-1] == 0), actions

    return check


def _held_still(root):
    """The zero baseline under joint_velocity:position, executed: the arm stays put."""
    import gymnasium as gym
    import torch

    import realm_ms  # noqa: F401
    from realm_ms.eval.policies import PolicyInput, make_policy

    env = gym.make(TASK, obs_mode="state", action_space="joint_velocity", gripper_action_space="position")
    try:
        env.reset(seed=0)
        u = env.unwrapped
        q0 = u.agent.arm_qpos[0].double().numpy().copy()
        chunk = make_policy("zero", action_space="joint_velocity:position").act(
            PolicyInput(u.agent.droid_state().numpy().astype(np.float32), ["x"])).actions[0]
        for a in chunk:
            env.step(torch.as_tensor(a))
        return float(np.abs(u.agent.arm_qpos[0].double().numpy() - q0).max())
    finally:
        env.close()


def _check_still(moved: float) -> None:
    assert moved < 0.02, f"the zero policy moved a joint by {moved:.3f} rad"  # read as velocities: 0.74 rad of path


def _step_huge(root):
    """A finite 1e39 joint target: beyond float32, but a value outside the space, not NaN/Inf."""
    import gymnasium as gym

    import realm_ms  # noqa: F401

    env = gym.make(TASK, obs_mode="state")
    try:
        env.reset(seed=0)
        return env.step(np.concatenate([HOME, [0.0]]) + np.array([1e39, 0, 0, 0, 0, 0, 0, 0]))
    finally:
        env.close()


def _expert_under(control_mode: str):
    def call(root):
        import gymnasium as gym

        import realm_ms  # noqa: F401
        from realm_ms.expert import make_expert

        env = gym.make(TASK, obs_mode="state", control_mode=control_mode)
        try:
            env.reset(seed=0)
            return make_expert(env)
        finally:
            env.close()

    return call


def _model(name: str):
    def call(root):
        from realm_ms.agents.robot_model import RobotModel

        return RobotModel.load(root / BAD / name)

    return call


def _check_params(expected: dict):
    def check(model):
        p = model.params()
        for k, v in expected.items():
            assert abs(p[k] - v) < 1e-6, (k, p[k], v)

    return check


def _verdict_zero_floor(root):
    from realm_ms.sysid.diagnose import DiagnoseConfig, Suspect, judge_verdict
    from realm_ms.sysid.torque.space import TorqueSpace

    # torque space's judging floor: its noise (0 here: noise-free data) and its own replay floor
    return judge_verdict(0.4, 0.0, [Suspect("coulomb_friction", 0.5, 0.2, 0.2, {}, "")], DiagnoseConfig(), unit="N·m",
                         replay_floor=TorqueSpace.replay_floor(DiagnoseConfig()))


def _check_no_ratio(result) -> None:
    verdict, msg, floor = result
    assert floor == 0 and "x the floor" not in msg and "no ratio" in msg, msg


def _recipe(*argv: str):
    """The train-eval recipe's own parser, as `python examples/train_eval_loop.py ARGV` runs it: its
    one-line error (exit code 2) as a ValueError, anything else (a traceback, another code) fails."""
    def call(root):
        import importlib.util
        import sys

        path = Path(__file__).resolve().parents[2] / "examples" / "train_eval_loop.py"
        spec = importlib.util.spec_from_file_location("train_eval_loop", path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = mod
        spec.loader.exec_module(mod)
        err = io.StringIO()
        args = [a.replace("{root}", str(root)) for a in argv]
        try:
            with contextlib.redirect_stderr(err):
                return mod.parse(args)
        except SystemExit as e:
            last = err.getvalue().strip().splitlines()[-1]
            assert e.code == 2 and "Traceback" not in err.getvalue(), err.getvalue()
            raise ValueError(last) from None

    return call


def _check_quick_steps(recipe) -> None:
    assert (recipe.steps, recipe.workers) == (3, 1), recipe


# ---------------------------------------------------------------------------- cases
CASES: list[Case] = [
    # ------------------------------------------------------------------------ action spaces x control modes
    Case("space-jv-under-pd-joint-delta", call=_make(action_space="joint_velocity", control_mode="pd_joint_delta_pos"),
         error=r"action_space 'joint_velocity' is DROID's and needs control_mode='droid_joint_pos' \(got 'pd_joint_delta_pos'\)", env=True),
    Case("space-cv-under-pd-ee-delta", call=_make(action_space="cartesian_velocity", control_mode="pd_ee_delta_pose"),
         error=r"'cartesian_velocity' is DROID's and needs control_mode='droid_joint_pos'", env=True),
    Case("space-gripper-velocity-under-pd-joint-pos", call=_make(gripper_action_space="velocity", control_mode="pd_joint_pos"),
         error=r"action_space 'joint_position:velocity' is DROID's and needs control_mode", env=True),
    Case("space-config-cp-under-pd", call=_config(action_space="cartesian_position", control_mode="pd_joint_pos"),
         error=r"'cartesian_position' is DROID's and needs control_mode='droid_joint_pos'"),
    Case("space-config-default-under-pd", call=_config(control_mode="pd_joint_delta_pos"),
         accepted="joint_position with ManiSkill's own modes: no DROID conversion, the mode reads its own actions"),
    Case("space-expert-under-pd-joint-pos", call=_expert_under("pd_joint_pos"),
         error=r"the expert drives droid_joint_pos, env uses 'pd_joint_pos'", env=True),
    # ------------------------------------------------------------------------ baselines x action spaces
    Case("space-zero-joint-velocity", call=_policy_chunk("zero", action_space="joint_velocity:position"),
         check=_check_chunk(8, -1.0, 1.0, zero_arm=True), accepted="zero motion is a zero velocity (not the absolute joints)"),
    Case("space-zero-cartesian-position-velocity-gripper", call=_policy_chunk("zero", action_space="cartesian_position:velocity"),
         check=_check_chunk(7, -np.pi, np.pi), accepted="the current flange pose, gripper velocity 0"),
    Case("space-random-cartesian-velocity", call=_policy_chunk("random", action_space="cartesian_velocity"),
         check=_check_chunk(7, -1.0, 1.0), accepted="the random walk of joint targets, asked for as Cartesian velocities in [-1, 1]"),
    Case("space-random-default", call=_policy_chunk("random", action_space=None), check=_check_chunk(8, -3.1, 3.8),
         accepted="no --action-space: joint_position"),
    Case("space-zero-executed-holds-still", call=_held_still, check=_check_still, env=True,
         accepted="the zero baseline under joint_velocity:position keeps the arm within 0.02 rad over a chunk"),
    Case("space-action-1e39-is-finite", call=_step_huge, error=r"outside the action space .* are clipped", env=True, warn_ok=True),
    Case("space-zero-unknown-gripper", call=_policy_chunk("zero", action_space="joint_velocity:sideways"),
         error=r"--action-space: unknown gripper_action_space 'sideways'"),
    cli("space-eval-zero-unknown-space", f"eval --policy zero --action-space joint_vel --tasks {TASK} --episodes 1 "
        f"--max-steps 2 --workers 1 --out {C}/run_unknown_space", r"--action-space: unknown action_space 'joint_vel'"),
    cli("space-eval-random-empty-gripper", f"eval --policy random --action-space cartesian_velocity:nope --tasks {TASK} "
        f"--episodes 1 --max-steps 2 --workers 1 --out {C}/run_bad_gripper", r"unknown gripper_action_space 'nope'"),
    # ------------------------------------------------------------------------ robot model files
    cli("model-physics-hz-1500000", f"sysid compare {{root}}/good --model {C}/hz_1500000.yaml {CPU}",
        r"hz_1500000\.yaml: physics_hz: 1\.5e\+06 Hz is outside the supported 60-2000 Hz"),
    cli("model-physics-hz-30", f"sysid compare {{root}}/good --model {C}/hz_30.yaml {CPU}", r"physics_hz: 30 Hz is outside the supported"),
    Case("model-physics-hz-2010-in-env", call=_make(robot_model={"physics_hz": 2010}), error=r"physics_hz: 2010 Hz is outside", env=True),
    cli("model-effect-twice", f"sysid compare {{root}}/good --model {C}/twice.yaml {CPU}",
        r"twice\.yaml: effects\[1\]: effect 'latency' given twice \(also effects\[0\]\)"),
    Case("model-units-mnm-converted", call=_model("units_mnm.yaml"),
         check=_check_params({"coulomb_friction.fc1": 0.25, "coulomb_friction.fc3": 0.4}),
         accepted="units: {fc: mN·m} scales every fc value to N·m"),
    Case("model-units-deg-converted", call=_model("units_deg.yaml"), check=_check_params({"encoder_bias.bias1": np.deg2rad(0.2)}),
         accepted="units: {bias: deg} converts to rad"),
    cli("model-units-unknown", f"sysid compare {{root}}/good --model {C}/units_unknown.yaml {CPU}",
        r"units\.fc: 'lbf·ft' is not N·m and cannot be converted to it"),
    cli("model-units-other-dimension", f"sysid compare {{root}}/good --model {C}/units_other_dim.yaml {CPU}",
        r"units\.fc: 'rad' is not N·m"),
    cli("model-units-unknown-param", f"sysid compare {{root}}/good --model {C}/units_no_param.yaml {CPU}",
        r"units\.lag: effect 'latency' has no parameter 'lag'"),
    cli("model-units-not-mapping", f"sysid compare {{root}}/good --model {C}/units_list.yaml {CPU}", r"units: expected a mapping"),
    cli("model-per-joint-list-of-3", f"sysid compare {{root}}/good --model {C}/per_joint_3.yaml {CPU}",
        r"effects\[0\]: b: expected one number or a list of 7 \(one per joint\), got a list of 3"),
    cli("model-per-joint-nested", f"sysid compare {{root}}/good --model {C}/per_joint_nested.yaml {CPU}",
        r"fc: expected one number or a list of 7 \(one per joint\), got an array of shape \(1, 2\)"),
    Case("control-effort-limits-list-of-3", call=_make(droid_control={"effort_limits": [87, 87, 87]}),
         error=r"droid_control\.effort_limits: expected 7 finite numbers \(one per joint\), got 3", env=True),
    Case("control-gains-kq-list-of-3", call=_make(droid_control={"gains": {"kq": [40, 30, 50], "kqd": [4] * 7,
                                                                           "kx": [750] * 6, "kxd": [37] * 6}}),
         error=r"gains\.kq: expected 7 finite numbers", env=True),
    cli("model-scalar-given-list", f"sysid compare {{root}}/good --model {C}/scalar_list.yaml {CPU}", r"delay: expected a number, got a list of 2"),
    cli("model-width-list-with-zero", f"sysid compare {{root}}/good --model {C}/width_list_zero.yaml {CPU}",
        r"config\.torque_width: must be > 0 N·m"),
    cli("model-asymmetric-number", f"sysid compare {{root}}/good --model {C}/asym_number.yaml {CPU}",
        r"config\.asymmetric: expected true or false, got 2\.5"),
    # `fit` checks --add with the loader's rules before any work, so it never writes a file the loader refuses
    cli("fit-add-negative-direction-velocity", f"sysid fit {{root}}/good --add coulomb_friction:direction_velocity=-0.01 --out {C}/m1.yaml {CPU}",
        r"--add: coulomb_friction\.config\.direction_velocity: must be > 0 rad/s"),
    cli("fit-add-asymmetric-2.5", f"sysid fit {{root}}/good --add coulomb_friction:asymmetric=2.5 --out {C}/m2.yaml {CPU}",
        r"--add: coulomb_friction\.config\.asymmetric: expected true or false, got 2\.5"),
    cli("fit-add-torque-width-neg", f"sysid fit {{root}}/good --add backlash:torque_width=-1 --out {C}/m3.yaml {CPU}",
        r"--add: backlash\.config\.torque_width: expected a list of 7 numbers"),
    cli("synth-hidden-zero-width", f"sysid synth --hidden coulomb_friction:fc=0.2,direction_velocity=0 --out {C}/synth_w0",
        r"--hidden: coulomb_friction\.config\.direction_velocity: must be > 0"),
    # ------------------------------------------------------------------------ sysid data: rates, nothing to identify
    cli("data-still-diagnose", f"sysid diagnose {C}/still {CPU}", r"nothing to identify: the arm never moves"),
    cli("data-still-auto", f"sysid auto {C}/still --out {C}/auto_still.yaml {CPU}", r"nothing to identify: the arm never moves"),
    cli("data-still-fit", f"sysid fit {C}/still --add coulomb_friction --out {C}/fit_still.yaml {CPU}", r"nothing to identify"),
    cli("data-still-compare", f"sysid compare {C}/still {CPU}",
        accepted="a comparison of a still arm is a measurement, not a verdict: it runs"),
    cli("data-tau-zero-column", f"sysid diagnose {C}/tau_zero_col {CPU}",
        r"nothing to identify in torque space: tau of joint\(s\) 6 is 0 N·m throughout"),
    cli("data-tau-constant", f"sysid auto {C}/tau_const --out {C}/auto_const.yaml {CPU}",
        r"nothing to identify in torque space: tau of joint\(s\) 1, 2, 3, 4, 5, 6, 7 is 2\.5 N·m"),
    cli("data-tau-15hz", f"sysid compare {C}/tau_15hz {CPU}",
        r"logged at 15 Hz; torque-space work needs >= 100 Hz .*Nyquist limit is 7\.5 Hz"),
    cli("data-tau-60hz-diagnose", f"sysid diagnose {C}/tau_60hz {CPU}", r"logged at 60 Hz; torque-space work needs >= 100 Hz"),
    cli("data-tau-1khz-compare", f"sysid compare {C}/tau_1khz {CPU}", accepted="a 1 kHz torque log is torque-space data"),
    Case("data-zero-floor-no-ratio", call=_verdict_zero_floor, check=_check_no_ratio,
         accepted="a floor of 0 (noise-free data) is named, never divided into a 1e29x ratio"),
    # ------------------------------------------------------------------------ the train-eval recipe's flags
    Case("recipe-steps-neg", call=_recipe("--steps", "-1"), error=r"argument --steps: must be >= 1, got -1"),
    Case("recipe-steps-frac", call=_recipe("--steps", "2.5"), error=r"argument --steps: expected an integer"),
    Case("recipe-batch-size-0", call=_recipe("--batch-size", "0"), error=r"argument --batch-size: must be >= 1"),
    Case("recipe-workers-text", call=_recipe("--workers", "many"), error=r"argument --workers: expected an integer"),
    Case("recipe-loader-workers-neg", call=_recipe("--loader-workers", "-2"), error=r"argument --loader-workers: must be >= 0"),
    Case("recipe-out-is-file", call=_recipe("--out", "{root}/good/traj_000.npz"), error=r"--out: .*traj_000\.npz exists and is a file"),
    Case("recipe-out-below-file", call=_recipe("--out", "{root}/good/traj_000.npz/run"), error=r"--out: cannot create .* is a file"),
    Case("recipe-device-tpu", call=_recipe("--device", "tpu"), error=r"unknown device 'tpu'; use cpu or cuda"),
    Case("recipe-device-cuda-without-gpu", call=_recipe("--device", "cuda"), error=r"--device cuda: no CUDA GPU is available here",
         needs_no_cuda=True),
    Case("recipe-quick-steps", call=_recipe("--quick", "--steps", "3"), check=_check_quick_steps,
         accepted="--quick with an explicit --steps keeps it"),
]
