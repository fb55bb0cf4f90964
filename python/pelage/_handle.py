"""The base of the classes that own a C handle."""

from __future__ import annotations

from typing import Any, Callable, Optional

from ._ffi import ffi


class Handle:
    """Owns one C handle, released by :meth:`close` (or on leaving a
    ``with`` block; as a last resort when garbage collected)."""

    _free: Optional[Callable[[Any], None]] = None

    def __init__(self) -> None:
        self._ptr: Any = ffi.NULL

    @property
    def closed(self) -> bool:
        """Whether the handle has been released."""
        return self._ptr == ffi.NULL

    def _get(self) -> Any:
        if self._ptr == ffi.NULL:
            raise ValueError(f"{type(self).__name__} is closed")
        return self._ptr

    def close(self) -> None:
        """Releases the C object now; later calls on it raise ValueError.
        Closing twice does nothing."""
        handle, self._ptr = self._ptr, ffi.NULL
        if handle != ffi.NULL and self._free is not None:
            type(self)._free(handle)  # type: ignore[misc]
        self._release()

    def _release(self) -> None:
        """What a subclass frees after its handle."""

    def __enter__(self):  # type: ignore[no-untyped-def]
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass
