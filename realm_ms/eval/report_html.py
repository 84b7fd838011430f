"""HTML pieces of the eval reports (``realm_ms.eval.report``) on the shared kit
(``realm_ms.html_kit``: style, page, tables, figures): the protocol header every page starts
with, episode labels and the inline video gallery.

Videos stay files next to the run and are referenced relatively, so a report can be moved together
with its run directory.
"""

from __future__ import annotations

import base64
import io
import json
import os
from pathlib import Path

from realm_ms.eval.provenance import CONTROL_HZ, describe_action_space
from realm_ms.html_kit import esc

def short(task: str) -> str:
    return task.removeprefix("REALM-").removesuffix("-v1")


# ------------------------------------------------------------------------------------ protocol
def _get(d: dict, key: str):
    """``d["a"]["b"]`` for ``key="a.b"``; None where a level is missing."""
    for part in key.split("."):
        d = d.get(part) if isinstance(d, dict) else None
    return d


def _values(records: list[dict], *keys: str) -> list:
    """Distinct values of the first of ``keys`` (dotted paths, e.g. ``fingerprint.camera_size``)
    each record has."""
    seen = []
    for r in records:
        v = next((v for v in (_get(r, k) for k in keys) if v is not None), None)
        if v is not None and v not in seen:
            seen.append(v)
    return seen


def _meta(meta: dict, *keys: str) -> list:
    return next(([v] for v in (_get(meta, k) for k in keys) if v is not None), [])


def _mixed(vals: list[str]) -> str:
    if not vals:
        return "not recorded"
    return vals[0] if len(vals) == 1 else " / ".join(vals) + " (mixed: records from runs with different settings)"


def run_protocol(run_dir: Path, records: list[dict]) -> dict[str, str]:
    """The protocol a run was made under, label -> text, from ``RUN/run.json`` and its records
    (records win where they hold the value: they are what actually ran)."""
    meta = {}
    meta_path = Path(run_dir) / "run.json"
    if meta_path.exists():
        try:
            meta = json.loads(meta_path.read_text())
        except json.JSONDecodeError:
            meta = {}
    tasks = meta.get("tasks") or sorted({r["task"] for r in records})
    perts = meta.get("perturbations") or sorted({r["perturbation"] for r in records})
    seeds = sorted({int(r["seed"]) for r in records})
    episodes = meta.get("episodes") or (len(seeds) or None)
    seed = meta.get("seed", seeds[0] if seeds else None)
    steps = _values(records, "max_steps") or _meta(meta, "max_steps")
    replan = _values(records, "replan_every") or _meta(meta, "replan_every")
    cams = [f"{c[0]}x{c[1]}" if isinstance(c, list) else str(c)
            for c in _values(records, "fingerprint.camera_size", "camera") or _meta(meta, "fingerprint.camera_size", "camera_size")]
    shaders = _values(records, "config.cameras.shader")
    spaces = (_values(records, "action_space", "fingerprint.action_space", "control_mode")
              or _meta(meta, "fingerprint.action_space", "action_space", "control_mode"))
    versions = _values(records, "code_version", "fingerprint.code_version") or _meta(meta, "fingerprint.code_version", "code_version")
    policies = _values(records, "policy") or _meta(meta, "policy")
    horizon = [f"{s} control steps ({s / CONTROL_HZ:.3g} s at {CONTROL_HZ} Hz)" for s in steps]
    tail = meta.get("success_tail")
    seeds_text = "not recorded"
    if seed is not None and episodes:
        span = f"{seed} .. {seed + episodes - 1} (episode i: seed + i" if episodes > 1 else f"{seed} (episode 0: seed"
        seeds_text = span + ", the same under every perturbation)"
    return {
        "policy": _mixed(policies),
        "protocol": f"the {meta.get('protocol', '?')} preset with the command's flags applied" if meta else "not recorded (no run.json)",
        "tasks": f"{plural(len(tasks), 'task')}: " + ", ".join(short(t) for t in tasks),
        "perturbations": f"{plural(len(perts), 'perturbation')}: " + ", ".join(perts),
        "episodes": f"{episodes} per (task, perturbation) cell" if episodes else "not recorded",
        "seeds": seeds_text,
        "horizon": _mixed(horizon) + (f"; ends {tail} steps after success" if tail else ""),
        "action space": _mixed([describe_action_space(m) for m in spaces])
        + (f"; re-planned every {replan[0]} steps" if len(replan) == 1 else ""),
        "camera": _mixed(cams) + (" per camera (the policy's frames and the videos)" if cams else "")
        + (f"; {' / '.join(shaders)} shader" if shaders else ""),
        "robot": _mixed(_values(records, "robot_model") or ["nominal"]),
        "code version": _mixed(versions),
        "policy latency": describe_latency(records),
    }


def describe_latency(records: list[dict]) -> str:
    """The ``--policy-latency`` setting(s) the records ran with, and the latencies measured per server."""
    from realm_ms.eval.latency import MEASURED, hold_steps, latency_summary

    lat = latency_summary(records)

    def setting(s: str) -> str:
        if s == "0":
            return "0 (time stops during inference, as REALM)"
        if s == MEASURED:
            return "measured (the arm holds its previous target for each request's wall time)"
        return f"{s} s (the arm holds its previous target {hold_steps(s, 0)} control steps before each chunk)"

    text = _mixed([setting(s) for s in lat["settings"]]) if lat["settings"] else "not recorded (0)"
    if lat["servers"]:
        text += "; measured: " + ", ".join(f"{k} median {v['median_s'] * 1000:.0f} ms, p95 {v['p95_s'] * 1000:.0f} ms "
                                           f"({v['requests']} requests)" for k, v in lat["servers"].items())
    return text


def protocol_block(proto: dict[str, str], n_ok: int, n_err: int, n_unsup: int, run_dir: Path | None = None) -> str:
    rows = "".join(f"<dt>{esc(k)}</dt><dd>{esc(v)}</dd>" for k, v in proto.items())
    rows += f"<dt>records</dt><dd>{records_summary(n_ok, n_err, n_unsup)}</dd>"
    if run_dir is not None:
        rows += f"<dt>run directory</dt><dd><code>{esc(run_dir)}</code></dd>"
    return f'<dl class="proto">{rows}</dl>'


def plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def records_summary(n_ok: int, n_err: int, n_unsup: int) -> str:
    """'4 finished episodes, 1 error record, 0 unsupported' (HTML; errors in red)."""
    err = f'<span class="err">{plural(n_err, "error record")}</span>' if n_err else '<span class="ok">0 error records</span>'
    return f"<span>{plural(n_ok, 'finished episode')}, {err}, {n_unsup} unsupported</span>"


def error_banner(n_err: int) -> str:
    if not n_err:
        return ""
    return (f'<p class="warn"><span class="err">{plural(n_err, "episode")} ended in an error record</span> and are not counted in the '
            f'numbers below; they are listed under <a href="#errors">Errors</a> and run again when the same '
            f"<code>realm eval</code> command is repeated.</p>")


# ------------------------------------------------------------------------------------ episodes
def episode_label(rec: dict) -> tuple[str, str]:
    """(text, css class): "succeeded", "stalled at GRASP", "error", ... never "stalled at DONE"."""
    status = rec.get("status", "ok")
    if status == "error":
        return "error", "e"
    if status == "unsupported":
        return "unsupported", "e"
    if rec.get("success"):
        return "succeeded", "s"
    stage = rec.get("stalled_stage")
    if stage == "DONE":  # every stage met at some point but success was not held to the end
        return "all stages reached, success not held", "f"
    return (f"stalled at {stage}" if stage else "failed"), "f"


def select_videos(records: list[dict], which: str, per_cell: int) -> tuple[list[dict], int, int]:
    """The episodes to show: per (task, perturbation) cell, the first ``per_cell`` by seed among the
    failed ones (``which="failures"``) or all (``"all"``) that have a video. Returns (chosen, how
    many more had a video, how many failed episodes had none)."""
    if which == "none":
        return [], 0, 0
    chosen, more, missing = [], 0, 0
    cells: dict[tuple[str, str], list[dict]] = {}
    for r in sorted(records, key=lambda r: (r["task"], r["perturbation"], int(r["seed"]))):
        if r.get("status", "ok") != "ok" or (which == "failures" and r.get("success")):
            continue
        if not r.get("video"):
            missing += int(not r.get("success"))
            continue
        cells.setdefault((r["task"], r["perturbation"]), []).append(r)
    for eps in cells.values():
        chosen += eps[:per_cell]
        more += max(0, len(eps) - per_cell)
    return chosen, more, missing


def video_path(rec: dict, run_dir: Path) -> Path:
    """The record's video; looked up in ``RUN/videos/`` when the stored path (relative to the
    directory ``realm eval`` ran in) does not resolve from here."""
    p = Path(rec["video"])
    return p if p.exists() else Path(run_dir) / "videos" / p.name


def _poster(path: Path) -> str:
    """The video's last frame (where the episode ended) as a PNG data URI, '' if unreadable."""
    try:
        import imageio.v2 as imageio

        reader = imageio.get_reader(path)
        try:  # seek straight to the end (constant time); decode through the file if seeking fails
            meta = reader.get_meta_data()
            frame = reader.get_data(max(0, int(round(meta["duration"] * meta["fps"])) - 1))
        except (IndexError, KeyError, TypeError, ValueError):
            frame = None
            for frame in imageio.get_reader(path):
                pass
        reader.close()
        if frame is None:
            return ""
        buf = io.BytesIO()
        imageio.imwrite(buf, frame, format="png")
        return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()
    except Exception:  # a missing or broken file: the player shows its own error, the page still renders
        return ""


def video_gallery(records: list[dict], run_dir: Path, out_dir: Path, which: str, per_cell: int) -> str:
    chosen, more, missing = select_videos(records, which, per_cell)
    kind = "failed episodes" if which == "failures" else "episodes"
    rule = f"the first {per_cell} {kind} by seed in each (task, perturbation) cell"
    notes = []
    if more:
        notes.append(f"{more} more with a video are in <code>videos/</code>")
    if missing:
        notes.append(f"{missing} failed episode(s) have no video (run <code>realm eval</code> with <code>--videos failures</code>)")
    if not chosen:
        if which == "failures" and not any(r.get("status", "ok") == "ok" and not r.get("success") for r in records):
            return "<p class='note'>Every finished episode succeeded: no failure videos to show.</p>"
        return f"<p class='note'>No episode videos to show ({'; '.join(notes) or 'none recorded'}).</p>"
    cards = []
    for r in chosen:
        label, cls = episode_label(r)
        path = video_path(r, run_dir)
        src = Path(os.path.relpath(path.resolve(), Path(out_dir).resolve())).as_posix()
        poster = _poster(path)
        poster_attr = f' poster="{poster}"' if poster else ""
        cards.append(
            f'<div class="vid"><video controls muted loop preload="none"{poster_attr} src="{esc(src)}"></video>'
            f'<div><span class="tag {cls}">{esc(label)}</span> {esc(short(r["task"]))} / {esc(r["perturbation"])} / seed {r["seed"]}: '
            f'progression {float(r["progression"]):.2f}, {r.get("steps", "?")} of {r.get("max_steps", "?")} steps</div>'
            f'<div class="note">“{esc(r.get("instruction", ""))}”</div></div>')
    intro = (f"<p class='note'>Exterior camera (left) and wrist camera (right), 15 fps; the still is the episode's last frame. "
             f"Shown: {rule}{'; ' + '; '.join(notes) if notes else ''}.</p>")
    return intro + '<div class="vids">' + "".join(cards) + "</div>"
