"""Records: numpy arrays checked and shaped for the compiled module."""

from __future__ import annotations

from typing import Optional, Sequence, Tuple, Union

import numpy as np

from ._errors import InputError

ArrayLike = Union[np.ndarray, Sequence[float], Sequence[Sequence[float]]]


def _real(x: object, name: str) -> np.ndarray:
    """``x`` as a numpy array of reals (float32 kept, integers and float16 made float64)."""
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists and the like
        raise InputError(f"{name}: not an array of numbers ({e})") from None
    if a.dtype.kind in "iub" or a.dtype == np.float16:
        a = a.astype(np.float64)
    elif a.dtype.kind != "f" or a.dtype.itemsize > 8:
        raise InputError(
            f"{name} has dtype {a.dtype}: real numbers are needed (float64 or float32)"
        )
    return a


def _columns(a: np.ndarray, name: str) -> np.ndarray:
    """1-D (one channel) or 2-D (samples × channels) → 2-D."""
    if a.ndim == 1:
        return a.reshape(-1, 1)
    if a.ndim == 2:
        if a.shape[1] == 0:
            raise InputError(f"{name} has shape {a.shape}: no channel")
        return a
    raise InputError(
        f"{name} has shape {a.shape}: 1-D (one channel) or 2-D (samples × channels) is needed"
    )


class IoData:
    """A measured record: inputs ``u``, outputs ``y`` and the sample time ``ts``.

    ``u`` is 1-D for one input or 2-D with one column per input; ``y`` is 1-D (or 2-D with
    one column per output: several outputs only for :func:`hammerstein.subspace`). Arrays of
    float32 are kept in single precision (the fit then runs in f32), anything else real is
    taken as float64. NaN, infinity, mismatched lengths, a constant channel, a wrong dtype or
    shape raise :class:`hammerstein.InputError` (a ``ValueError``).
    """

    __slots__ = ("u", "y", "ts")

    def __init__(self, u: ArrayLike, y: ArrayLike, ts: Optional[float] = None) -> None:
        uu = _columns(_real(u, "u"), "u")
        yy = _columns(_real(y, "y"), "y")
        if uu.shape[0] != yy.shape[0]:
            raise InputError(
                f"length mismatch: input has {uu.shape[0]} samples, output has {yy.shape[0]}"
            )
        if uu.shape[0] < 2:
            raise InputError(f"not enough samples: 2 needed, got {uu.shape[0]}")
        for a, name in ((uu, "u"), (yy, "y")):
            bad = np.argwhere(~np.isfinite(a))
            if bad.size:
                k, j = bad[0]
                ch = name if a.shape[1] == 1 else f"{name}{j + 1}"
                raise InputError(
                    f"non-finite value (NaN or infinity) in {ch} at sample {k}"
                )
        if ts is None:
            ts = 1.0
        ts = float(ts)
        if not (np.isfinite(ts) and ts > 0):
            raise InputError(f"sample time must be positive and finite, got {ts}")
        dtype = np.float32 if uu.dtype == np.float32 and yy.dtype == np.float32 else np.float64
        self.u: np.ndarray = np.ascontiguousarray(uu, dtype=dtype)
        self.y: np.ndarray = np.ascontiguousarray(yy, dtype=dtype)
        self.ts: float = ts

    @property
    def precision(self) -> str:
        """"f32" when both arrays are float32, else "f64"."""
        return "f32" if self.u.dtype == np.float32 else "f64"

    @property
    def n_inputs(self) -> int:
        """Number of inputs (columns of ``u``)."""
        return int(self.u.shape[1])

    @property
    def n_outputs(self) -> int:
        """Number of outputs (columns of ``y``)."""
        return int(self.y.shape[1])

    def __len__(self) -> int:
        return int(self.u.shape[0])

    def cast(self, precision: str) -> "IoData":
        """The same record in ``precision`` ("f32" or "f64")."""
        if precision == self.precision:
            return self
        dtype = {"f32": np.float32, "f64": np.float64}.get(precision)
        if dtype is None:
            raise InputError(f"unknown precision '{precision}' (f32 or f64)")
        out = IoData.__new__(IoData)
        out.u = np.ascontiguousarray(self.u, dtype=dtype)
        out.y = np.ascontiguousarray(self.y, dtype=dtype)
        out.ts = self.ts
        return out

    def split(self, fraction: float) -> Tuple["IoData", "IoData"]:
        """(training, validation): the last ``fraction`` of the samples held out."""
        if not 0.0 < fraction < 1.0:
            raise InputError(f"validation fraction must lie in (0, 1), got {fraction}")
        n_val = int(np.floor(len(self) * fraction + 0.5))  # half away from zero, as Rust
        k = len(self) - n_val
        if n_val < 2 or k < 2:
            raise InputError(
                f"not enough samples: 4 needed (splitting off a validation fraction of "
                f"{fraction}), got {len(self)}"
            )
        a, b = IoData.__new__(IoData), IoData.__new__(IoData)
        a.u, a.y, a.ts = self.u[:k], self.y[:k], self.ts
        b.u, b.y, b.ts = self.u[k:], self.y[k:], self.ts
        return a, b

    def __repr__(self) -> str:
        return (
            f"IoData({len(self)} samples, {self.n_inputs} input(s), {self.n_outputs} "
            f"output(s), ts={self.ts:g}, {self.precision})"
        )


def record(
    u: Union[IoData, ArrayLike],
    y: Optional[ArrayLike] = None,
    ts: Optional[float] = None,
    *,
    one_output: bool = True,
) -> IoData:
    """An :class:`IoData` from ``(u, y, ts)`` or from an ``IoData`` given as ``u``."""
    if isinstance(u, IoData):
        if y is not None:
            raise InputError("give either an IoData or the arrays u and y, not both")
        data = u if ts is None else IoData(u.u, u.y, ts)
    else:
        if y is None:
            raise InputError("the output y is missing")
        data = IoData(u, y, ts)
    if one_output and data.n_outputs != 1:
        raise InputError(
            f"y has {data.n_outputs} columns: the model has one output (1-D y)"
        )
    return data
