"""Array conventions at the C boundary, the record dtypes, and PelageRun."""

from __future__ import annotations

from typing import Any, Callable, List, Optional, Sequence, Tuple

import numpy as np

from ._ffi import ffi, lib
from .errors import check

#: A progress callback: gets the share of the work done in [0, 1]; returning
#: False cancels the call (:class:`pelage.Cancelled`). ``None`` goes on.
ProgressFn = Callable[[float], Optional[bool]]

# Record dtypes: the C structs field for field, so arrays of them cross the
# boundary without copies (checked against cffi's layout below).
ROOT_DTYPE = np.dtype(
    [("face", "<u4"), ("u", "<f4"), ("v", "<f4"), ("id", "<u4"), ("rank", "<u4")]
)
BINDING_DTYPE = np.dtype(
    [("guides", "<u4", (8,)), ("weights", "<f4", (8,)), ("count", "<u4"), ("clump", "<u4")]
)
GROOM_DTYPE = np.dtype(
    [
        ("length", "<f4"),
        ("root_radius", "<f4"),
        ("tip_radius", "<f4"),
        ("bend", "<f4"),
        ("kink_amplitude", "<f4"),
        ("kink_frequency", "<f4"),
        ("kink_phase", "<f4", (2,)),
        ("clump", "<f4"),
        ("lift", "<f4", (2,)),
    ]
)
PATCH_DTYPE = np.dtype([("first", "<u4"), ("count", "<u4")])
TRIM_RECORD_DTYPE = np.dtype([("guide", "<u4"), ("cv", "<u4"), ("length", "<f4")])

_CHECKED = {
    "PelageRoot": ROOT_DTYPE,
    "PelageStrandBinding": BINDING_DTYPE,
    "PelageStrandGroom": GROOM_DTYPE,
    "PelagePatch": PATCH_DTYPE,
    "PelageTrimRecord": TRIM_RECORD_DTYPE,
}
for _ctype, _dtype in _CHECKED.items():
    assert ffi.sizeof(_ctype) == _dtype.itemsize, _ctype
    for _name in _dtype.names:
        assert ffi.offsetof(_ctype, _name) == _dtype.fields[_name][1], (_ctype, _name)


def ptr(a: Optional[np.ndarray], ctype: str = "void *") -> Any:
    """A C pointer to ``a``'s first element (NULL for None). The caller keeps
    ``a`` alive for the call."""
    if a is None:
        return ffi.NULL
    return ffi.cast(ctype, a.ctypes.data)


def records(a: Any, dtype: np.dtype, name: str, *, writable: bool = False) -> np.ndarray:
    """``a`` as a 1-D C-contiguous array of the record ``dtype``: the same
    array when it is one (no copy), a contiguous copy of a strided view of
    one; any other dtype is a TypeError."""
    arr = np.asarray(a)
    if arr.dtype != dtype:
        raise TypeError(f"{name}: expected an array of dtype {dtype}, got {arr.dtype}")
    if arr.ndim != 1:
        raise ValueError(f"{name}: expected a 1-D array, got shape {arr.shape}")
    if writable:
        if not (arr.flags.c_contiguous and arr.flags.writeable):
            raise ValueError(f"{name}: updated in place, so it must be a writable C-contiguous array")
        return arr
    return np.ascontiguousarray(arr)


def rows(a: Any, dtype: Any, cols: int, name: str) -> np.ndarray:
    """``a`` as an (n, cols) array the C API can read with a byte stride:
    the same array when its dtype matches and each row is packed (the rows
    may be any multiple of 4 bytes apart, like a column slice of a wider
    array), else a converted C-contiguous copy."""
    arr = np.asarray(a)
    if arr.ndim == 1 and cols == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2 or arr.shape[1] != cols:
        raise ValueError(f"{name}: expected shape (n, {cols}), got {arr.shape}")
    item = np.dtype(dtype).itemsize
    if (
        arr.dtype != dtype
        or (arr.shape[1] > 1 and arr.strides[1] != item)
        or arr.strides[0] < item * cols
        or arr.strides[0] % 4
    ):
        arr = np.ascontiguousarray(arr, dtype=dtype)
    return arr


def row_stride(arr: np.ndarray) -> int:
    """Bytes between rows of an array from :func:`rows`."""
    return int(arr.strides[0]) if arr.shape[0] > 1 else int(arr.itemsize * arr.shape[1])


def point_rows(out: np.ndarray, cols: int, name: str) -> Tuple[np.ndarray, int]:
    """A float32 output array as rows of at least ``cols`` packed floats,
    equally spaced, without a copy: returns the (points, row) view and its
    byte stride. Raises when ``out`` cannot be written in place."""
    if not isinstance(out, np.ndarray) or out.dtype != np.float32:
        raise TypeError(f"{name}: expected a float32 numpy array")
    if not out.flags.writeable:
        raise ValueError(f"{name}: the array is read-only")
    if out.ndim < 2 or out.shape[-1] < cols or (out.shape[-1] > 1 and out.strides[-1] != 4):
        raise ValueError(f"{name}: expected rows of at least {cols} packed float32, got {out.shape}")
    view = out.view()
    try:
        view.shape = (-1, out.shape[-1])
    except AttributeError:
        raise ValueError(f"{name}: its points are not equally spaced in memory") from None
    stride = int(view.strides[0]) if view.shape[0] > 1 else 4 * out.shape[-1]
    if stride % 4 or stride < 4 * cols:
        raise ValueError(f"{name}: rows {stride} bytes apart cannot hold {cols} floats")
    return view, stride


def new_struct(ctype: str, value: Any = None) -> Any:
    """A new C struct (a pointer to it), optionally initialised from ``value``."""
    return ffi.new(ctype + " *", value)


def set_fields(struct: Any, **values: Any) -> None:
    """Sets each field of ``struct`` whose value is not None."""
    for key, value in values.items():
        if value is not None:
            setattr(struct, key, value)


def write_bytes(capacity: int, write: Any, function: str, call: Optional[Call] = None) -> bytearray:
    """Calls an output byte buffer function ``write(out, capacity, written)``
    into a new bytearray, truncated in place to what was written."""
    buf = bytearray(max(int(capacity), 1))
    written = ffi.new("size_t *")
    with ffi.from_buffer(buf) as out:
        status = write(out, int(capacity), written)
    if call is not None:
        call.check(status, function)
    else:
        check(status, function)
    del buf[written[0]:]
    return buf


class Call:
    """One long call's PelageRun: its thread count and its progress callback.

    The callback (one cffi callback for the process, told apart by a
    handle) runs on the calling thread with the GIL, which cffi takes back
    for it; an exception in it cancels the call and is re-raised by
    :meth:`check` in place of :class:`pelage.Cancelled`.
    """

    def __init__(self, threads: Optional[int], progress: Optional[ProgressFn]) -> None:
        self.threads = threads
        self.progress = progress
        self.error: Optional[BaseException] = None
        self._handle = ffi.new_handle(self) if progress is not None else None

    def fill(self, run: Any) -> None:
        """Writes this call's settings into a PelageRun struct (its fields
        keep their defaults where the caller gave None)."""
        if self.threads is not None:
            if self.threads < 0:
                raise ValueError("threads must be >= 0 (0: every core)")
            run.thread_count = self.threads
        if self._handle is not None:
            run.progress = _PROGRESS
            run.progress_user_data = self._handle

    def run(self) -> Any:
        """A PelageRun value for the calls that take it by value."""
        run = ffi.new("PelageRun *", lib.pelage_run_defaults())
        self.fill(run)
        return run[0]

    def check(self, status: int, function: str, colliders: Sequence[Any] = ()) -> None:
        """Raises what the callbacks raised (progress first, then a distance
        field's), else the status's exception."""
        errors: List[BaseException] = []
        if self.error is not None:
            errors.append(self.error)
        for c in colliders:
            if c is not None:
                errors.extend(c._take_errors())
        if errors:
            error = errors[0]
            if status != lib.PELAGE_STATUS_OK and hasattr(error, "add_note"):
                message = ffi.string(lib.pelage_last_error()).decode("utf-8", "replace")
                error.add_note(f"pelage: raised in a callback of {function}, which then failed: {message}")
            raise error
        check(status, function)


@ffi.callback("PelageProgressFn")
def _PROGRESS(user_data: Any, fraction: float) -> bool:
    call: Call = ffi.from_handle(user_data)
    if call.error is not None:
        return False
    try:
        result = call.progress(fraction)  # type: ignore[misc]
    except BaseException as error:  # noqa: BLE001 - re-raised by Call.check
        call.error = error
        return False
    return result is None or bool(result)
