"""`realm export`: REALM episodes (scripted-expert demonstrations) -> a LeRobot v3.0 dataset.

    realm export --policy expert --tasks REALM-PickApple-v1 REALM-OpenDrawer-v1 [--perturbations Default V-LIGHT]
                 --episodes 10 [--seed 0] --out data/realm_demos [--repo-id realm/demos] [--success-only]

    realm export --from-eval outputs/eval/RUN --out data/realm_eval_episodes   # episodes of a `realm eval` run

Rerunning the same command resumes: episodes already in the dataset are skipped.
"""

from __future__ import annotations

from pathlib import Path

from realm_ms.task_index import DEFAULT


def add_parser(sub) -> None:
    p = sub.add_parser("export", help="write REALM episodes to a LeRobot v3.0 dataset (DROID features)",
                       description=__doc__.splitlines()[0])
    p.add_argument("--policy", default="expert", help="policy that acts (default: expert, the privileged scripted expert)")
    p.add_argument("--tasks", nargs="+", metavar="ID", help="REALM env ids, or 'all'")
    p.add_argument("--perturbations", nargs="+", default=[DEFAULT], metavar="NAME", help=f"perturbation names (default: {DEFAULT})")
    from realm_ms.validate import seed

    p.add_argument("--episodes", type=int, help="episodes per (task, perturbation), >= 1")
    p.add_argument("--seed", type=seed(), default=0, help="episode k of each (task, perturbation) uses seed + k; in [0, 2**32)")
    p.add_argument("--out", type=Path, required=True, help="dataset root (created, or resumed if it holds a dataset)")
    p.add_argument("--repo-id", default=None, help="dataset repo id (default: realm/<out dir name>)")
    p.add_argument("--success-only", action="store_true", help="drop failed episodes (and try further seeds)")
    p.add_argument("--width", type=int, default=320, help="camera width (default 320)")
    p.add_argument("--height", type=int, default=180, help="camera height (default 180)")
    p.add_argument("--max-steps", type=int, default=None, help="control steps per episode (default: task horizon)")
    from realm_ms.rendering import SHADERS  # the one shader table

    p.add_argument("--shader", default="default", choices=SHADERS,
                   help="default (raster) | rt | rt-med | rt-fast | minimal (default: default)")
    p.add_argument("--from-eval", type=Path, default=None, metavar="RUN",
                   help="re-simulate the episodes of a `realm eval` run (its records.jsonl) instead of --tasks")
    from realm_ms.lerobot.export import GRIPPER_LABELS

    p.add_argument("--gripper-labels", default="command", choices=GRIPPER_LABELS,
                   help="action[7]: the gripper command as sent (default), or binary (1 wherever the policy closed "
                        "at all: DROID's and REALM's convention, what a policy should learn)")
    p.add_argument("--robot-model", default=None, metavar="NAME|MODEL.yaml",
                   help="robot the envs run: a named model (droid-aligned) or a MODEL.yaml (default: the nominal DROID robot)")
    p.add_argument("--commit-every", type=int, default=1, help="finalize + reopen every N episodes, >= 1 (resume granularity)")
    p.set_defaults(func=run)


def run(args) -> int:
    from realm_ms.errors import UserError
    from realm_ms.lerobot.export import ExportConfig, export_dataset, export_eval_run

    if args.from_eval is None and (not args.tasks or args.episodes is None):
        raise UserError("give --tasks and --episodes (or --from-eval RUN)")
    if args.from_eval is not None and args.tasks:
        raise UserError("--from-eval takes its tasks from the run's records; drop --tasks")
    if args.from_eval is not None and args.episodes is not None:
        raise UserError("--from-eval exports one episode per record of the run; drop --episodes")
    if args.from_eval is None:  # the policy is known before a dataset is created
        from realm_ms.eval.cli import check_policy_spec
        from realm_ms.eval.policies import policy_names

        if args.policy.partition(":")[0] not in policy_names():
            raise UserError(f"unknown policy {args.policy!r}; known: {', '.join(policy_names())}")
        check_policy_spec(args.policy)
    from realm_ms.eval.cli import robot_model_kwargs

    robot_model = robot_model_kwargs(args.robot_model).get("robot_model")
    tasks = args.tasks or []
    if "all" in tasks and len(tasks) > 1:
        raise UserError("--tasks all stands alone; drop the other task ids")
    if tasks == ["all"]:
        from realm_ms.tasks import TASKS

        tasks = sorted(TASKS)
    # ExportError and UnknownNameError are user errors: `realm` prints them as one line
    cfg = ExportConfig(
        out=args.out, tasks=tasks, episodes=1 if args.episodes is None else args.episodes, perturbations=args.perturbations, seed=args.seed,
        policy=args.policy, repo_id=args.repo_id, success_only=args.success_only, width=args.width,
        height=args.height, max_steps=args.max_steps, shader=args.shader, commit_every=args.commit_every,
        gripper_labels=args.gripper_labels, robot_model=robot_model,
    )
    summary = export_eval_run(args.from_eval, cfg) if args.from_eval is not None else export_dataset(cfg)
    print(f"wrote {summary['written']} episode(s) ({summary['already']} already there, {summary['dropped']} dropped); "
          f"{summary['total_episodes']} in {summary['root']} (repo id {summary['repo_id']})")
    return 0
