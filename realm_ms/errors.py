"""The user-error root every layer raises. ``UserError``: bad input from the user, printed by the
``realm`` command as one clear line (exit code 2), never as a traceback. It lives here, below every
package (the other leaf utilities may import it), so that a package's command module need not
import the top-level CLI.

Subclasses name a kind where a caller may want to catch just that kind; the command line treats
them all alike:

* ``InputError``: a bad value (flag, field, file); also a ``ValueError``, so Python callers of
  the API can catch it as one. ``realm_ms.validate`` raises it; sysid's ``DataError``, the
  registry's ``UnknownNameError``, the perturbations' ``CatalogTooSmall`` and the LeRobot
  ``ExportError`` are kinds of it.
"""


class UserError(Exception):
    """Bad input from the user: the message says what is wrong and how to fix it."""


class InputError(UserError, ValueError):
    """Bad user input; the message names what is wrong and where (flag, field or file)."""
