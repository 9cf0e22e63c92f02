"""Exceptions that petthm reports to the user as a one-line message."""


class InputError(Exception):
    """Bad input: an option, a file or a value outside its accepted range.

    The message names the option or file and, where it applies, the accepted
    range; the command-line driver prints it on one line and exits with 2.
    """


class WriteFailure(Exception):
    """A file of the run could not be written (no space left, a lost file
    system): raised on every rank alike; the run ends as failed (exit code
    1) with this one-line message, and the last checkpoint stays intact."""


def os_error_text(error: BaseException) -> str:
    """The operating system's words for a failed write: the ``strerror`` of
    an OSError, or the ``error message = '...'`` inside HDF5's long message."""
    import re
    if isinstance(error, OSError) and error.strerror:
        return error.strerror
    m = re.search(r"error message = '([^']*)'", str(error))
    return m.group(1) if m else str(error).splitlines()[0] if str(error) else type(error).__name__


class petsc_option_errors:
    """Turn a PETSc error raised while PETSc reads its options (an unknown
    ``-pc_type``, a value out of range such as ``-dm_refine -1``) into an
    ``InputError`` with PETSc's own message (the last line of the error
    stack that petsc4py puts in the exception), instead of a Python
    traceback.  ``what`` says what was being set up ("the solver options");
    ``codes``: convert only these PETSc error codes (where other errors than
    the options' can arise, as in a preconditioner's set-up)."""

    def __init__(self, what: str, codes: tuple[int, ...] | None = None):
        self.what = what
        self.codes = codes

    def __enter__(self):
        return self

    def __exit__(self, kind, error, tb):
        from petsc4py import PETSc
        if kind is not None and issubclass(kind, PETSc.Error) and (
                self.codes is None or getattr(error, "ierr", None) in self.codes):
            raise InputError(f"PETSc refused {self.what}: {_petsc_message(error)}") from None
        return False


#: PETSc's error codes for a wrong option value: PETSC_ERR_ARG_WRONG,
#: PETSC_ERR_ARG_OUTOFRANGE, PETSC_ERR_UNKNOWN_TYPE
OPTION_ERRORS = (62, 63, 86)


def _petsc_message(error) -> str:
    """The specific message of a PETSc error: the last line of its stack
    that is not a location ("[0] Func() at file.c:NN")."""
    import re
    lines = [re.sub(r"^\[\d+\]\s*", "", line).strip() for line in str(error).splitlines()[1:]]
    lines = [s for s in lines if s and not re.search(r"\(\) at .*:\d+$", s)]
    return lines[-1] if lines else f"PETSc error code {getattr(error, 'ierr', '?')}"
