"""The main job as a user types it: the installed ``realm`` command, several workers, exit codes.

Env registration must not depend on how a process was started: the ``realm`` console script and the
worker processes it spawns (which inherit its ``argv``) see every ``REALM-*`` id, as does a plain
``import realm_ms``.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REALM = Path(sys.executable).parent / "realm"
needs_script = pytest.mark.skipif(not REALM.exists(), reason="console script not installed (pip install -e .)")


def _records(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "records.jsonl").read_text().splitlines() if line.strip()]


def test_import_registers_every_id_whatever_argv0_is():
    from realm_ms.task_index import TASK_MODULES

    code = ("import sys; sys.argv = ['realm', 'eval']\n"
            "import realm_ms, gymnasium as gym\n"
            "print(sorted(i for i in gym.registry if i.startswith('REALM-')))\n"
            "print('mani_skill' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    ids, heavy = r.stdout.strip().splitlines()
    assert eval(ids) == sorted(TASK_MODULES)
    assert heavy == "False", "registering the ids must not import ManiSkill (realm --help stays instant)"


def test_every_task_module_is_listed():
    """TASK_MODULES is the one list of tasks: every module under realm_ms/tasks that declares a task is in it."""
    from realm_ms.task_index import TASK_MODULES

    declared = {}
    for path in (ROOT / "realm_ms" / "tasks").glob("*.py"):
        m = re.search(r'env_id="(REALM-[^"]+)"', path.read_text())
        if m and "register_task(" in path.read_text():
            declared[m.group(1)] = path.stem
    assert declared == TASK_MODULES


def test_first_make_is_wrapped_like_every_later_one():
    code = ("import realm_ms, gymnasium as gym\n"
            "a = gym.make('REALM-PickApple-v1', obs_mode='state'); b = gym.make('REALM-PickApple-v1', obs_mode='state')\n"
            "print(str(a) == str(b), a.spec.additional_wrappers == b.spec.additional_wrappers, "
            "a.unwrapped.spec.max_episode_steps == b.unwrapped.spec.max_episode_steps)\n"
            "print(str(b))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    same, wrappers = r.stdout.strip().splitlines()[-2:]
    assert same == "True True True", r.stdout
    assert "TimeLimitWrapper" in wrappers and "PickAppleEnv" in wrappers


def test_perturbations_load_whatever_was_imported_first():
    """A task module imported directly (no gymnasium placeholder, no perturbation package yet):
    an env asked for a perturbation still finds it."""
    code = ("import sys\n"
            "from realm_ms.tasks import TASKS\n"
            "assert 'realm_ms.perturbations' not in sys.modules\n"
            "import gymnasium as gym\n"
            "env = gym.make('REALM-PickApple-v1', obs_mode='state', perturbation='V-LIGHT')\n"
            "print(env.reset(seed=0)[1]['perturbation']['names'])")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip().splitlines()[-1] == "['V-LIGHT']"


@needs_script
def test_installed_realm_eval_with_two_workers_makes_every_env(tmp_path):
    run = tmp_path / "run"
    r = subprocess.run([str(REALM), "eval", "--policy", "zero", "--tasks", "REALM-PickApple-v1", "--perturbations", "Default",
                        "V-AUG", "--episodes", "1", "--max-steps", "3", "--workers", "2", "--no-progress", "--out", str(run)],
                       capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    recs = _records(run)
    assert sorted(rec["perturbation"] for rec in recs) == ["Default", "V-AUG"]
    assert all(rec["status"] == "ok" for rec in recs), [rec.get("error") for rec in recs]
    assert all(rec["steps"] == 3 for rec in recs)
    # a quiet run: none of the third-party warnings known to be harmless
    for noise in ("STL file is unsupported", "CUDA device was not found", "precision lowered"):
        assert noise not in r.stderr, noise


@pytest.mark.slow  # its messages and exit 1 are checked in-process by test_e2e's dead-openpi test
@needs_script
def test_a_run_with_an_error_record_exits_nonzero_and_says_where(tmp_path):
    import socket

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    run = tmp_path / "run"
    r = subprocess.run([str(REALM), "eval", "--policy", f"openpi:127.0.0.1:{port}", "--openpi-wait", "0.5", "--tasks",
                        "REALM-PickApple-v1", "--perturbations", "Default", "--episodes", "1", "--max-steps", "3",
                        "--workers", "1", "--out", str(run)], capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert r.returncode == 1, (r.returncode, r.stderr[-3000:])
    assert [rec["status"] for rec in _records(run)] == ["error"]
    assert "1 episode(s) ended in an error record" in r.stderr and str(run / "records.jsonl") in r.stderr
    assert "error: REALM-PickApple-v1 x Default seed 1234" in r.stderr  # shown live, as it happened
