"""pydiag's exceptions: one base class, one subclass per kind of problem.

Every exception the user can act on derives from :class:`PydiagError`; the command line
prints those as one line and exits with status 2. Anything else that escapes is a bug in
pydiag (or a library under it) and is reported as an internal error, never as the user's
mistake. Exceptions raised while handling another keep it as their ``__cause__``.
"""

from __future__ import annotations


class PydiagError(Exception):
    """A problem the user can act on; the message says what and, where it can, how."""


class UsageError(PydiagError):
    """An argument or setting is out of range or contradicts another."""


class MeasurementError(PydiagError):
    """A measurement file or record that cannot be used."""


class OutputError(PydiagError):
    """An output file that cannot be written where it was asked for."""


class AdapterError(PydiagError):
    """An adapter file that cannot be used; the message names the file, table and key."""


class MachineError(PydiagError):
    """A machine description that cannot be used; the message names the file and key."""


class PlantError(PydiagError):
    """The FMU cannot be loaded or simulated as asked."""


class UnsafeArchive(PlantError):
    """The FMU archive is malformed or hostile; nothing was extracted."""


class EstimationError(PydiagError):
    """The estimate cannot be made as asked."""


class TooManyFailures(EstimationError):
    """Simulations failed too many times in a row.

    Attributes:
        count: failed evaluations so far
        consecutive: failures in a row that stopped the run
        last: the cause of the last failure
    """

    def __init__(self, message: str, count: int = 0, consecutive: int = 0,
                 last: str = "") -> None:
        super().__init__(message)
        self.count = count
        self.consecutive = consecutive
        self.last = last


class GoldenError(PydiagError):
    """A regression golden file that is missing or cannot be used."""
