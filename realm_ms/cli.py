"""`realm` command line: one entry point, one subcommand module per area.

Each module listed in ``COMMANDS`` exposes ``add_parser(subparsers)`` which registers its
subcommand and sets ``func`` on the parsed namespace. Only the module of the command being run is
imported (``realm --help`` lists the commands from ``COMMANDS`` alone), and modules keep heavy
imports (torch, sapien, mani_skill) inside their handlers, so help is instant (a test checks it). The
``REALM-*`` envs are registered before a handler runs, unless its parser says
``set_defaults(needs_envs=False)`` (sysid, assets). Bad input ends in one line on stderr and exit
code 2: ``realm_ms.errors.UserError``, the root of every user error (handlers raise it; the shared
checks below them raise its ``InputError`` kind, e.g. the sysid ``DataError``).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Iterable

from realm_ms.errors import UserError  # noqa: F401  (re-exported: raised by every command module)

# subcommand -> (module providing add_parser(), one-line help shown by `realm --help`). Only the
# module of the command being run is imported: `realm --help` imports none of them.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("realm_ms.demo", "quick protocol run: the expert and a tiny LeRobot policy through `realm eval`, ending in an HTML index"),
    "sysid": ("realm_ms.sysid.cli", "system identification: compare, diagnose, fit, report"),
    "assets": ("realm_ms.assets.cli", "build and inspect the object catalog"),
    "perturbations": ("realm_ms.perturbations.cli", "REALM's perturbations: list them, render a contact sheet"),
    "export": ("realm_ms.lerobot.cli", "write REALM episodes to a LeRobot v3.0 dataset (DROID features)"),
    "eval": ("realm_ms.eval.cli", "evaluate a policy under the REALM protocol; `realm eval report RUN/` for the report"),
    "validate": ("realm_ms.eval.real_vs_sim", "real-vs-sim statistics of policy rankings: Pearson r, MMRV, RMSD from a paired CSV"),
    "render": ("realm_ms.render_cli", "render contact sheets of the tasks' cameras"),
}


def build_parser(load: Iterable[str] | None = None) -> argparse.ArgumentParser:
    """The ``realm`` parser; the subcommands in ``load`` (default: all) get their full parsers, the
    others a placeholder that only lists them."""
    from realm_ms import __version__

    parser = argparse.ArgumentParser(
        prog="realm", description="realm-ms: the REALM generalization benchmark on ManiSkill3 (evaluate policies, export "
        "LeRobot datasets, perturbations, assets) and a system-identification workbench for the DROID robot.",
        epilog="`realm COMMAND --help` for a command's options; README.md for set-up and examples.")
    parser.add_argument("--version", action="version", version=f"realm-ms {__version__}")
    parser.add_argument("--verbose", action="store_true",
                        help="show every third-party warning (sets REALM_MS_VERBOSE=1, which worker processes inherit)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    load = set(COMMANDS) if load is None else set(load)
    for name, (module, help_text) in COMMANDS.items():
        if name not in load:
            sub.add_parser(name, help=help_text, add_help=False)
            continue
        importlib.import_module(module).add_parser(sub)
    from realm_ms.validate import forbid_repeats

    # every command: a single-valued option given twice is an error (never last-one-wins in silence);
    # list options (nargs="+") and append options accumulate
    return forbid_repeats(parser)


def _command(argv: list[str]) -> str | None:
    """The subcommand named in ``argv`` (the first token that is one), if any."""
    return next((a for a in argv if a in COMMANDS), None)


def _prog(parser: argparse.ArgumentParser, argv: list[str]) -> str:
    """``realm sysid compare``: the deepest subcommand named in ``argv``."""
    cur = parser
    for token in argv:
        subs = [a for a in cur._actions if isinstance(a, argparse._SubParsersAction)]
        if subs and token in subs[0].choices:
            cur = subs[0].choices[token]
    return cur.prog


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = _command(argv)
    parser = build_parser([command] if command else [])
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    if args.verbose:
        os.environ["REALM_MS_VERBOSE"] = "1"
    if getattr(args, "needs_envs", True):
        from realm_ms import register_envs

        register_envs()
    try:
        return int(args.func(args) or 0)
    except UserError as e:  # the root of every user error
        msg = " ".join(str(e).split()) or type(e).__name__  # always one line
        print(f"{_prog(parser, argv)}: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted; partial results are kept where the command writes incrementally", file=sys.stderr)
        return 130


if __name__ == "__main__":
    # `python -m realm_ms.cli` runs this file as __main__: use the package's module so that
    # realm_ms.cli.UserError raised by subcommands is the class caught above
    from realm_ms.cli import main as _main

    sys.exit(_main())
