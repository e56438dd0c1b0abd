"""``subspace``: a linear state-space model of a record (MOESP or N4SID)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Optional, Union

import numpy as np

from . import _hammerstein as _h
from ._data import ArrayLike, IoData, record
from ._errors import InputError


@dataclass(frozen=True)
class Subspace:
    """An identified linear model: ``A``, ``B``, ``C``, ``D`` (numpy arrays; unpack as
    ``A, B, C, D = hammerstein.subspace(u, y)``), the initial state ``x0``, the
    ``singular_values`` the order was read from, the ``order``, ``horizon``, ``method`` and
    ``sample_time``; ``stabilised_from``: the spectral radius of the estimate that
    ``stable=True`` replaced (``None`` when nothing was replaced)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    x0: np.ndarray = field(repr=False)
    singular_values: np.ndarray = field(repr=False)
    order: int = 0
    horizon: int = 0
    method: str = ""
    sample_time: float = 1.0
    stabilised_from: Optional[float] = None

    def __iter__(self):
        return iter((self.A, self.B, self.C, self.D))


def subspace(
    u: Union[IoData, ArrayLike],
    y: Optional[ArrayLike] = None,
    method: str = "moesp",
    order: Union[int, str, None] = "auto",
    horizon: Optional[int] = None,
    *,
    stable: bool = False,
    detrend: bool = True,
    with_d: bool = True,
    ts: Optional[float] = None,
) -> Subspace:
    """Identifies a linear state-space model, as ``hammerstein subspace`` does.

    ``method``: ``"moesp"``, ``"n4sid"`` or ``"n4sid-unweighted"``; ``order``: a number,
    ``"auto"`` (the largest singular-value log gap) or ``"threshold:T"``; ``horizon``: block
    rows (``None``: 10, raised for a fixed order that needs more); ``stable``: the
    guaranteed-stable A of Maciejowski (1995); ``detrend``: each channel's mean removed
    first; ``with_d``: estimate D (``False``: D = 0). ``y`` may have several columns.
    """
    data = record(u, y, ts, one_output=False)
    if horizon is not None and (
        isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < 1
    ):
        raise InputError(f"horizon must be a positive integer, got {horizon!r}")
    o = "auto" if order is None else str(order)
    text = _h.subspace(
        data.u, data.y, data.ts, data.precision, str(method), o,
        None if horizon is None else int(horizon), bool(stable), bool(detrend), bool(with_d),
    )
    d = json.loads(text)
    n, m, l = d["order"], data.n_inputs, data.n_outputs
    return Subspace(
        A=np.array(d["A"], dtype=float).reshape(n, n),
        B=np.array(d["B"], dtype=float).reshape(n, m),
        C=np.array(d["C"], dtype=float).reshape(l, n),
        D=np.array(d["D"], dtype=float).reshape(l, m),
        x0=np.array(d["x0"], dtype=float),
        singular_values=np.array(d["singular_values"], dtype=float),
        order=int(n),
        horizon=int(d["horizon"]),
        method=d["method"],
        sample_time=float(d["sample_time"]),
        stabilised_from=d["stabilised_from"],
    )
