"""Kill a `realm eval` run mid-way (SIGKILL, the whole process group) and rerun the same command:
no finished episode is lost or duplicated, and the rerun completes the plan."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.exists() else []


def test_kill_and_resume(tmp_path):
    out = tmp_path / "run"
    # 20-step episodes: still far longer than the 50 ms poll below, so the kill lands mid-plan
    cmd = [sys.executable, "-m", "realm_ms.cli", "eval", "--policy", "zero", "--tasks", "REALM-PushSwitch-v1", "--perturbations", "Default",
           "--episodes", "6", "--max-steps", "20", "--workers", "1", "--no-progress", "--no-quality", "--out", str(out)]
    env = dict(os.environ, MS_SKIP_ASSET_DOWNLOAD_PROMPT="1")
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    records = out / "records.jsonl"
    deadline = time.monotonic() + 240
    try:
        while len(_lines(records)) < 2 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    before = _lines(records)
    assert 2 <= len(before) < 6, "the run must be killed mid-way"
    from realm_ms.cli import main

    assert main(cmd[3:]) == 0  # the same command again, in this process (no second interpreter start-up to pay)
    after = _lines(records)
    complete = [line for line in before if line.endswith("}")]
    assert after[: len(complete)] == complete  # finished episodes kept as written
    seeds = [json.loads(line)["seed"] for line in after]
    assert sorted(seeds) == list(range(1234, 1240))  # each episode exactly once
    assert json.loads((out / "metrics.json").read_text())["overall"]["episodes"] == 6
