"""Append-only records: a cut last line is dropped, finished keys are skipped, errors are retried."""

import json

from realm_ms.eval.protocol import EpisodeKey, factor_groups, plan
from realm_ms.eval.records import RecordWriter, read_records


def test_partial_line_is_dropped_and_finished_keys(tmp_path):
    path = tmp_path / "records.jsonl"
    w = RecordWriter(path)
    w.append(dict(task="T", perturbation="Default", seed=0, status="ok", success=True, progression=1.0))
    w.append(dict(task="T", perturbation="Default", seed=1, status="error", error="server down"))
    w.close()
    with open(path, "ab") as f:  # a kill in the middle of the next write
        f.write(b'{"task": "T", "perturbation": "Default", "se')
    w = RecordWriter(path)
    assert w.finished_keys() == {EpisodeKey("T", "Default", 0)}  # the error is retried, the cut line is gone
    w.append(dict(task="T", perturbation="Default", seed=2, status="ok", success=False, progression=0.0))
    w.close()
    recs = read_records(path)
    assert [r["seed"] for r in recs] == [0, 1, 2]
    assert all(json.loads(line) for line in path.read_text().splitlines())


def test_plan_and_factor_groups():
    keys = plan(["A", "B"], ["Default", "V-AUG"], 2, 1234)
    assert keys[:3] == [EpisodeKey("A", "Default", 1234), EpisodeKey("A", "Default", 1235), EpisodeKey("A", "V-AUG", 1234)]
    assert len(set(keys)) == 8
    assert factor_groups("VSB-NOBJ") == ("V", "S", "B") and factor_groups("Default") == () and factor_groups("S-LANG") == ("S",)
