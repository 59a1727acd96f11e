"""Input checks shared by the public classes: each names what it rejects."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def float_array(name: str, value: Any, shape: tuple[int | None, ...]) -> NDArray[np.float64]:
    """``value`` as a C-contiguous float64 array of ``shape`` (None: any length),
    all finite; otherwise ``ValueError`` naming ``name``."""
    try:
        a = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 - any conversion failure is bad input
        raise ValueError(f"{name}: cannot be read as an array ({exc})") from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.number) or a.dtype == bool):
        raise ValueError(f"{name}: expected numbers, got dtype {a.dtype}")
    if np.iscomplexobj(a):
        raise ValueError(f"{name}: complex values are not allowed")
    _check_shape(name, a, shape)
    a = np.ascontiguousarray(a, dtype=np.float64)
    bad = ~np.isfinite(a)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise ValueError(f"{name}: entry {row} is NaN or infinite")
    return a


def index_array(name: str, value: Any, shape: tuple[int | None, ...], upper: int | None = None) -> NDArray[np.int64]:
    """``value`` as a C-contiguous int64 array of ``shape`` with entries in
    ``[0, upper)``; floats are accepted only when integral."""
    try:
        a = np.asarray(value)
    except Exception as exc:  # noqa: BLE001
        raise ValueError(f"{name}: cannot be read as an array ({exc})") from None
    if a.size == 0:
        a = a.astype(np.int64).reshape([0 if s is None else s for s in shape] if None in shape else shape)
    if a.dtype == bool or not np.issubdtype(a.dtype, np.number) or np.iscomplexobj(a):
        raise ValueError(f"{name}: expected integer ids, got dtype {a.dtype}")
    _check_shape(name, a, shape)
    if not np.issubdtype(a.dtype, np.integer):
        if not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
            raise ValueError(f"{name}: ids must be integers")
        if a.size and np.abs(a).max() >= 2.0**62:
            raise ValueError(f"{name}: id {np.abs(a).max():g} is out of range")
    elif a.dtype == np.uint64 and a.size and a.max() >= 2**62:
        raise ValueError(f"{name}: id {a.max()} is out of range")
    a = np.ascontiguousarray(a, dtype=np.int64)
    if a.size:
        lo = int(a.min())
        if lo < 0:
            raise ValueError(f"{name}: id {lo} is negative")
        if upper is not None and int(a.max()) >= upper:
            raise ValueError(f"{name}: id {int(a.max())} is out of range (there are {upper})")
    return a


def _check_shape(name: str, a: np.ndarray, shape: tuple[int | None, ...]) -> None:
    ok = a.ndim == len(shape) and all(s is None or s == d for s, d in zip(shape, a.shape, strict=False))
    if not ok:
        dims = ["n" if s is None else str(s) for s in shape]
        want = f"({dims[0]},)" if len(dims) == 1 else "(" + ", ".join(dims) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {a.shape}")


def positive(name: str, value: Any, *, allow_zero: bool = False) -> float:
    """A finite positive (or non-negative) float."""
    v = number(name, value)
    if v < 0 or (v == 0 and not allow_zero):
        raise ValueError(f"{name} = {v} must be {'>= 0' if allow_zero else 'positive'}")
    return v


def number(name: str, value: Any) -> float:
    """A finite float."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(v):
        raise ValueError(f"{name} = {v} must be finite")
    return v


def whole(name: str, value: Any, *, minimum: int = 1, maximum: int = 2**31 - 1) -> int:
    """An integer in ``[minimum, maximum]`` (integral floats accepted);
    anything else, NaN and infinities included, is a ``ValueError``."""
    try:
        k = int(value)
        ok = k == value and minimum <= k <= maximum
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{name} = {value!r} must be an integer in [{minimum}, {maximum}]")
    return k
