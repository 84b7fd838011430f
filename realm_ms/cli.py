"""`realm` command line: one entry point, one subcommand module per area.

Each module listed in ``COMMANDS`` exposes ``add_parser(subparsers)`` which registers its
subcommand(s) and sets ``func`` on the parsed namespace. Modules keep heavy imports (torch,
sapien, mani_skill) inside their handlers so ``realm --help`` stays fast (a test checks it). The
``REALM-*`` envs are registered before a handler runs, unless its parser says
``set_defaults(needs_envs=False)`` (sysid, assets). Bad input ends in one line on stderr and exit
code 2: ``UserError`` from handlers, ``realm_ms.validate.InputError`` (and its subclasses, e.g. the
sysid ``DataError``) from anything below them.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# subcommand name -> module providing add_parser(); later areas append here.
COMMANDS: dict[str, str] = {
    "demo": "realm_ms.demo",
    "sysid": "realm_ms.sysid.cli",
    "assets": "realm_ms.assets.cli",
    "perturbations": "realm_ms.perturbations.cli",
    "export": "realm_ms.lerobot.cli",
}


class UserError(Exception):
    """Bad input from the user: printed as one clear message, never as a traceback."""


def build_parser() -> argparse.ArgumentParser:
    from realm_ms import __version__

    parser = argparse.ArgumentParser(prog="realm", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"realm-ms {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in COMMANDS.items():
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as e:
            if e.name and e.name.startswith(module.rsplit(".", 1)[0]):
                continue  # area not installed in this checkout
            raise
        mod.add_parser(sub)
    return parser


def _prog(parser: argparse.ArgumentParser, argv: list[str] | None) -> str:
    """``realm sysid compare``: the deepest subcommand named in ``argv``."""
    cur = parser
    for token in sys.argv[1:] if argv is None else argv:
        subs = [a for a in cur._actions if isinstance(a, argparse._SubParsersAction)]
        if subs and token in subs[0].choices:
            cur = subs[0].choices[token]
    return cur.prog


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    from realm_ms.validate import InputError

    if getattr(args, "needs_envs", True):
        from realm_ms import register_envs

        register_envs()
    try:
        return int(args.func(args) or 0)
    except (UserError, InputError) as e:
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
