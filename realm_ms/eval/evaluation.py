"""``evaluate()``: a whole ``realm eval`` run, the library API the CLI, the demo, the benches and the
examples call: load the policy, check and open the run directory (``rundir.py``: fingerprint,
resume), plan the episodes not yet done, run them on the chosen backend (``backends/``) through the
driver (``runner.run_plan``) or over Ray, and write the metrics."""

from __future__ import annotations

import sys
from pathlib import Path


def evaluate(policy_spec: str, tasks, perturbations, proto, out: Path, workers: int | None = None, backend: str = "auto",
             ray_address: str | None = None, camera_size=None, videos: str = "none", quality: bool = True,
             progress: bool = True, policy_options: dict | None = None, env_kwargs: dict | None = None, quiet: bool = False,
             policy_latency="0") -> int:
    """Run ``policy_spec`` on tasks x perturbations x ``proto.episodes`` into the run directory ``out``
    (resuming it), write ``metrics.json``; returns the exit code (1: some episode ended in an error
    record). ``realm eval`` is this; ``policy_latency``: 0, seconds or ``"measured"`` (``latency.py``)."""
    from realm_ms.errors import UserError
    from realm_ms.eval.metrics import compute_metrics
    from realm_ms.eval.policies import make_policy, policy_action_space
    from realm_ms.eval.protocol import plan
    from realm_ms.eval.records import RecordWriter, format_problems, read_records
    from realm_ms.eval.rundir import check_records, check_run_json, check_run_paths, fingerprint, write_run_json
    from realm_ms.eval.runner import RunConfig, default_workers, run_plan
    from realm_ms.eval.backends.choose import choose_backend
    from realm_ms.eval.backends.ray import run_ray
    from realm_ms.registry import UnknownNameError
    from realm_ms.validate import check_seed

    from realm_ms.eval.latency import parse_latency

    out = check_run_paths(Path(out), videos)  # before the policy loads: a bad --out never costs a model load
    check_seed(proto.seed, "--seed", proto.episodes)
    try:
        policy_latency = parse_latency(policy_latency)
    except ValueError as e:
        raise UserError(str(e)) from None
    policy_options = policy_options or {}
    try:
        policy = make_policy(policy_spec, **policy_options)
    except (ValueError, OSError, UnknownNameError, ImportError) as e:
        raise UserError(f"cannot load policy {policy_spec!r}: {e}") from None
    req = policy.obs_request()
    if camera_size:
        req.width, req.height = camera_size
    cfg = RunConfig(policy=policy.spec(), env_side=policy.env_side, max_steps=proto.max_steps, replan_every=proto.replan_every,
                    success_tail=proto.success_tail, obs=req, videos=videos, videos_dir=str(out / "videos"), quality=quality,
                    env_kwargs=policy_action_space(policy, policy_options) | (env_kwargs or {}), policy_latency=policy_latency)
    # the run directory contract (rundir.py): run.json and every record carry this fingerprint
    fp = fingerprint(policy.spec(), proto, cfg)
    problems: list[str] = []
    try:
        check_run_json(out, fp)
        _, done = check_records(out, fp, problems)
        out.mkdir(parents=True, exist_ok=True)
        write_run_json(out, dict(policy=policy.spec(), protocol=proto.name, tasks=tasks, perturbations=perturbations,
                                 episodes=proto.episodes, seed=proto.seed, max_steps=proto.max_steps,
                                 replan_every=proto.replan_every, success_tail=proto.success_tail, fingerprint=fp))
        writer = RecordWriter(out / "records.jsonl")
    except BaseException:
        policy.close()
        raise
    if problems:
        print(f"realm eval: warning: {len(problems)} line(s) of {out / 'records.jsonl'} are not records: skipped, "
              f"not counted (an episode among them runs again):\n{format_problems(problems)}", file=sys.stderr)

    def append(rec: dict) -> None:
        writer.append({**rec, "fingerprint": fp})

    keys = [k for k in plan(tasks, perturbations, proto.episodes, proto.seed) if k not in done]
    if not quiet:
        print(f"realm eval: {policy.spec()} on {len(tasks)} task(s) x {len(perturbations)} perturbation(s) x {proto.episodes} episode(s); "
              f"{len(done)} already done, {len(keys)} to run -> {out}/", file=sys.stderr)
    n_workers = workers or default_workers()
    try:
        if keys and ray_address:
            run_ray(keys, policy.spec(), policy_options, cfg, ray_address, append, progress_bar=progress)
        elif keys:
            try:
                be = choose_backend(backend, cfg, min(n_workers, len(keys)))
            except RuntimeError as e:
                raise UserError(str(e)) from None
            try:
                run_plan(keys, policy, be, append, progress_bar=progress, replan_every=proto.replan_every,
                         policy_latency=cfg.policy_latency, env_kwargs=cfg.env_kwargs)
            finally:
                be.close()
    finally:
        writer.close()
        policy.close()
        metrics = compute_metrics(read_records(out / "records.jsonl"))
        from realm_ms.atomic import write_json

        write_json(out / "metrics.json", metrics, indent=2)
    o = metrics["overall"]
    if not quiet:
        print(f"{o['episodes']} episodes: success {o['success_rate']:.3f} [{o['success_ci'][0]:.3f}, {o['success_ci'][1]:.3f}], "
              f"progression {o['mean_progression']:.3f}; errors {len(metrics['errors'])}; metrics in {out / 'metrics.json'}")
    return _error_exit(metrics["errors"], out)


def _error_exit(errors: list, out: Path) -> int:
    """1, with where to look, when any episode of the run ended in an error record (a rerun of the
    same command retries exactly those); 0 otherwise."""
    if not errors:
        return 0
    cells = sorted({f"{e.get('task')} x {e.get('perturbation')}" for e in errors})
    print(f"realm eval: {len(errors)} episode(s) ended in an error record, in {len(cells)} cell(s): {'; '.join(cells[:6])}"
          f"{' ...' if len(cells) > 6 else ''}. The errors are in {out / 'metrics.json'} (\"errors\") and "
          f"{out / 'records.jsonl'} (status \"error\"); rerun the same command to retry those episodes.", file=sys.stderr)
    return 1


__all__ = ["evaluate"]
