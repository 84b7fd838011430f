"""The batched backend (sub-envs of one ManiSkill env as episode slots).

On CPU physics (one sub-env per env, ``--backend batched``) its records must equal the in-process
runner's for the same seeds. GPU simulation (``num_envs > 1``) cannot run here, so its scheduling,
partial resets and per-slot bookkeeping are checked against a stand-in env with several sub-envs
that follows ManiSkill's reset/step contract."""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import torch

from realm_ms.cli import main
from realm_ms.eval.backends.batched import BatchedBackend
from realm_ms.eval.backends.inline import InlineBackend
from realm_ms.eval.policies.baselines import ZeroPolicy
from realm_ms.eval.policies.policy import ObsRequest
from realm_ms.eval.protocol import EpisodeKey, plan
from realm_ms.eval.runner import RunConfig, run_plan
from realm_ms.tasks.progression import Stage

TASKS = ["REALM-PickApple-v1", "REALM-PushSwitch-v1"]


def _records(path):
    """Records by key, without wall times (the episode's, the policy's requests'); a video as its
    file's bytes (the paths differ by run directory)."""
    out = {}
    for r in map(json.loads, path.read_text().splitlines()):
        r.pop("wall_s"), r.pop("latency_s", None)
        r["config"].pop("sim_backend")  # inline asks for "auto", batched names "physx_cpu": the same CPU physics
        if "video" in r:
            r["video"] = Path(r["video"]).read_bytes()
        out[r["task"], r["perturbation"], r["seed"]] = r
    return out


def _inline_and_batched(tmp_path, args):
    common = ["eval", *args, "--no-progress"]
    assert main([*common, "--backend", "cpu", "--workers", "1", "--out", str(tmp_path / "inline")]) == 0
    assert main([*common, "--backend", "batched", "--workers", "2", "--out", str(tmp_path / "batched")]) == 0
    return _records(tmp_path / "inline" / "records.jsonl"), _records(tmp_path / "batched" / "records.jsonl")


# zero: 2 episodes per cell, so each of the 2 slots runs several episodes and switches cells; expert: one
# episode per task is enough for the early stop after success (the long, costly episodes)
@pytest.mark.parametrize("policy,max_steps,perturbations,episodes", [("zero", "20", ["Default", "VB-POSE"], 2), ("expert", "100", ["Default"], 1)])
def test_batched_cpu_records_equal_inline(tmp_path, policy, max_steps, perturbations, episodes):
    inline, batched = _inline_and_batched(tmp_path, ["--policy", policy, "--tasks", *TASKS, "--perturbations", *perturbations,
                                                     "--episodes", str(episodes), "--max-steps", max_steps])
    # success, progression, stages, steps, quality, drawn perturbation parameters: all equal
    assert len(inline) == len(TASKS) * len(perturbations) * episodes and inline == batched
    if policy == "expert":  # the expert succeeds and the episode stops 15 steps after success, before max steps
        assert all(r["success"] and r["stalled_stage"] == "DONE" and r["steps"] < 100 for r in batched.values())


def test_batched_cpu_videos_equal_inline(tmp_path):
    inline, batched = _inline_and_batched(tmp_path, ["--policy", "zero", "--tasks", TASKS[0], "--perturbations", "Default", "--episodes", "1",
                                                     "--max-steps", "6", "--videos", "all", "--camera-size", "64x36"])
    assert len(batched) == 1 and all(r["video"] for r in batched.values()) and inline == batched  # the same frames, last step included


def test_batched_cpu_hands_the_observation_batch_to_the_policy(tmp_path):
    cfg = RunConfig(policy="zero", max_steps=10, obs=ObsRequest(cameras=("wrist", "exterior_1"), width=64, height=36), quality=False)
    seen = []

    class Recording(ZeroPolicy):
        def act(self, batch):
            seen.append(batch)
            return super().act(batch)

    be = BatchedBackend(cfg, num_envs=1, groups=1, sim_backend="physx_cpu")
    recs = []
    try:
        run_plan([EpisodeKey(TASKS[0], "Default", 7)], Recording(), be, recs.append, progress_bar=False, replan_every=8)
        assert seen and all(b.images["wrist"].shape == (1, 36, 64, 3) and b.images["wrist"].dtype == np.uint8 for b in seen)
        assert seen[-1].images["wrist"] is be.groups[0].batch.images["wrist"]  # the batch itself, no copy
        assert seen[-1].state is be.groups[0].batch.state and seen[-1].state.shape == (1, 8)
    finally:
        be.close()
    assert len(recs) == 1 and recs[0]["steps"] == 10 and recs[0]["status"] == "ok"


def test_backend_choice(monkeypatch):
    import realm_ms.eval.backends.choose as w

    cfg = RunConfig()
    monkeypatch.setattr(w, "gpu_physx_status", lambda: (False, "no CUDA device is visible"))
    be = w.choose_backend("batched", cfg, 3)
    assert isinstance(be, BatchedBackend) and be.n_slots == 3 and be.cfg.env_kwargs["sim_backend"] == "physx_cpu"
    assert isinstance(w.choose_backend("auto", cfg, 1), InlineBackend)
    with pytest.raises(RuntimeError, match="--backend gpu: no CUDA device"):
        w.choose_backend("gpu", cfg, 4)
    monkeypatch.setattr(w, "gpu_physx_status", lambda: (True, "ok"))
    be = w.choose_backend("auto", cfg, 4)  # builds no env until a slot starts
    assert isinstance(be, BatchedBackend) and len(be.groups) == 1 and be.groups[0].num_envs == 4
    assert be.cfg.env_kwargs == {"num_envs": 4, "sim_backend": "physx_cuda"}
    with pytest.raises(ValueError, match="one sub-env per env"):
        BatchedBackend(cfg, num_envs=2, sim_backend="physx_cpu")


# ---------------------------------------------------------------------------------------- num_envs > 1
TAIL = 2


def _goal(seed: int) -> int:
    """Control step at which the stand-in's episode of ``seed`` succeeds (differs between seeds)."""
    return 3 + seed % 5


class _Agent:
    def __init__(self, env):
        self.env = env

    def droid_state(self):
        return self.env.q.clone()

    @property
    def arm_qpos(self):
        return self.env.q[:, :7]

    @property
    def tcp_pose(self):
        return SimpleNamespace(p=self.env.q[:, :3])


class StandInEnv:
    """``num_envs`` sub-envs under ManiSkill's contract: ``reset(seed=list, options={"env_idx"})``
    sets every row's episode seed from the list and resets only ``env_idx`` (all rows without it;
    no partial reset when the scene is rebuilt every reset); obs and info are batched tensors.
    Row i succeeds at step ``_goal(seed_i)``, terminates ``TAIL`` steps later, truncates at the horizon;
    its instruction and camera pixels carry its seed, so a record shows which reset produced it."""

    def __init__(self, task, perturbation, cfg, num_envs, rebuilds_scene=False):
        self.num_envs, self.cfg, self.device = num_envs, cfg, torch.device("cpu")
        self.unwrapped = self
        self.task_spec = SimpleNamespace(skill="pick")
        self.tracker = SimpleNamespace(stages=[Stage.REACH, Stage.GRASP])
        self.perturbations = SimpleNamespace(needs_reconfigure=rebuilds_scene)
        self.agent = _Agent(self)
        self.q = torch.zeros(num_envs, 8)
        self.seeds = [0] * num_envs
        self.t = torch.zeros(num_envs, dtype=torch.long)
        self.success_steps = torch.zeros(num_envs, dtype=torch.long)
        self.resets: list[tuple[list[int], list[int] | None]] = []
        self.actions: list[torch.Tensor] = []

    def reset(self, seed=None, options=None):
        options = options or {}
        idx = [int(i) for i in options["env_idx"]] if "env_idx" in options else list(range(self.num_envs))
        if self.perturbations.needs_reconfigure and len(idx) != self.num_envs:
            raise RuntimeError("Cannot do a partial reset and reconfigure the environment.")
        seeds = list(seed) if isinstance(seed, list) else [seed]
        assert len(seeds) == self.num_envs or self.num_envs == 1, "ManiSkill would derive the other rows' seeds from seeds[0]"
        self.resets.append((seeds, idx if "env_idx" in options else None))
        self.seeds = seeds
        for i in idx:
            self.t[i], self.success_steps[i] = 0, 0
            self.q[i] = float(seeds[i])  # a row's state says which seed reset it
        return self._obs(), {"perturbation": dict(name="Default", names=["Default"], ids=[0], episode_seed=list(self.seeds),
                                                  instruction=self.get_language_instruction(), skill=["pick"] * self.num_envs,
                                                  params=[{} for _ in range(self.num_envs)])}

    def _obs(self):
        h, w = self.cfg.obs.height, self.cfg.obs.width
        rgb = torch.stack([torch.full((h, w, 3), s % 256, dtype=torch.uint8) for s in self.seeds])
        return {"sensor_data": {c: {"rgb": rgb} for c in self.cfg.obs.cameras}}

    def step(self, action):
        self.actions.append(action.clone())
        self.t += 1
        goals = torch.as_tensor([_goal(s) for s in self.seeds])
        success = self.t >= goals
        self.success_steps = torch.where(success, self.success_steps + 1, 0)
        info = {"progression": (self.t >= 1).float() / 2 + success.float() / 2, "success": success,
                "stage_reach": self.t >= 1, "stage_grasp": success}
        return self._obs(), info["progression"], self.success_steps > TAIL, self.t >= self.cfg.max_steps, info

    def get_language_instruction(self):
        return [f"seed {s}" for s in self.seeds]

    def stalled_stage(self):
        return ["DONE" if bool(self.t[i] >= _goal(s)) else ("GRASP" if self.t[i] >= 1 else "REACH") for i, s in enumerate(self.seeds)]

    def close(self):
        pass


def _run_stand_in(keys, num_envs, max_steps=30, rebuilds_scene=False, replan_every=4):
    cfg = RunConfig(policy="zero", max_steps=max_steps, replan_every=replan_every, success_tail=TAIL, obs=ObsRequest(cameras=("wrist",), width=4, height=2))
    envs = []

    def factory(task, perturbation, run_cfg):
        envs.append(StandInEnv(task, perturbation, run_cfg, run_cfg.env_kwargs["num_envs"], rebuilds_scene))
        return envs[-1]

    batches, zero_copy = [], []

    class Recording(ZeroPolicy):
        def act(self, batch):
            # every row sees its own episode: pixels and state carry the seed its sub-env was reset with
            seeds = [int(t.split()[1]) for t in batch.instructions]
            assert [int(v) for v in batch.images["wrist"][:, 0, 0, 0]] == [s % 256 for s in seeds]
            assert [int(v) for v in batch.state[:, 0]] == seeds
            batches.append(batch)
            zero_copy.append(batch.state is be.groups[0].batch.state and batch.images["wrist"] is be.groups[0].batch.images["wrist"])
            out = super().act(batch)
            # which call and chunk step chose an action: a finished row must hold its last one
            out.actions[..., 7] = len(batches) / 100 + np.arange(out.actions.shape[1]) / 1000
            return out

    be = BatchedBackend(cfg, num_envs=num_envs, groups=1, sim_backend="physx_cuda", env_factory=factory)
    recs = []
    try:
        run_plan(keys, Recording(), be, recs.append, progress_bar=False, replan_every=replan_every)
    finally:
        be.close()
    return recs, envs, zero_copy


def test_sub_env_slots_partial_resets_and_per_slot_bookkeeping():
    keys = plan(["REALM-A", "REALM-B"], ["Default"], 7, seed=100)  # 7 episodes per cell on 3 sub-envs
    recs, envs, zero_copy = _run_stand_in(keys, num_envs=3, max_steps=8, replan_every=2)
    assert sorted((r["task"], r["seed"]) for r in recs) == sorted((k.task, k.seed) for k in keys)
    assert len(envs) == 2  # one env per cell: a group switches cell only when all its rows are free
    for r in recs:
        goal = _goal(r["seed"])
        assert r["instruction"] == f"seed {r['seed']}" and r["perturbation_params"]["episode_seed"] == [r["seed"]]
        if goal + TAIL <= 8:  # early stop TAIL steps after success
            assert r["success"] and r["steps"] == goal + TAIL and r["stalled_stage"] == "DONE"
            assert r["stages"] == {"REACH": 1, "GRASP": goal} and r["progression"] == 1.0 and r["progression_timestamps"] == [1, goal]
        else:  # max steps
            assert r["steps"] == 8 and r["success"] and r["stages"]["REACH"] == 1
        assert r["quality"]["joint_path_length"] == 0.0 and r["quality"]["collisions_self"] is None
    partial = [(seeds, idx) for e in envs for seeds, idx in e.resets if idx is not None]
    assert partial, "episodes of different lengths must restart their own sub-envs only"
    for seeds, idx in partial:
        assert len(idx) < 3 and len(seeds) == 3
    for e in envs:  # the rows that run on keep their episode seeds in the list ManiSkill resets every row's seed from
        for (prev, _), (seeds, idx) in zip(e.resets, e.resets[1:]):
            assert idx is None or all(seeds[r] == prev[r] for r in range(3) if r not in idx)
    assert any(zero_copy) and not all(zero_copy)  # the batch itself when all rows come from one step, else stacked


def test_rows_of_a_finished_slot_hold_and_whole_batch_waves():
    keys = plan(["REALM-A"], ["Default"], 5, seed=0)
    recs, envs, _ = _run_stand_in(keys, num_envs=3, max_steps=30, rebuilds_scene=True)
    assert sorted(r["seed"] for r in recs) == list(range(5))
    (env,) = envs
    assert [idx for _, idx in env.resets] == [None, None]  # waves of 3 then 2 episodes, no partial reset
    assert env.resets[1][0] == [3, 4, 3]  # the idle third row reuses a started row's seed
    assert all(r["steps"] == _goal(r["seed"]) + TAIL for r in recs)
    # wave 1: seed 0 ends at step 5, inside the second 4-step chunk; seeds 1 and 2 run on to steps 6 and 7
    assert all(torch.equal(env.actions[k][0], env.actions[4][0]) for k in (5, 6)) and not torch.equal(env.actions[5][2], env.actions[4][2])
    # wave 2: seed 3 ends at step 8 (end of a 4-step chunk), seed 4 runs one step more
    last, before = env.actions[-1], env.actions[-2]
    assert torch.equal(last[0], before[0]) and last[1, 7] > before[1, 7]  # the finished row holds, the other got a new chunk
    wave2 = env.actions[-9:]
    assert all(torch.equal(a[2], torch.full((8,), 3.0)) for a in wave2)  # the idle row holds its reset state


def test_one_slot_runner_and_sub_env_slots_give_the_same_records():
    """``EpisodeRunner`` (the engine's one-slot case) and three sub-envs of one batched env run the
    same keys to the same records (but for wall time and the env config's ``num_envs``)."""
    from realm_ms.eval.slots import EpisodeRunner

    cfg = RunConfig(policy="zero", max_steps=8, replan_every=3, success_tail=TAIL, quality=False, obs=ObsRequest(cameras=("wrist",), width=4, height=2))

    def factory(task, perturbation, run_cfg):
        return StandInEnv(task, perturbation, run_cfg, run_cfg.env_kwargs.get("num_envs", 1))

    def run(backend):
        recs = []
        try:
            run_plan(plan(["REALM-A", "REALM-B"], ["Default"], 4, seed=20), ZeroPolicy(), backend, recs.append, progress_bar=False, replan_every=3)
        finally:
            backend.close()
        for r in recs:
            r.pop("wall_s"), r.pop("latency_s", None)
            r["config"].pop("num_envs", None), r["config"].pop("sim_backend", None)
        return {(r["task"], r["seed"]): r for r in recs}

    inline = InlineBackend(cfg, 1)
    inline.runners = [EpisodeRunner(cfg, env_factory=factory)]
    one, batched = run(inline), run(BatchedBackend(cfg, num_envs=3, sim_backend="physx_cuda", env_factory=factory))
    assert len(one) == 8 and one == batched
    assert {r["steps"] for r in one.values()} == {min(_goal(s) + TAIL, 8) for s in range(20, 24)}


def test_policy_errors_fail_their_slot_and_unsupported_cells_are_recorded():
    from realm_ms.eval.policies.policy import PolicyOutput

    cfg = RunConfig(policy="zero", max_steps=8, replan_every=2, success_tail=TAIL, obs=ObsRequest(cameras=("wrist",), width=4, height=2))

    def factory(task, perturbation, run_cfg):
        if task == "REALM-B":
            raise NotImplementedError("REALM-B: perturbation not applicable")
        return StandInEnv(task, perturbation, run_cfg, run_cfg.env_kwargs["num_envs"])

    class FailsOddSeeds(ZeroPolicy):  # a server that cannot serve some rows: those episodes fail, not the run
        def act(self, batch):
            out = super().act(batch)
            return PolicyOutput(out.actions, [("down" if int(t.split()[1]) % 2 else None) for t in batch.instructions])

    keys = plan(["REALM-A", "REALM-B"], ["Default"], 4, seed=10)
    be = BatchedBackend(cfg, num_envs=3, sim_backend="physx_cuda", env_factory=factory)
    recs = []
    try:
        run_plan(keys, FailsOddSeeds(), be, recs.append, progress_bar=False, replan_every=2)
    finally:
        be.close()
    by = {(r["task"], r["seed"]): r for r in recs}
    assert len(recs) == 8 and set(by) == {(k.task, k.seed) for k in keys}
    for s in range(10, 14):
        a, b = by["REALM-A", s], by["REALM-B", s]
        assert b["status"] == "unsupported" and "not applicable" in b["error"]
        if s % 2:
            assert a["status"] == "error" and a["error"] == "down" and a["steps"] == 0 and a["instruction"] == f"seed {s}"
        else:
            assert a["status"] == "ok" and a["steps"] == _goal(s) + TAIL


def test_gpu_probe_reports_a_missing_physx_library_without_fetching_it(monkeypatch, tmp_path):
    import sapien

    import realm_ms.eval.backends.choose as w

    def no_fetch(*a, **k):
        raise AssertionError("the probe must not start SAPIEN's download")

    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(w, "gpu_physx_library", lambda: tmp_path / "libPhysXGpu_64.so")
    monkeypatch.setattr(sapien.physx, "PhysxGpuSystem", no_fetch)
    ok, why = w.gpu_physx_status()
    assert not ok and "not installed" in why and "sapien.physx.enable_gpu()" in why
    with pytest.raises(RuntimeError, match="--backend gpu: SAPIEN's GPU PhysX library is not installed"):
        w.choose_backend("gpu", RunConfig(), 2)
    assert isinstance(w.choose_backend("auto", RunConfig(), 1), InlineBackend)
