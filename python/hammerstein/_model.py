"""The estimator :class:`Hammerstein` and the fitted :class:`Model`."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import _hammerstein as _h
from ._data import ArrayLike, IoData, record
from ._errors import InputError

if TYPE_CHECKING:
    from ._feedback import FeedbackModel

EffectList = Union[str, Sequence[str]]

#: The UDN's effects, as ``--effects`` names them.
EFFECTS = ("hysteresis", "dead-zone", "saturation", "preload", "prandtl-ishlinskii")


def _effect_list(e: Optional[EffectList], what: str) -> Optional[str]:
    """An effect list as the command line's comma-separated text (``None``: none given)."""
    if e is None:
        return None
    if isinstance(e, str):
        return e
    try:
        items = list(e)
    except TypeError:
        raise InputError(f"{what}: a list of effect names is needed, got {e!r}") from None
    for x in items:
        if not isinstance(x, str):
            raise InputError(f"{what}: effect names are strings, got {x!r}")
    return ",".join(items) if items else "linear"


@dataclass(frozen=True)
class TransferFunction:
    """The linear block's b(z⁻¹)/a(z⁻¹): ``numerator`` b0..bn (b0 = D), ``denominator``
    1, a1..an (one input)."""

    numerator: np.ndarray
    denominator: np.ndarray


@dataclass(frozen=True)
class StateSpace:
    """A discrete-time linear block x(k+1) = A x(k) + B u(k), y(k) = C x(k) + D u(k)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    ts: float

    def __iter__(self):
        return iter((self.A, self.B, self.C, self.D))


class Model:
    """A fitted Hammerstein model (returned by :meth:`Hammerstein.fit` and :func:`load`).

    ``simulate(u)`` gives its output for an input record; ``parameters`` (name → value),
    ``standard_errors``, ``poles``, ``transfer_function``, ``linear`` (A, B, C, D), ``order``,
    ``report`` (training MSE, order, termination, …) describe it; ``save(path)`` writes the
    model file the command line's ``--save`` writes (and ``hammerstein compare`` reads).
    """

    __slots__ = ("_m", "_info")

    def __init__(self, compiled: "_h.Model") -> None:
        self._m = compiled
        self._info: Dict[str, Any] = json.loads(compiled.describe())

    # --- what it is ---------------------------------------------------------------------
    @property
    def precision(self) -> str:
        """"f64" or "f32": the scalar type it was fitted in (loaded models are f64)."""
        return self._m.precision

    @property
    def n_inputs(self) -> int:
        """Number of inputs."""
        return int(self._m.n_inputs)

    @property
    def parameters(self) -> Dict[str, float]:
        """The nonlinearity's parameters by name ("input.name" with several inputs)."""
        return {k: v for k, v, _ in self._info["parameters"]}

    @property
    def standard_errors(self) -> Dict[str, Optional[float]]:
        """Each parameter's standard error (``None`` where the fit gives none)."""
        return {k: se for k, _, se in self._info["parameters"]}

    @property
    def effects(self) -> Union[List[str], List[List[str]], None]:
        """The UDN's effects (one list per input with several inputs)."""
        if self.n_inputs == 1:
            return self._info["effects"]
        return [b["effects"] for b in self._info["branches"]]

    @property
    def nonlinearity(self) -> str:
        """The nonlinearity's name."""
        if self.n_inputs == 1:
            return self._info["nonlinearity"]
        return " | ".join(b["nonlinearity"] for b in self._info["branches"])

    @property
    def output_nonlinearity(self) -> Optional[Dict[str, Any]]:
        """The static map after the linear block (name and parameters), if any."""
        on = self._info.get("output_nonlinearity")
        if not on:
            return None
        return {"name": on["name"], "parameters": {k: v for k, v, _ in on["parameters"]}}

    @property
    def order(self) -> int:
        """Order of the linear block."""
        return int(self._info["order"])

    @property
    def delay(self) -> int:
        """Input delay in samples (one input)."""
        return int(self._info.get("delay", 0))

    @property
    def sample_time(self) -> float:
        """Sample time in seconds (1 when the record gave none)."""
        return float(self._info["sample_time"])

    @property
    def decimation(self) -> int:
        """The decimation factor the model file records (1: none); records given to
        ``simulate`` and ``compare`` are taken at the model's rate."""
        return int(self._m.decimation)

    @property
    def linear(self) -> StateSpace:
        """The linear block (A, B, C, D); with several inputs the branches side by side."""
        i = self._info
        return StateSpace(*(np.array(i[k], dtype=float) for k in "ABCD"), ts=self.sample_time)

    @property
    def poles(self) -> np.ndarray:
        """The linear block's poles (complex)."""
        return np.array([complex(re, im) for re, im in self._info["poles"]])

    @property
    def transfer_function(self) -> TransferFunction:
        """b(z⁻¹)/a(z⁻¹) of the linear block (one input)."""
        if self.n_inputs != 1:
            raise InputError("transfer_function: one input only (see .linear)")
        return TransferFunction(
            np.array(self._info["numerator"], dtype=float),
            np.array(self._info["denominator"], dtype=float),
        )

    @property
    def report(self) -> Dict[str, Any]:
        """What the fit did: ``train_mse``, ``order``, ``termination``, ``converged``,
        ``iterations``, ``refined``, ``horizon``, the order selection's candidates, …"""
        return dict(self._info["report"])

    def describe(self) -> Dict[str, Any]:
        """Everything above as one dict (what ``hammerstein fit --json`` prints about the
        model, without the metrics)."""
        return json.loads(self._m.describe())

    # --- what it does -------------------------------------------------------------------
    def simulate(self, u: ArrayLike) -> np.ndarray:
        """The model's output for input ``u`` (1-D, or N × m for several inputs), from a
        zero state. A diverging simulation raises :class:`HammersteinError`."""
        data_u = _input(u, self.n_inputs, self.precision)
        return self._m.simulate(data_u)

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the model file (JSON; atomically) that ``hammerstein fit --save`` writes;
        ``hammerstein compare`` and ``simulate`` read it, :func:`load` reads it back."""
        self._m.save(os.fspath(path))

    def to_json(self) -> str:
        """The model file's text."""
        return self._m.to_json()

    def __repr__(self) -> str:
        eff = self.effects
        return (
            f"<hammerstein.Model {self.nonlinearity} effects={eff} order={self.order} "
            f"inputs={self.n_inputs} {self.precision}>"
        )


def _input(u: ArrayLike, m: int, precision: str) -> np.ndarray:
    """An input record checked against the model: N × m of the model's precision."""
    from ._data import _columns, _real

    a = _columns(_real(u, "u"), "u")
    if a.shape[1] != m:
        raise InputError(f"u has {a.shape[1]} columns: the model has {m} input(s)")
    if a.shape[0] < 2:
        raise InputError(f"not enough samples: 2 needed (simulation), got {a.shape[0]}")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        raise InputError(f"non-finite value (NaN or infinity) in u at sample {bad[0][0]}")
    dtype = np.float32 if precision == "f32" else np.float64
    return np.ascontiguousarray(a, dtype=dtype)


class Hammerstein:
    """The estimator: settings of a Hammerstein fit, in the scikit-learn manner.

    ``Hammerstein(effects=["saturation", "hysteresis"]).fit(u, y)`` fits the UDN nonlinearity
    with those effects into a linear state-space block and returns a :class:`Model`. The
    arguments are the command line's (``hammerstein fit --help``), with its defaults:

    - ``effects``: the UDN's effects (``"hysteresis"``, ``"dead-zone"``, ``"saturation"``,
      ``"preload"``, and ``"prandtl-ishlinskii"`` for dynamic hysteresis), a list or a
      comma-separated string; ``[]`` or ``"linear"``: none. With several inputs one list per
      input (a list of lists, or a dict input index → list). ``None``: by ``nonlinearity``.
    - ``order``: the linear block's order, a number, ``"auto"`` (every order fitted, the
      lowest BIC kept; also ``None``) or ``"gap"``.
    - ``output_nonlinearity``: a static map after the linear block (Hammerstein–Wiener):
      ``"poly3"`` (``"polyK"``), ``"saturation"`` or ``"pwl:K"``.
    - ``nonlinearity``: ``"udn"``, ``"sh"``, ``"linear"`` (default) or ``"poly3"`` when
      ``effects`` is ``None``.
    - ``method`` (``"moesp"``, ``"n4sid"``, ``"n4sid-unweighted"``), ``horizon`` (block rows;
      ``None``: the method's), ``delay`` (input delay in samples), ``refine`` (the
      output-error refinement, on), ``stable`` (every pole within radius 0.9999),
      ``feedthrough`` (``"auto"``, ``"on"``, ``"off"``), ``seed``, ``backend``
      (``"faer"``).
    - ``precision``: ``"f32"`` or ``"f64"``; ``None``: f32 when u and y are float32 arrays.

    The fit releases the GIL: other Python threads run meanwhile.
    """

    def __init__(
        self,
        effects: Union[EffectList, Sequence[EffectList], Mapping[int, EffectList], None] = None,
        order: Union[int, str, None] = None,
        output_nonlinearity: Optional[str] = None,
        *,
        nonlinearity: Optional[str] = None,
        method: str = "moesp",
        horizon: Optional[int] = None,
        delay: int = 0,
        refine: bool = True,
        stable: bool = False,
        feedthrough: str = "auto",
        seed: int = 0,
        backend: str = "faer",
        precision: Optional[str] = None,
    ) -> None:
        self.effects = effects
        self.order = order
        self.output_nonlinearity = output_nonlinearity
        self.nonlinearity = nonlinearity
        self.method = method
        self.horizon = horizon
        self.delay = delay
        self.refine = refine
        self.stable = stable
        self.feedthrough = feedthrough
        self.seed = seed
        self.backend = backend
        self.precision = precision

    def get_params(self) -> Dict[str, Any]:
        """The settings as a dict (scikit-learn's ``get_params``)."""
        return {
            k: getattr(self, k)
            for k in (
                "effects", "order", "output_nonlinearity", "nonlinearity", "method",
                "horizon", "delay", "refine", "stable", "feedthrough", "seed", "backend",
                "precision",
            )
        }

    def set_params(self, **params: Any) -> "Hammerstein":
        """Changes settings (scikit-learn's ``set_params``); returns ``self``."""
        known = self.get_params()
        for k, v in params.items():
            if k not in known:
                raise InputError(f"unknown setting '{k}' (known: {', '.join(known)})")
            setattr(self, k, v)
        return self

    def _effects_per_input(self, m: int) -> List[Optional[str]]:
        e = self.effects
        if m == 1:
            if isinstance(e, Mapping):
                raise InputError("effects: a dict is for several inputs")
            if e is not None and not isinstance(e, str) and any(
                not isinstance(x, str) for x in e
            ):
                raise InputError("effects: one input takes one list of effect names")
            return [_effect_list(e, "effects")]
        if e is None:
            return [None] * m
        if isinstance(e, str) or (
            isinstance(e, Sequence) and all(isinstance(x, str) for x in e) and len(e) > 0
        ):
            raise InputError(
                f"effects: with {m} inputs give one list per input "
                "(a list of lists, or a dict input index → list)"
            )
        if isinstance(e, Mapping):
            out: List[Optional[str]] = [None] * m
            for k, v in e.items():
                if not isinstance(k, int) or not 0 <= k < m:
                    raise InputError(f"effects: {k!r} is not an input index (0..{m - 1})")
                out[k] = _effect_list(v, f"effects[{k}]")
            return out
        lists = list(e)
        if len(lists) != m:
            raise InputError(f"effects: {len(lists)} lists for {m} inputs")
        return [_effect_list(v, f"effects[{i}]") for i, v in enumerate(lists)]

    def _settings(self, m: int) -> str:
        order = "auto" if self.order is None else str(self.order)
        for name in ("delay", "seed"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise InputError(f"{name} must be a non-negative integer, got {v!r}")
        if self.horizon is not None and (
            isinstance(self.horizon, bool)
            or not isinstance(self.horizon, (int, np.integer))
            or self.horizon < 1
        ):
            raise InputError(f"horizon must be a positive integer, got {self.horizon!r}")
        fb = self.feedthrough
        if isinstance(fb, bool):
            fb = "on" if fb else "off"
        return json.dumps(
            {
                "effects": self._effects_per_input(m),
                "nonlinearity": self.nonlinearity,
                "method": str(self.method),
                "order": order,
                "horizon": None if self.horizon is None else int(self.horizon),
                "delay": int(self.delay),
                "refine": bool(self.refine),
                "stable": bool(self.stable),
                "feedthrough": str(fb),
                "seed": int(self.seed),
                "output_nonlinearity": self.output_nonlinearity,
                "backend": str(self.backend),
            }
        )

    def _precision(self, data: IoData) -> str:
        p = self.precision or data.precision
        if p not in ("f32", "f64"):
            raise InputError(f"unknown precision '{p}' (f32 or f64)")
        return p

    def fit(
        self,
        u: Union[IoData, ArrayLike],
        y: Optional[ArrayLike] = None,
        ts: Optional[float] = None,
    ) -> Model:
        """Fits the model to the record (``u``, ``y``) (or an :class:`IoData`); ``ts``: the
        sample time in seconds. Bad input raises :class:`InputError` (a ``ValueError``), a
        failed fit :class:`HammersteinError`."""
        data = record(u, y, ts)
        p = self._precision(data)
        data = data.cast(p)
        return Model(_h.fit(data.u, data.y, data.ts, p, self._settings(data.n_inputs)))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items() if v is not None)
        return f"Hammerstein({args})"


def load(path: Union[str, "os.PathLike[str]"]) -> Union[Model, "FeedbackModel"]:
    """Reads a model file (written by :meth:`Model.save` or ``hammerstein fit --save``); a
    feedback model's file (``fit --feedback-nonlinearity --save``) gives a
    :class:`FeedbackModel`."""
    from ._feedback import is_feedback_text, loads_feedback

    p = os.fspath(path)
    try:
        with open(p, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError):
        text = ""  # the compiled reader reports it in the crate's words
    if text and is_feedback_text(text):
        return loads_feedback(text, p)
    return Model(_h.load(p))


def loads(text: str) -> Union[Model, "FeedbackModel"]:
    """A model from a model file's text (:meth:`Model.to_json`, :meth:`FeedbackModel.to_json`)."""
    from ._feedback import is_feedback_text, loads_feedback

    if is_feedback_text(text):
        return loads_feedback(text)
    return Model(_h.loads(text))
