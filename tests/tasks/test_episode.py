"""The episode engine's rules on a small stand-in env (the real envs run through it in the eval,
export and expert tests): chunks, stopping rules per slot, sparse capture, hooks, partial resets."""

from types import SimpleNamespace

import numpy as np
import torch

from realm_ms.tasks.episode import Episode, EpisodeEngine
from realm_ms.tasks.progression import Stage


class Env:
    """``num_envs`` rows; row i succeeds at step ``goal[i]`` of its episode and terminates one step later."""

    def __init__(self, num_envs=1, goal=(3,)):
        self.num_envs, self.goal, self.device, self.unwrapped = num_envs, list(goal), torch.device("cpu"), self
        self.tracker = SimpleNamespace(stages=[Stage.REACH, Stage.GRASP])
        self.perturbations = SimpleNamespace(needs_reconfigure=False)
        self.agent = SimpleNamespace(droid_state=lambda: torch.zeros(num_envs, 8))
        self.t = torch.zeros(num_envs, dtype=torch.long)
        self.capture_sensors, self.captures, self.resets, self.actions = True, [], [], []

    def reset(self, seed=None, options=None):
        rows = [int(i) for i in (options or {}).get("env_idx", range(self.num_envs))]
        self.resets.append((seed, rows))
        self.t[rows] = 0
        return {"t": self.t.clone()}, {"perturbation": {"name": "Default", "params": [{}] * self.num_envs}}

    def step(self, action):
        self.actions.append(action.clone())
        self.captures.append(self.capture_sensors)
        self.t += 1
        goal = torch.as_tensor(self.goal)
        success = self.t >= goal
        info = {"progression": success.float() * 0.5 + 0.5, "success": success, "stage_reach": self.t >= 1, "stage_grasp": success}
        return {"t": self.t.clone()}, None, self.t > goal, torch.zeros(self.num_envs, dtype=torch.bool), info

    def get_language_instruction(self):
        return ["do it"] * self.num_envs

    def stalled_stage(self):
        return ["DONE" if int(t) >= g else "GRASP" for t, g in zip(self.t, self.goal)]


def test_chunks_run_open_loop_with_sparse_capture_and_stop_on_termination():
    env = Env(goal=(3,))
    seen = []
    engine = EpisodeEngine(env, before_step=lambda obs: seen.append(int(obs["t"][0])), after_step=lambda s: seen.append(s.ended))
    ep = Episode(seed=5, max_steps=100)
    engine.reset({0: ep})
    assert env.resets == [(5, [0])] and ep.instruction == "do it" and ep.stages == ["REACH", "GRASP"]
    assert engine.run(8, {0: np.ones((3, 8))}) == []  # a chunk of 3: three steps, camera only at the last
    assert env.captures == [False, False, True] and ep.steps == 3 and ep.success and not ep.done
    assert seen == [0, [], 1, [], 2, []]  # before: the obs the action is chosen from; after: rows that ended
    assert engine.run(8, {0: np.ones((8, 8))}) == [0]  # terminates one step after success
    assert ep.done and ep.steps == 4 and ep.stalled == "DONE" and ep.latched == {"REACH": 1, "GRASP": 3}
    assert ep.rises == [1, 3] and ep.best == 1.0 and env.captures[3:] == [False]


def test_max_steps_and_the_end_of_an_actors_script_stop_an_episode():
    class Actor:
        def __init__(self):
            self.done, self.calls, self.resets = [False], 0, 0

        def reset(self):
            self.resets += 1

        def act(self, obs):
            self.calls += 1
            self.done = [self.calls >= 2]
            return torch.zeros(1, 8)

    env, actor = Env(goal=(50,)), Actor()
    engine = EpisodeEngine(env, actor=actor)
    ep = Episode(seed=0, max_steps=10)
    engine.reset({0: ep})
    assert actor.resets == 1 and engine.run(10) == [0] and ep.steps == 2 and ep.stalled == "GRASP"
    assert env.captures == [True, True]  # an actor reads every observation
    ep = Episode(seed=1, max_steps=3)
    actor.calls = -100
    engine.reset({0: ep})
    assert engine.run(10) == [0] and ep.steps == 3 and not ep.success  # max_steps


def test_rows_hold_after_their_episode_and_restart_with_a_partial_reset():
    env = Env(num_envs=2, goal=(1, 5))
    engine = EpisodeEngine(env)
    a, b = Episode(seed=10, max_steps=20), Episode(seed=11, max_steps=20)
    engine.reset({0: a, 1: b})
    chunk = {r: np.full((4, 8), r + 1.0) for r in (0, 1)}
    assert engine.run(4, chunk) == [0] and a.steps == 2 and b.steps == 4
    assert torch.equal(env.actions[3][0], env.actions[1][0]) and float(env.actions[3][1, 0]) == 2.0  # row 0 holds
    c = Episode(seed=12, max_steps=20)
    engine.reset({0: c})  # only row 0: ManiSkill's partial reset, every row's seed in the list
    assert env.resets[-1] == ([12, 11], [0]) and engine.episodes == [c, b]
