"""The one exception type the command line shows to the user as a plain message."""


class UserError(Exception):
    """A problem the user can act on (bad file, missing port, bad option).

    The CLI prints ``str(error)`` and exits with status 2 instead of showing a traceback.
    """
