"""Exceptions: one class per ``PelageStatus``, each carrying the status and
``pelage_last_error()``'s message."""

from __future__ import annotations

from ._ffi import ffi, lib

__all__ = [
    "PelageError",
    "Error",
    "NullParameter",
    "InvalidArgument",
    "NonFinite",
    "OutOfRange",
    "CapacityExceeded",
    "Misaligned",
    "CorruptData",
    "VersionMismatch",
    "Cancelled",
    "Panic",
    "OutOfMemory",
    "check",
]


class PelageError(Exception):
    """A pelage call returned a status other than ``PELAGE_STATUS_OK``.

    Attributes:
        status: the ``PelageStatus`` value (an int; ``lib.PELAGE_STATUS_*``).
        function: the C function that failed.
        message: ``pelage_last_error()``'s detailed message for the call.
    """

    status: int = -1

    def __init__(self, status: int, function: str, message: str) -> None:
        self.status = status
        self.function = function
        self.message = message
        summary = ffi.string(lib.pelage_status_message(status)).decode("utf-8", "replace")
        # the detailed message names the status itself ("invalid argument: ...")
        super().__init__(f"{function}: {message or summary}")


#: The name STYLE.md gives the base class (``pelage.Error``).
Error = PelageError


class NullParameter(PelageError, ValueError):
    """PELAGE_STATUS_NULL_PARAMETER: a required pointer was NULL."""


class InvalidArgument(PelageError, ValueError):
    """PELAGE_STATUS_INVALID_ARGUMENT: a value outside its documented domain."""


class NonFinite(PelageError, ValueError):
    """PELAGE_STATUS_NON_FINITE: a NaN or infinity in an input (a distance
    callback's answers included)."""


class OutOfRange(PelageError, IndexError):
    """PELAGE_STATUS_OUT_OF_RANGE: an index in the input is out of range."""


class CapacityExceeded(PelageError):
    """PELAGE_STATUS_CAPACITY_EXCEEDED: an arena or output buffer too small."""


class Misaligned(PelageError, ValueError):
    """PELAGE_STATUS_MISALIGNED: a pointer or stride not 4-byte aligned."""


class CorruptData(PelageError, ValueError):
    """PELAGE_STATUS_CORRUPT_DATA: serialized data truncated or corrupt."""


class VersionMismatch(PelageError, ValueError):
    """PELAGE_STATUS_VERSION_MISMATCH: data from an incompatible version."""


class Cancelled(PelageError):
    """PELAGE_STATUS_CANCELLED: the progress callback returned False."""


class Panic(PelageError, RuntimeError):
    """PELAGE_STATUS_PANIC: an internal error in pelage."""


class OutOfMemory(PelageError, MemoryError):
    """PELAGE_STATUS_OUT_OF_MEMORY: the system refused memory; nothing changed."""


_BY_STATUS = {
    lib.PELAGE_STATUS_NULL_PARAMETER: NullParameter,
    lib.PELAGE_STATUS_INVALID_ARGUMENT: InvalidArgument,
    lib.PELAGE_STATUS_NON_FINITE: NonFinite,
    lib.PELAGE_STATUS_OUT_OF_RANGE: OutOfRange,
    lib.PELAGE_STATUS_CAPACITY_EXCEEDED: CapacityExceeded,
    lib.PELAGE_STATUS_MISALIGNED: Misaligned,
    lib.PELAGE_STATUS_CORRUPT_DATA: CorruptData,
    lib.PELAGE_STATUS_VERSION_MISMATCH: VersionMismatch,
    lib.PELAGE_STATUS_CANCELLED: Cancelled,
    lib.PELAGE_STATUS_PANIC: Panic,
    lib.PELAGE_STATUS_OUT_OF_MEMORY: OutOfMemory,
}
for _status, _cls in _BY_STATUS.items():
    _cls.status = _status


def check(status: int, function: str) -> None:
    """Raises the exception of ``status`` (with the calling thread's
    ``pelage_last_error()``) unless it is ``PELAGE_STATUS_OK``."""
    if status != lib.PELAGE_STATUS_OK:
        message = ffi.string(lib.pelage_last_error()).decode("utf-8", "replace")
        raise _BY_STATUS.get(status, PelageError)(int(status), function, message)
