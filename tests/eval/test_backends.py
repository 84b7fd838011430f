"""Execution backends: one declared protocol, control signals as types, one record schema, one Ray connection."""

from __future__ import annotations

from pathlib import Path

import pytest

from realm_ms.eval.backends.base import Backend, Failed, Unsupported
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.runner import RunConfig, error_record, run_plan, unsupported_record

ROOT = Path(__file__).resolve().parents[2]


def test_the_protocol_is_declared_and_every_backend_implements_it():
    from realm_ms.eval.backends.batched import BatchedBackend
    from realm_ms.eval.backends.inline import InlineBackend
    from realm_ms.eval.backends.processes import ProcessBackend

    assert Backend.__abstractmethods__ == {"cell", "start", "step", "abort"}

    class Half(Backend):
        def cell(self, slot):
            return None

    with pytest.raises(TypeError, match="abstract"):
        Half()
    for cls in (InlineBackend, ProcessBackend, BatchedBackend):
        assert issubclass(cls, Backend) and not cls.__abstractmethods__


def test_ray_init_is_called_in_one_place():
    calls = [(p.relative_to(ROOT), n) for p in (ROOT / "realm_ms").rglob("*.py")
             for n, line in enumerate(p.read_text().splitlines(), 1) if "ray.init(" in line]
    assert [str(p) for p, _ in calls] == ["realm_ms/eval/backends/ray.py"], calls


def test_error_and_unsupported_records_have_the_episode_records_fields():
    """Every record a backend writes for a key starts with the same fields (what rebuilds its env)."""
    cfg, key = RunConfig(policy="zero"), EpisodeKey("REALM-PickApple-v1", "V-AUG", 3)
    err = error_record(cfg, key, "worker process died (exit code -9)", "Traceback ...\n" + "x" * 5000)
    uns = unsupported_record(cfg, key, "not applicable")
    base = {"task", "perturbation", "seed", "policy", "action_space", "robot_model", "config"}
    assert base <= set(err) and base <= set(uns)
    assert err["status"] == "error" and err["success"] is False and err["steps"] == 0 and len(err["traceback"]) == 4000
    assert err["config"] == uns["config"] and err["config"]["perturbation"] == "V-AUG"


class _Signals(Backend):
    """Two slots: one cell is unsupported, one reset fails; neither reaches the policy."""

    n_slots = 2

    def __init__(self, cfg):
        self.cfg, self.cells = cfg, {}

    def cell(self, slot):
        return self.cells.get(slot)

    def start(self, starts):
        out = {}
        for s, k in starts.items():
            self.cells[s] = k.cell()
            out[s] = Unsupported("no such scene") if k.perturbation == "SB-NOUN" else Failed(error_record(self.cfg, k, "reset failed"))
        self.keys = dict(starts)
        return out

    def step(self, commands, delays=None):
        assert all(a is None for a in commands.values()), "an unsupported slot gets no actions"
        return {s: (None, unsupported_record(self.cfg, self.keys[s], "no such scene")) for s in commands}

    def abort(self, aborts):
        raise AssertionError("nothing to abort")


def test_the_driver_reads_control_signals_as_types():
    class NeverAsked:
        env_side = False

        def reset(self, slots):
            pass

        def act(self, batch):
            raise AssertionError("the policy must not be asked for a slot without an observation")

        def spec(self):
            return "never"

    cfg = RunConfig(policy="never")
    keys = [EpisodeKey("REALM-PickApple-v1", "SB-NOUN", 0), EpisodeKey("REALM-PickApple-v1", "Default", 0)]
    recs: list[dict] = []
    prog = run_plan(keys, NeverAsked(), _Signals(cfg), recs.append, progress_bar=False)
    assert sorted(r["status"] for r in recs) == ["error", "unsupported"] and prog.done == 2 and prog.errors == 1


def test_a_worker_that_cannot_start_its_episode_fails_that_episode_in_the_record_schema():
    """A worker process whose reset raises hands back ``Failed``: the episode's error record (with
    the worker's traceback) in the schema of every record; the worker is replaced."""
    from realm_ms.eval.backends.processes import ProcessBackend
    from realm_ms.eval.policies.baselines import ZeroPolicy

    cfg = RunConfig(policy="zero", max_steps=4, quality=False)
    be = ProcessBackend(cfg, 1)
    recs: list[dict] = []
    try:
        run_plan([EpisodeKey("REALM-NoSuchTask-v1", "Default", 0)], ZeroPolicy(), be, recs.append, progress_bar=False)
    finally:
        be.close()
    (rec,) = recs
    assert rec["status"] == "error" and "NoSuchTask" in rec["error"] and "Traceback" in rec["traceback"]
    assert rec["config"]["task"] == "REALM-NoSuchTask-v1" and rec["policy"] == "zero" and rec["seed"] == 0
