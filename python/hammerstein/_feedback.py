"""The estimator :class:`Feedback` and the fitted :class:`FeedbackModel`: a linear block with
a static nonlinearity in feedback (a nonlinear LFR, or Lur'e system), as ``hammerstein fit
--feedback-nonlinearity`` fits it."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hammerstein as _h
from ._data import ArrayLike, IoData, record
from ._errors import InputError

#: The built-in feedback nonlinearities, as ``--feedback-nonlinearity`` names them (and
#: ``"pwl:K"``, K linear segments).
FEEDBACK_NONLINEARITIES = ("poly3", "poly5", "coulomb", "dead-zone", "saturation")


class FeedbackModel:
    """A fitted feedback model (returned by :meth:`Feedback.fit` and :func:`hammerstein.load`)::

        x(k+1) = A x(k) + B (v(k) + u0) + E w(k),   y(k) = g(C x(k) + D v(k)) + y0,
        w(k) = f(z(k)),   z = C x (``on="output"``), its first difference (``"velocity"``)
        or F x with F estimated (``"state"``), v = N(u) with an input nonlinearity (else
        v = u), g the output map (else the identity); z is the linear block's own output,
        before g

    ``simulate(u)`` gives its output from rest; ``f(z)`` the nonlinearity in the record's
    units; ``parameters`` (f's coefficients by name, in the model's normalised units),
    ``order``, ``on``, ``nonlinearity``, ``input_nonlinearity`` and ``output_nonlinearity``
    (their names, ``None`` without one; ``input_map(u)`` and ``output_map(l)`` evaluate
    them), ``z_range`` (the z the training record visited),
    ``report`` (training RMS errors, iterations, …; ``None`` for a loaded model) describe it;
    ``save(path)`` writes the model file ``hammerstein fit --feedback-nonlinearity --save``
    writes (``hammerstein compare`` and ``simulate`` read it).
    """

    __slots__ = ("_m", "_file", "_report")

    def __init__(self, compiled: "_h.Feedback", report: Optional[Dict[str, Any]] = None) -> None:
        self._m = compiled
        self._file: Dict[str, Any] = json.loads(compiled.to_json())
        self._report = report

    @property
    def n_inputs(self) -> int:
        """Number of inputs (1)."""
        return 1

    @property
    def precision(self) -> str:
        """"f64": feedback models are fitted in double precision."""
        return "f64"

    @property
    def order(self) -> int:
        """Order n of the linear block."""
        return len(self._file["b"])

    @property
    def on(self) -> str:
        """What the nonlinearity acts on: ``"output"``, ``"velocity"`` or ``"state"``."""
        return str(self._file["feedback"]["on"])

    @property
    def state_combination(self) -> Optional[np.ndarray]:
        """F of ``on="state"`` (z = F x in the linear block's state coordinates, scaled so
        that z has the RMS of C x on the training record); ``None`` otherwise."""
        f = self._file["feedback"].get("state_combination")
        return None if not f else np.array(f, dtype=float)

    @property
    def nonlinearity(self) -> str:
        """The nonlinearity's name as the command line spells it (``"poly3"``, ``"coulomb"``,
        …)."""
        return str(self._m.name)

    @property
    def input_nonlinearity(self) -> Optional[str]:
        """The input nonlinearity N before the loop (its name, as ``Model.nonlinearity``
        spells it), ``None`` without one."""
        return self._m.input_name

    @property
    def output_nonlinearity(self) -> Optional[str]:
        """The output map g after the loop (``"poly3"``, ``"saturation"``, ``"pwl:K"``),
        ``None`` without one."""
        return self._m.output_name

    def input_map(self, u: ArrayLike) -> Optional[np.ndarray]:
        """N over ``u`` (the input the linear block receives, in the input's units);
        ``None`` without an input nonlinearity."""
        uu = np.ascontiguousarray(np.asarray(u, dtype=np.float64).reshape(-1))
        return self._m.input_map(uu)

    def output_map(self, l: ArrayLike) -> Optional[np.ndarray]:
        """g over the linear output ``l`` = C x + D v (in the output's units, before the
        offset); ``None`` without an output map."""
        ll = np.ascontiguousarray(np.asarray(l, dtype=np.float64).reshape(-1))
        return self._m.output_map(ll)

    @property
    def parameters(self) -> Dict[str, float]:
        """f's parameters by name (normalised units; :meth:`f` evaluates f in the record's
        units), and ``viscous`` for feedback on the velocity."""
        nl = self._file["feedback"]["nonlinearity"]
        p = {str(k): float(v) for k, v in zip(nl["param_names"], nl["params"])}
        if self.on == "velocity":
            p["viscous"] = float(self._file["feedback"]["viscous"])
        return p

    @property
    def linear(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D, E) of the linear block, in the model's normalised units."""
        f = self._file
        n = self.order
        return (
            np.array(f["a"], dtype=float).reshape(n, n),
            np.array(f["b"], dtype=float).reshape(n, 1),
            np.array(f["c"], dtype=float).reshape(1, n),
            np.array([[f["d"]]], dtype=float),
            np.array(f["feedback"]["e"], dtype=float).reshape(n, 1),
        )

    @property
    def poles(self) -> np.ndarray:
        """The poles of the linear block A (the loop's linearisation at z = 0 when f has
        no linear part)."""
        return np.linalg.eigvals(self.linear[0])

    @property
    def z_range(self) -> Tuple[float, float]:
        """The range of z the training record visited, in the output's units."""
        lo, hi = self._m.z_range
        return float(lo), float(hi)

    @property
    def decimation(self) -> int:
        """The decimation factor the model file records (1: none)."""
        return int(self._m.decimation)

    @property
    def report(self) -> Optional[Dict[str, Any]]:
        """What the fit did (``linear_rms``, ``start_rms``, ``train_rms``,
        ``validation_rms``, ``validation_fit_percent``, ``iterations``,
        ``refused_diverging_steps``, ``warnings``: the fields of ``hammerstein fit
        --feedback-nonlinearity --json``); ``None`` for a loaded model."""
        return None if self._report is None else dict(self._report)

    def f(self, z: ArrayLike) -> np.ndarray:
        """The nonlinearity over ``z`` in the record's units: z in the output's units (per
        sample for ``velocity``), w as the input that would act the same way."""
        zz = np.ascontiguousarray(np.asarray(z, dtype=np.float64).reshape(-1))
        return self._m.f(zz)

    def simulate(self, u: ArrayLike) -> np.ndarray:
        """The output for the input ``u`` (1-D) from rest, as ``hammerstein simulate``; a
        diverging loop raises :class:`HammersteinError`."""
        from ._data import _columns, _real

        a = _columns(_real(u, "u"), "u")
        if a.shape[1] != 1:
            raise InputError(f"u has {a.shape[1]} columns: a feedback model has one input")
        if a.shape[0] < 2:
            raise InputError(f"not enough samples: 2 needed (simulation), got {a.shape[0]}")
        bad = np.flatnonzero(~np.isfinite(a[:, 0]))
        if bad.size:
            raise InputError(f"non-finite value (NaN or infinity) in u at sample {bad[0]}")
        return self._m.simulate(np.ascontiguousarray(a[:, 0], dtype=np.float64))

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the model file (JSON, atomically)."""
        self._m.save(os.fspath(path))

    def to_json(self) -> str:
        """The model file's text."""
        return self._m.to_json()

    def describe(self) -> Dict[str, Any]:
        """The model file as a dict."""
        return json.loads(self._m.to_json())

    def __repr__(self) -> str:
        return (
            f"<hammerstein.FeedbackModel {self.nonlinearity} on {self.on} order={self.order}>"
        )


class Feedback:
    """The estimator of a feedback model, as ``hammerstein fit --feedback-nonlinearity``:

    - ``nonlinearity``: ``"poly3"`` (c₃ z³, a Duffing stiffness), ``"poly5"``, ``"coulomb"``
      (smoothed sign: friction), ``"dead-zone"`` (clearance), ``"saturation"`` or
      ``"pwl:K"`` (K linear segments);
    - ``on``: ``"output"`` (stiffness), ``"velocity"`` (the output's first difference:
      friction) or ``"state"`` (a combination z = F x of the states, F estimated);
    - ``order``: the linear block's order, a number or ``"auto"`` (also ``None``: the
      singular-value gap's order n and n + 1 fitted, the lower AIC kept) or ``"gap"``;
    - ``horizon``: the subspace block rows (``None``: 10); ``feedthrough``: ``"auto"`` and
      ``"off"`` fit no D, ``"on"`` a D (refused with ``on="velocity"``);
    - ``max_iterations`` (100) and ``tolerance`` (0.1) of the output-error refinement: it
      stops when a step lowers N ln(MSE) by less than ``tolerance``;
    - ``effects``: an input nonlinearity N before the loop, the UDN with these effects
      (``"saturation"``, ``"dead-zone"``, …, a list or a comma-separated string: the
      command line's ``--effects``), or ``input_nonlinearity``: ``"udn"``, ``"sh"``,
      ``"linear"`` or ``"poly3"`` (the command line's ``--nonlinearity``; ``Hammerstein``
      calls it ``nonlinearity``, which here names f);
    - ``output_nonlinearity``: an output map g after the loop, ``"poly3"`` (``"polyK"``),
      ``"saturation"`` or ``"pwl:K"`` (``--output-nonlinearity``); z is the linear output
      before g.

    Each of N and g is fitted nested: from the model without it, and kept only when it
    lowers the training error by more than its parameters' Akaike penalty (otherwise the
    simpler model is returned and ``report["warnings"]`` says so).

    ``fit(u, y, validate=0.3)`` holds the last 30 % back and reports the model's RMS error
    and fit there (an error when the loop diverges there). The fit releases the GIL.
    """

    def __init__(
        self,
        nonlinearity: str = "poly3",
        on: str = "output",
        order: Union[int, str, None] = None,
        *,
        horizon: Optional[int] = None,
        feedthrough: str = "auto",
        max_iterations: int = 100,
        tolerance: float = 0.1,
        effects: Union[str, Sequence[str], None] = None,
        input_nonlinearity: Optional[str] = None,
        output_nonlinearity: Optional[str] = None,
    ) -> None:
        self.nonlinearity = nonlinearity
        self.on = on
        self.order = order
        self.horizon = horizon
        self.feedthrough = feedthrough
        self.max_iterations = max_iterations
        self.tolerance = tolerance
        self.effects = effects
        self.input_nonlinearity = input_nonlinearity
        self.output_nonlinearity = output_nonlinearity

    def get_params(self) -> Dict[str, Any]:
        """The settings as a dict (scikit-learn's ``get_params``)."""
        return {
            k: getattr(self, k)
            for k in ("nonlinearity", "on", "order", "horizon", "feedthrough",
                      "max_iterations", "tolerance", "effects", "input_nonlinearity",
                      "output_nonlinearity")
        }

    def set_params(self, **params: Any) -> "Feedback":
        """Changes settings (scikit-learn's ``set_params``); returns ``self``."""
        known = self.get_params()
        for k, v in params.items():
            if k not in known:
                raise InputError(f"unknown setting '{k}' (known: {', '.join(known)})")
            setattr(self, k, v)
        return self

    def fit(
        self,
        u: Union[IoData, ArrayLike],
        y: Optional[ArrayLike] = None,
        ts: Optional[float] = None,
        *,
        validate: Optional[float] = None,
    ) -> FeedbackModel:
        """Fits the model to the record (``u``, ``y``) (one input, one output) or an
        :class:`IoData`; ``validate``: the last fraction held out and reported on."""
        data = record(u, y, ts)
        if data.n_inputs != 1:
            raise InputError(f"u has {data.n_inputs} columns: a feedback model has one input")
        data = data.cast("f64")
        val = None
        if validate is not None:
            data, val = data.split(float(validate))
        if self.horizon is not None and (
            isinstance(self.horizon, bool)
            or not isinstance(self.horizon, (int, np.integer))
            or self.horizon < 1
        ):
            raise InputError(f"horizon must be a positive integer, got {self.horizon!r}")
        mi = self.max_iterations
        if isinstance(mi, bool) or not isinstance(mi, (int, np.integer)) or mi < 0:
            raise InputError(f"max_iterations must be a non-negative integer, got {mi!r}")
        tol = float(self.tolerance)
        if not (np.isfinite(tol) and tol >= 0):
            raise InputError(f"tolerance must be a non-negative number, got {self.tolerance!r}")
        fb = self.feedthrough
        if isinstance(fb, bool):
            fb = "on" if fb else "off"
        order = "auto" if self.order is None else str(self.order)
        from ._model import _effect_list

        if isinstance(self.effects, dict):
            raise InputError("effects: a dict is for several inputs")
        effects = _effect_list(self.effects, "effects")
        for name in ("input_nonlinearity", "output_nonlinearity"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, str):
                raise InputError(f"{name} must be a name (a string), got {v!r}")
        m, report = _h.fit_feedback(
            data.u, data.y, data.ts, str(self.nonlinearity), str(self.on), order,
            None if self.horizon is None else int(self.horizon), str(fb), int(mi), tol,
            None if val is None else val.u, None if val is None else val.y,
            effects, self.input_nonlinearity, self.output_nonlinearity,
        )
        return FeedbackModel(m, json.loads(report))

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items() if v is not None)
        return f"Feedback({args})"


def is_feedback_text(text: str) -> bool:
    """Whether a model file's text is a feedback model's (kind "feedback")."""
    try:
        v = json.loads(text)
    except ValueError:
        return False
    return isinstance(v, dict) and v.get("kind") == "feedback"


def loads_feedback(text: str, label: str = "model JSON") -> FeedbackModel:
    """A feedback model from its model file's text."""
    return FeedbackModel(_h.loads_feedback(text, label))
