"""``compare`` and ``diagnose``: how well a model fits a record, and what it is missing."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from . import _hammerstein as _h
from ._data import ArrayLike, IoData, record
from ._errors import InputError
from ._model import Hammerstein, Model


@dataclass(frozen=True)
class Comparison:
    """A model's simulation against a record: ``fit_percent`` (MATLAB's ``compare``:
    100·(1 − NRMSE)), ``mse``, ``nrmse``, ``n`` samples, and the simulated ``y_hat``
    (initial state estimated)."""

    fit_percent: float
    mse: float
    nrmse: float
    n: int
    y_hat: Optional[np.ndarray] = field(default=None, repr=False, compare=False)


def _metrics(d: Dict[str, Any], y_hat: Optional[np.ndarray] = None) -> Comparison:
    nan = float("nan")

    def num(k: str) -> float:
        v = d.get(k)
        return nan if v is None else float(v)

    return Comparison(num("fit_percent"), num("mse"), num("nrmse"), int(d.get("n", 0)), y_hat)


def compare(
    model: Model,
    u: Union[IoData, ArrayLike],
    y: Optional[ArrayLike] = None,
    ts: Optional[float] = None,
) -> Comparison:
    """Fit %, MSE and NRMSE of ``model`` on the record (``u``, ``y``), as ``hammerstein
    compare`` reports them (the initial state estimated from the record)."""
    from ._feedback import FeedbackModel

    if isinstance(model, FeedbackModel):
        data = record(u, y, ts)
        if data.n_inputs != 1:
            raise InputError(f"u has {data.n_inputs} columns: a feedback model has one input")
        data = data.cast("f64")
        text, y_hat = model._m.compare(data.u, data.y, data.ts)
        d = json.loads(text)
        e = 1.0 - d["fit_percent"] / 100.0
        d.update(mse=d["rms"] ** 2, nrmse=e)
        return _metrics(d, y_hat)
    if not isinstance(model, Model):
        raise InputError(f"compare: a fitted Model is needed, got {type(model).__name__}")
    data = record(u, y, ts)
    if data.n_inputs != model.n_inputs:
        raise InputError(f"u has {data.n_inputs} columns: the model has {model.n_inputs} input(s)")
    data = data.cast(model.precision)
    text, y_hat = model._m.compare(data.u, data.y, data.ts)
    return _metrics(json.loads(text), y_hat)


@dataclass(frozen=True)
class Estimate:
    """One size estimate of a suggestion: ``quantity`` (e.g. a parameter's name),
    ``source`` ("residual": read from the residual; "refit": from the refitted model),
    ``value``, ``standard_error``; ``key`` names it in :attr:`Suggestion.estimate`."""

    key: str
    quantity: str
    source: str
    value: float
    standard_error: Optional[float]


@dataclass(frozen=True)
class Suggestion:
    """A missing effect the diagnosis names, checked by a refit.

    ``effect`` (e.g. "hysteresis", "order", "delay"), ``input`` (the input it concerns),
    ``estimate`` (key → value: the effect's size), ``estimates`` (the same with sources and
    standard errors), ``expected_gain`` (the relative fall of the training MSE the refit
    gave: 1 − after/before), ``score``, ``evidence`` (why), the training and validation MSE
    before and after the refit, ``criterion_change`` (ΔBIC on the training part), ``p_value``,
    ``change`` (what the refit changed) and ``action`` (the typed settings change).
    """

    effect: str
    input: str
    estimate: Dict[str, float]
    estimates: Tuple[Estimate, ...]
    expected_gain: float
    score: float
    evidence: str
    train_mse_before: float
    train_mse_after: float
    validation_mse_before: float
    validation_mse_after: float
    criterion_change: float
    p_value: Optional[float]
    change: str
    action: Any


@dataclass(frozen=True)
class Unexplained:
    """A residual test still failing with no suggestion for it: ``test``, its adjusted
    p-value, and the ``model_classes`` that would explain it."""

    test: str
    p_adjusted: float
    model_classes: Tuple[str, ...]


def _f(v: Any) -> float:
    return float("nan") if v is None else float(v)


def _suggestion(s: Dict[str, Any]) -> Suggestion:
    ests = tuple(
        Estimate(e["key"], str(e["quantity"]), str(e["source"]), _f(e["value"]), e["standard_error"])
        for e in s["estimates"]
    )
    before, after = _f(s["train_mse_before"]), _f(s["train_mse_after"])
    gain = 1.0 - after / before if before > 0 else float("nan")
    return Suggestion(
        effect=s["effect"],
        input=s.get("input", "u"),
        estimate={e.key: e.value for e in ests},
        estimates=ests,
        expected_gain=gain,
        score=_f(s["score"]),
        evidence=s["evidence"],
        train_mse_before=before,
        train_mse_after=after,
        validation_mse_before=_f(s["validation_mse_before"]),
        validation_mse_after=_f(s["validation_mse_after"]),
        criterion_change=_f(s["criterion_change"]),
        p_value=s["p_value"],
        change=s["change"],
        action=s["action"],
    )


@dataclass(frozen=True)
class Step:
    """One step of a followed diagnosis: what ``change`` led to it ("start" first), its
    ``model`` and its ``diagnosis``."""

    change: str
    model: Model
    diagnosis: "Diagnosis"


class Diagnosis:
    """What :func:`diagnose` returns.

    ``adequate`` (the residuals are consistent with noise), ``suggestions`` (typed, best
    first), ``unexplained`` (tests no suggestion explains), ``summary``, ``tests`` (every
    residual test), ``null_parameters`` (candidates left out: their refit does not credit
    the effect), ``train`` and ``validation`` (:class:`Comparison`), ``model`` (the diagnosed
    model). With ``follow=True``: ``steps`` (one :class:`Step` per model, the last being
    ``model``), ``stop`` (why it stopped) and ``validation_rose_at`` (steps whose validation
    error rose). ``to_html(directory)`` writes the HTML report.
    """

    def __init__(
        self,
        d: Dict[str, Any],
        model: Model,
        steps: Optional[List[Step]] = None,
        stop: Optional[str] = None,
        validation_rose_at: Optional[List[int]] = None,
        compiled: Any = None,
    ) -> None:
        self.adequate: bool = bool(d["adequate"])
        self.summary: str = d["summary"]
        self.suggestions: List[Suggestion] = [_suggestion(s) for s in d["suggestions"]]
        #: several inputs: suggestions outside the model class (not applied by ``follow``)
        self.outside_class: List[Suggestion] = [_suggestion(s) for s in d.get("outside_class", [])]
        self.unexplained: List[Unexplained] = [
            Unexplained(u["test"], _f(u["p_adjusted"]), tuple(u["model_classes"]))
            for u in d["unexplained"]
        ]
        self.tests: List[Dict[str, Any]] = d["tests"]
        self.null_parameters: List[Dict[str, str]] = d["null_parameters"]
        self.generalisation: Optional[Dict[str, Any]] = d["generalisation"]
        self.train: Comparison = _metrics(d["train"])
        self.validation: Comparison = _metrics(d["validation"])
        self.model: Model = model
        self.steps: List[Step] = steps or []
        self.stop: Optional[str] = stop
        self.validation_rose_at: List[int] = validation_rose_at or []
        self._compiled = compiled

    def to_html(self, directory: Union[str, "os.PathLike[str]"], title: str = "Hammerstein model") -> str:
        """Writes the HTML report (plots as SVG files beside it) into ``directory``, as
        ``hammerstein diagnose --report`` does; returns the page's path."""
        if self._compiled is None:
            raise InputError("this diagnosis is one step of a followed one: call to_html on the result")
        return self._compiled.write_html(os.fspath(directory), title)

    def __repr__(self) -> str:
        top = self.suggestions[0].effect if self.suggestions else None
        return (
            f"<hammerstein.Diagnosis adequate={self.adequate} top={top!r} "
            f"validation fit={self.validation.fit_percent:.2f} % steps={len(self.steps)}>"
        )


def diagnose(
    model: Union[Model, Hammerstein],
    u: Union[IoData, ArrayLike],
    y: Optional[ArrayLike] = None,
    validate: Union[float, IoData, Tuple[ArrayLike, ArrayLike]] = 0.3,
    follow: bool = False,
    max_steps: int = 6,
    ts: Optional[float] = None,
) -> Diagnosis:
    """Diagnoses a model on the record (``u``, ``y``), as ``hammerstein diagnose`` does.

    The model's settings (a fitted :class:`Model`'s or an unfitted :class:`Hammerstein`'s)
    are fitted on the training part: the first 1 − ``validate`` of the record, or the whole
    record when ``validate`` is a validation record (``IoData`` or ``(u_val, y_val)``). The
    residuals are tested; each candidate effect is refitted and the ones that pass the
    training criterion are suggested, with their size. ``follow=True`` takes the top
    suggestion and refits, step by step (at most ``max_steps``), until the residuals are
    consistent with noise or nothing helps. The GIL is released meanwhile.
    """
    data = record(u, y, ts)
    fraction: Optional[float] = None
    val: Optional[IoData] = None
    if isinstance(validate, IoData):
        val = record(validate, ts=ts)
    elif isinstance(validate, tuple):
        if len(validate) != 2:
            raise InputError("validate: a fraction, an IoData or a pair (u_val, y_val)")
        val = record(validate[0], validate[1], data.ts)
    elif isinstance(validate, (float, int)) and not isinstance(validate, bool):
        fraction = float(validate)
    else:
        raise InputError(f"validate: a fraction, an IoData or (u_val, y_val), got {validate!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
        raise InputError(f"max_steps must be a positive integer, got {max_steps!r}")
    if isinstance(model, Model):
        if model.n_inputs != data.n_inputs:
            raise InputError(
                f"u has {data.n_inputs} columns: the model has {model.n_inputs} input(s)"
            )
        p = model.precision
        args = dict(model=model._m, settings=None)
    elif isinstance(model, Hammerstein):
        p = model._precision(data)
        args = dict(model=None, settings=model._settings(data.n_inputs))
    else:
        raise InputError(
            f"diagnose: a Model or a Hammerstein estimator is needed, got {type(model).__name__}"
        )
    data = data.cast(p)
    if val is not None:
        if val.n_inputs != data.n_inputs:
            raise InputError("the validation record has another number of inputs")
        val = val.cast(p)
    compiled = _h.diagnose(
        args["model"],
        args["settings"],
        p,
        data.u,
        data.y,
        data.ts,
        fraction,
        None if val is None else val.u,
        None if val is None else val.y,
        bool(follow),
        max_steps,
    )
    out = json.loads(compiled.describe())
    models = [Model(m) for m in compiled.models()]
    steps = [
        Step(s["change"], m, Diagnosis(s["diagnosis"], m))
        for s, m in zip(out["steps"], models)
    ]
    last = out["steps"][-1]["diagnosis"]
    stop = out["stop"]["text"] if out.get("stop") else None
    return Diagnosis(
        last,
        models[-1],
        steps if follow else None,
        stop,
        out.get("validation_rose_at"),
        compiled,
    )
