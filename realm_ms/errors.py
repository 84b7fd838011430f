"""Errors every layer may raise. ``UserError``: bad input from the user, printed by the ``realm``
command as one clear line (exit code 2), never as a traceback. It lives here, below every package,
so that a package's command module need not import the top-level CLI."""


class UserError(Exception):
    """Bad input from the user: the message says what is wrong and how to fix it."""
