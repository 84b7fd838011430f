"""The eval reports on hand-made run directories (no simulation): the index compares policies with
their numbers, every page states the protocol and counts error records, labels are honest, no empty
delta plot, inline videos chosen by a rule, and videos written at their own size (never stretched)."""

import base64
import io
import json
import logging
import re
import warnings

import imageio.v2 as imageio
import numpy as np
import pytest

from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.report import write_index, write_report
from realm_ms.eval.report_html import episode_label, select_videos
from realm_ms.eval.runner import RunConfig, _write_video

TASK = "REALM-PickApple-v1"


def _rec(policy, pert, seed, success, progression, stalled, status="ok", **kw):
    r = dict(task=TASK, perturbation=pert, seed=seed, policy=policy, status=status, instruction="pick up the apple", success=success,
             progression=progression, stages={"REACH": 10 if progression > 0 else None, "GRASP": None, "LIFT_LARGE": None},
             stalled_stage=stalled, steps=150, max_steps=150, replan_every=8, action_space="joint_position:position",
             code_version="realm-ms 0.1.0 (abc123)", fingerprint=dict(camera_size=[160, 90], action_space="joint_position:position"))
    r.update(kw)
    return r


def _run(tmp_path, name, records, **meta):
    d = tmp_path / name
    d.mkdir()
    m = dict(policy=records[0]["policy"], protocol="realm", tasks=[TASK], perturbations=["Default", "V-AUG"], episodes=2, seed=1234,
             max_steps=150, replan_every=8, success_tail=15)
    m.update(meta)
    (d / "run.json").write_text(json.dumps(m))
    (d / "records.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return d


def _video(d, key, n=3, size=(90, 320)):
    cfg = RunConfig(videos="failures", videos_dir=str(d / "videos"))
    return _write_video(cfg, key, [np.full((*size, 3), 40 * i, np.uint8) for i in range(n)])


def _expert_and_zero(tmp_path):
    expert = _run(tmp_path, "expert", [_rec("expert", p, s, True, 1.0, "DONE") for p in ("Default", "V-AUG") for s in (1234, 1235)])
    zero = _run(tmp_path, "zero", [_rec("zero", p, s, False, 0.0, "REACH", max_steps=60) for p in ("Default", "V-AUG") for s in (1234, 1235)]
                + [_rec("zero", "V-AUG", 1236, False, 0.0, None, status="error", error="NameNotFound: REALM-PickApple", max_steps=60)],
                max_steps=60)
    return expert, zero


def test_index_compares_both_policies_with_their_numbers_and_intervals(tmp_path):
    expert, zero = _expert_and_zero(tmp_path)
    write_report(expert, expert / "report.html")
    page = write_index([expert, zero], tmp_path / "index.html").read_text()
    assert "expert" in page and "zero" in page
    # 4 of 4 successes: Wilson 95 % [0.51, 1.00]; 0 of 4: [0.00, 0.49]
    assert "4/4 = 1.00 [0.51, 1.00]" in page and "0/4 = 0.00 [0.00, 0.49]" in page
    # per perturbation, side by side: Default 2/2 for the expert next to 0/2 for the zero policy
    row = re.search(r"<tr><td class=\"l\">V-AUG</td>(.*?)</tr>", page).group(1)
    assert row.index("2/2 = 1.00 [0.34, 1.00]") < row.index("0/2 = 0.00 [0.00, 0.66]")
    assert 'href="expert/report.html"' in page  # the run with a report is linked
    # the runs' protocols side by side: the horizon differs and is flagged, what they share is shown once
    assert re.search(r"<b>horizon</b> <span class='err'>differs</span></td><td class=l>150 control steps.*?</td><td class=l>60 control steps", page)
    assert page.count("1 task: PickApple") == 1
    assert "1 error record" in page
    assert "data:image/png;base64" in page  # the comparison figure


def test_report_header_states_protocol_and_error_count(tmp_path):
    _, zero = _expert_and_zero(tmp_path)
    page = write_report(zero, zero / "report.html").read_text()
    header = page[:page.index("<h2")]
    for text in ("1 task", "Default, V-AUG", "2 per (task, perturbation) cell", "1234 .. 1235", "60 control steps (4 s at 15 Hz)",
                 "joint_position:position (7 absolute joint targets (rad) + gripper position in [0, 1]", "re-planned every 8 steps", "160x90", "realm-ms 0.1.0 (abc123)", "1 error record"):
        assert text in header, text
    assert "<dt>robot</dt><dd>nominal</dd>" in header  # records without a robot model ran the nominal robot
    assert "NameNotFound" in page[page.index("id='errors'"):]  # and the errors are listed


def test_successful_episode_is_never_labelled_stalled(tmp_path):
    recs = [_rec("expert", "Default", 1234, True, 1.0, "DONE"), _rec("expert", "Default", 1235, False, 0.33, "GRASP")]
    for r in recs:
        r["video"] = _video(tmp_path / "run", EpisodeKey(TASK, "Default", r["seed"]))
    d = _run(tmp_path, "run_dir", recs)
    assert episode_label(recs[0]) == ("succeeded", "s") and episode_label(recs[1]) == ("stalled at GRASP", "f")
    page = write_report(d, d / "report.html", videos="all").read_text()
    assert "stalled at DONE" not in page and "DONE" not in page[page.index("Episode videos"):]
    cards = re.findall(r'<div class="vid">(.*?)</div></div>', page)
    assert len(cards) == 2 and "<video controls" in cards[0]
    assert "succeeded" in cards[0] and "seed 1234" in cards[0] and "stalled at GRASP" in cards[1]
    # the stored path does not resolve from the report's folder: found under RUN/videos/ by name
    assert 'src="../run/videos/' in cards[0]
    # the still is the episode's last frame (frames are flat grey 0, 40, 80)
    poster = re.search(r'poster="data:image/png;base64,([^"]+)"', cards[0]).group(1)
    assert abs(imageio.imread(io.BytesIO(base64.b64decode(poster))).mean() - 80) < 3


def test_no_empty_delta_plot(tmp_path):
    same = _run(tmp_path, "same", [_rec("zero", p, s, False, 0.0, "REACH") for p in ("Default", "V-AUG") for s in (1, 2)])
    page = write_report(same, same / "report.html").read_text()
    assert "all deltas are 0" in page and not (same / "report_files" / "delta_to_default.png").exists()
    differ = _run(tmp_path, "differ", [_rec("zero", "Default", 1, True, 1.0, "DONE"), _rec("zero", "V-AUG", 1, False, 0.33, "GRASP")])
    page = write_report(differ, differ / "report.html").read_text()
    assert "all deltas are 0" not in page and (differ / "report_files" / "delta_to_default.png").stat().st_size > 1000
    assert "delta_to_default.png" in page and "change against Default" in page


def test_videos_are_the_first_failures_by_seed_in_each_cell(tmp_path):
    recs = [_rec("p", "Default", s, False, 0.0, "REACH", video=f"v{s}.mp4") for s in (7, 3, 5)]
    recs += [_rec("p", "V-AUG", 3, True, 1.0, "DONE", video="ok.mp4"), _rec("p", "V-AUG", 4, False, 0.0, "REACH")]
    chosen, more, missing = select_videos(recs, "failures", per_cell=2)
    assert [(r["perturbation"], r["seed"]) for r in chosen] == [("Default", 3), ("Default", 5)]
    assert more == 1 and missing == 1
    chosen, _, _ = select_videos(recs, "all", per_cell=2)
    assert ("V-AUG", 3) in [(r["perturbation"], r["seed"]) for r in chosen]


@pytest.mark.parametrize("size", [(90, 320), (91, 161)])
def test_videos_keep_their_size_and_print_no_resize_warning(tmp_path, caplog, size):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with caplog.at_level(logging.WARNING):
            path = _video(tmp_path, EpisodeKey(TASK, "Default", 0), size=size)
    assert not [r for r in caplog.records if "resiz" in r.getMessage().lower()]
    reader = imageio.get_reader(path)
    w, h = reader.get_meta_data()["size"]
    reader.close()
    assert (h, w) == (size[0] + size[0] % 2, size[1] + size[1] % 2)  # odd sizes padded by one row / column, not scaled


def test_demo_index_compares_both_policies_and_shows_the_learned_policys_failures(tmp_path):
    """``realm demo`` end to end, shortened: the index has both policies' numbers, and the tiny
    LeRobot policy's failed episode is recorded and shown inline in its report."""
    from realm_ms.cli import main

    rc = main(["demo", "--tasks", TASK, "--perturbations", "Default", "--max-steps", "24", "--workers", "1", "--out", str(tmp_path)])
    assert rc == 0
    index = (tmp_path / "index.html").read_text()
    assert "scripted expert" in index and "tiny LeRobot ACT" in index
    assert 'href="expert/report.html"' in index and 'href="lerobot_tiny/report.html"' in index
    assert re.search(r"tiny LeRobot ACT \(random init\)</td>.*?<td>1</td><td>0/1 = 0.00 \[0.00, 0.79\]</td>", index)
    tiny = [json.loads(line) for line in (tmp_path / "lerobot_tiny" / "records.jsonl").read_text().splitlines()]
    assert len(tiny) == 1 and not tiny[0]["success"] and tiny[0]["video"]
    report = (tmp_path / "lerobot_tiny" / "report.html").read_text()
    assert report.count("<video controls") == 1 and "stalled at REACH" in report
    # the header reads the protocol from what this run wrote (run.json, records)
    header = report[:report.index("<h2")]
    for text in ("24 control steps (1.6 s at 15 Hz)", "160x90 per camera", "joint_position", "realm-ms ", "0 error records"):
        assert text in header, text


def test_realm_eval_report_of_several_runs_writes_one_index(tmp_path, capsys):
    from realm_ms.cli import main

    expert, zero = _expert_and_zero(tmp_path)
    assert main(["eval", "report", str(expert), str(zero)]) == 2  # an index needs a name
    assert "name it with --out" in capsys.readouterr().err
    out = tmp_path / "cmp" / "index.html"
    assert main(["eval", "report", str(expert), str(zero), "--out", str(out)]) == 0
    page = out.read_text()
    assert "4/4 = 1.00 [0.51, 1.00]" in page and "0/4 = 0.00 [0.00, 0.49]" in page
    assert main(["eval", "report", str(expert), str(tmp_path / "nope"), "--out", str(out)]) == 2
    assert "does not exist" in capsys.readouterr().err
