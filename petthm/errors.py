"""Exceptions that petthm reports to the user as a one-line message."""


class InputError(Exception):
    """Bad input: an option, a file or a value outside its accepted range.

    The message names the option or file and, where it applies, the accepted
    range; the command-line driver prints it on one line and exits with 2.
    """
