"""The run directory (``realm eval --out RUN/``) as a contract: what makes its records comparable.

``RUN/run.json`` holds the run's *fingerprint*: the policy spec, the protocol preset, max steps,
re-planning interval, success tail, camera size, action space, code version and the extra env
config. Every record in ``RUN/records.jsonl`` carries the same fingerprint. A resume (the same
command again) refuses, with one line naming what differs, a ``run.json`` or any record whose
fingerprint is not this command's -- also when ``run.json`` is missing, so records copied in from
another policy or another ``--max-steps`` never mix into ``metrics.json``. Lines that are not
records are skipped and reported with their line numbers (``records.read_records``).

Tasks, perturbations, episodes and the base seed are not in the fingerprint: a run may grow (more
episodes, another task) and its records stay comparable. The code version is the package version;
the git revision is provenance in each record (``code_version`` there), not a reason to refuse.
"""

from __future__ import annotations

import json
from pathlib import Path

from realm_ms.atomic import write_json
from realm_ms.eval.protocol import EpisodeKey
from realm_ms.eval.records import FINISHED, key_of, numbered_records
from realm_ms.validate import InputError, check_output_path

RUN_FILES = ("run.json", "records.jsonl", "metrics.json")
DEFAULT_ACTION_SPACE = "joint_position"  # DROID's; env keywords action_space / gripper_action_space


def fingerprint(policy_spec: str, proto, cfg) -> dict:
    """What makes two records comparable (``cfg``: the run's ``RunConfig``)."""
    from realm_ms import __version__
    from realm_ms.jsonable import jsonable

    env_config = jsonable(dict(cfg.env_kwargs or {}))
    space = env_config.pop("action_space", None) or DEFAULT_ACTION_SPACE
    gripper = env_config.pop("gripper_action_space", None)
    control = env_config.pop("control_mode", None)
    action_space = ":".join(str(x) for x in (space, gripper) if x) + (f" ({control})" if control else "")
    fp = dict(policy=policy_spec, protocol=proto.name, max_steps=proto.max_steps, replan_every=proto.replan_every,
              success_tail=proto.success_tail, camera_size=[cfg.obs.width, cfg.obs.height], action_space=action_space,
              code_version=f"realm-ms {__version__}", env_config=env_config)
    latency = str(getattr(cfg, "policy_latency", "0"))
    if latency != "0":  # absent at the default, so runs made before the setting existed still resume
        fp["policy_latency"] = latency
    return fp


def check_run_paths(out: Path, videos: str = "none") -> Path:
    """``--out`` and the files a run writes there can be written: checked before any work."""
    out = check_output_path(out, "--out", "dir")
    for name in RUN_FILES:
        check_output_path(out / name, "--out", "file")
    if videos != "none":
        check_output_path(out / "videos", "--out", "dir")
    return out


def differences(have: dict, want: dict) -> list[str]:
    """``key: theirs vs this command's`` for each fingerprint field that differs."""
    keys = list(want) + [k for k in have if k not in want]
    return [f"{k} {_short(have.get(k, '<missing>'))} vs {_short(want.get(k, '<missing>'))}" for k in keys if have.get(k) != want.get(k)]


def _short(v) -> str:
    text = json.dumps(v, separators=(",", ":")) if not isinstance(v, str) else v
    return text if len(text) <= 60 else text[:57] + "..."


def _read_run_json(path: Path) -> dict:
    hint = (f"it describes the run in {path.parent}: restore it, or delete it to have this command rewrite it "
            "(the records keep their own fingerprints), or use another --out")
    if path.is_dir():
        raise InputError(f"{path} is a directory; {hint}")
    try:
        data = json.loads(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError:
        raise InputError(f"{path}: not UTF-8 text; {hint}") from None
    except json.JSONDecodeError as e:
        raise InputError(f"{path}: not valid JSON ({e.msg}, line {e.lineno}); {hint}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object, got {type(data).__name__}; {hint}")
    return data


def check_run_json(out: Path, fp: dict) -> None:
    """Refuse a ``run.json`` made by another setup (one line naming what differs)."""
    path = out / "run.json"
    if not path.exists():
        return
    old = _read_run_json(path)
    if isinstance(old.get("fingerprint"), dict):
        diff = differences(old["fingerprint"], fp)
    else:  # written before fingerprints: the fields it has
        diff = [f"{k} {old.get(k)!r} vs {fp[k]!r}" for k in ("policy", "max_steps", "replan_every") if old.get(k) != fp[k]]
    if diff:
        raise InputError(f"{out} holds a run made differently ({'; '.join(diff)}; theirs vs this command's): use another --out")


def check_records(out: Path, fp: dict, problems: list[str]) -> tuple[list[dict], set[EpisodeKey]]:
    """The run's valid records and its finished keys; refuses records of another fingerprint.
    Unreadable lines are appended to ``problems`` (``FILE:LINE: why``) and do not count."""
    path = out / "records.jsonl"
    numbered = numbered_records(path, problems)
    records = [rec for _, rec in numbered]
    foreign = []
    for n, rec in numbered:
        theirs = rec.get("fingerprint")
        if theirs != fp:
            why = ("no run fingerprint (written by an older realm-ms, or copied in)" if not isinstance(theirs, dict)
                   else "; ".join(differences(theirs, fp)))
            foreign.append((n, why))
    if foreign:
        n, why = foreign[0]
        raise InputError(f"{path}: {len(foreign)} of {len(records)} record(s) were not made by this command "
                         f"(line {n}: {why}; theirs vs this command's): use another --out, or remove those lines")
    return records, {key_of(r) for r in records if r.get("status", "ok") in FINISHED}


def write_run_json(out: Path, meta: dict) -> None:
    """``RUN/run.json``, replaced atomically (a kill never leaves half of it)."""
    write_json(out / "run.json", meta, indent=2)
