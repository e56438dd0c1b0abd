"""The structure tools: a multisine :func:`design`, the best linear approximation
(:func:`bla`) and the structure verdict (:func:`structure`), as ``hammerstein design``,
``bla`` and ``structure`` give them."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _hammerstein as _h
from ._data import ArrayLike
from ._errors import InputError


def _positive_int(v: Any, name: str, least: int = 1) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < least:
        raise InputError(f"{name} must be an integer of at least {least}, got {v!r}")
    return int(v)


def _ts(ts: Optional[float]) -> Optional[float]:
    if ts is None:
        return None
    t = float(ts)
    if not (np.isfinite(t) and t > 0):
        raise InputError(f"ts must be a positive number of seconds, got {ts!r}")
    return t


def _pair(v: Any, name: str) -> Tuple[float, float]:
    try:
        lo, hi = (float(x) for x in v)
    except Exception:
        raise InputError(f"{name} must be two numbers (lo, hi), got {v!r}") from None
    return lo, hi


def _vector(x: ArrayLike, name: str) -> np.ndarray:
    try:
        a = np.asarray(x)
    except Exception as e:
        raise InputError(f"{name}: not an array of numbers ({e})") from None
    if a.dtype.kind not in "iubf":
        raise InputError(f"{name} has dtype {a.dtype}: real numbers are needed")
    if a.ndim != 1:
        raise InputError(f"{name} has shape {a.shape}: a 1-D array is needed")
    a = np.ascontiguousarray(a, dtype=np.float64)
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise InputError(f"non-finite value (NaN or infinity) in {name} at sample {bad[0]}")
    return a


class Experiment:
    """A multisine record in the record format: the columns ``level``, ``realization``,
    ``period`` (integers; period 0 of each block is the transient) and ``u``, and once
    measured ``y``; ``samples`` per period, the ``excited`` lines (line k is the frequency
    k/samples of the sampling frequency) and the sampling time ``ts`` (``None``: unknown).

    :func:`design` makes one; :meth:`replay` runs a plant on it; :meth:`to_csv` and
    :meth:`from_csv` write and read the CSV that ``hammerstein design``, ``bla`` and
    ``structure`` write and read.
    """

    __slots__ = ("level", "realization", "period", "u", "y", "samples", "excited", "ts")

    def __init__(
        self,
        level: ArrayLike,
        realization: ArrayLike,
        period: ArrayLike,
        u: ArrayLike,
        y: Optional[ArrayLike] = None,
        *,
        samples: Optional[int] = None,
        excited: Optional[Sequence[int]] = None,
        ts: Optional[float] = None,
    ) -> None:
        cols = [_vector(c, n) for c, n in ((level, "level"), (realization, "realization"), (period, "period"))]
        for c, n in zip(cols, ("level", "realization", "period")):
            if np.any(c != np.round(c)) or np.any(c < 0):
                raise InputError(f"{n} must hold whole numbers of at least 0")
        self.level, self.realization, self.period = (c.astype(np.int64) for c in cols)
        self.u = _vector(u, "u")
        self.y = None if y is None else _vector(y, "y")
        n = len(self.u)
        for name, c in (("level", self.level), ("realization", self.realization), ("period", self.period), ("y", self.y)):
            if c is not None and len(c) != n:
                raise InputError(f"length mismatch: u has {n} samples, {name} has {len(c)}")
        if samples is None:
            # the length of the first block's first period
            p0 = np.flatnonzero(self.period != self.period[0]) if n else np.array([])
            samples = int(p0[0]) if p0.size else n
        self.samples = _positive_int(samples, "samples")
        self.excited = None if excited is None else np.asarray(excited, dtype=np.int64)
        self.ts = _ts(ts)

    def __len__(self) -> int:
        return len(self.u)

    def __repr__(self) -> str:
        levels = len(np.unique(self.level))
        return (
            f"Experiment({len(self)} samples, {levels} level(s), {self.samples} samples per "
            f"period, {'measured' if self.y is not None else 'no output yet'})"
        )

    def blocks(self) -> Iterator[Tuple[int, int, slice]]:
        """Each block of constant (level, realization): ``(level, realization, slice)`` of
        its samples, the transient period included."""
        n = len(self.u)
        if n == 0:
            return
        change = np.flatnonzero((np.diff(self.level) != 0) | (np.diff(self.realization) != 0)) + 1
        starts = np.concatenate(([0], change))
        ends = np.concatenate((change, [n]))
        for a, b in zip(starts, ends):
            yield int(self.level[a]), int(self.realization[a]), slice(int(a), int(b))

    def replay(self, plant: Callable[[np.ndarray], ArrayLike]) -> "Experiment":
        """The experiment with ``y`` measured on ``plant``: ``plant(u)`` is called on each
        block's input (transient period included, from rest) and returns its output, e.g.
        ``model.simulate`` of a fitted model."""
        y = np.empty_like(self.u)
        for _, _, s in self.blocks():
            out = np.asarray(plant(self.u[s].copy()), dtype=np.float64).reshape(-1)
            if len(out) != s.stop - s.start:
                raise InputError(
                    f"the plant returned {len(out)} samples for a block of {s.stop - s.start}"
                )
            y[s] = out
        return self.with_output(y)

    def with_output(self, y: ArrayLike) -> "Experiment":
        """The experiment with the measured output ``y`` (one value per sample of ``u``)."""
        return Experiment(
            self.level, self.realization, self.period, self.u, y,
            samples=self.samples, excited=self.excited, ts=self.ts,
        )

    def to_csv(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the record format ``level,realization,period,u[,y]`` (what ``hammerstein
        design`` writes; ``bla`` and ``structure`` read it)."""
        cols = [self.level, self.realization, self.period, self.u] + ([self.y] if self.y is not None else [])
        header = "level,realization,period,u" + (",y" if self.y is not None else "")
        tmp = f"{os.fspath(path)}.tmp{os.getpid()}"
        with open(tmp, "w") as f:
            f.write(header + "\n")
            for row in zip(*(c.tolist() for c in cols)):
                f.write(",".join(repr(v) for v in row) + "\n")
        os.replace(tmp, path)

    @classmethod
    def from_csv(
        cls,
        path: Union[str, "os.PathLike[str]"],
        input: str = "u",
        output: str = "y",
        ts: Optional[float] = None,
    ) -> "Experiment":
        """Reads a record in the record format (columns ``level``, ``realization``,
        ``period``, the input ``input`` and, if present, the output ``output``); the
        sampling time ``ts`` is by default the step of a ``t`` column, as the command line
        reads it."""
        t = np.genfromtxt(path, delimiter=",", names=True, dtype=np.float64)
        names = t.dtype.names or ()
        for c in ("level", "realization", "period", input):
            if c not in names:
                raise InputError(f"{os.fspath(path)} has no column '{c}' (it has {', '.join(names)})")
        y = t[output] if output in names else None
        if ts is None and "t" in names and len(t) > 1:
            step = (t["t"][-1] - t["t"][0]) / (len(t) - 1)
            ts = float(step) if np.isfinite(step) and step > 0 else None
        return cls(t["level"], t["realization"], t["period"], t[input], y, ts=ts)

    def _part(self, label: str) -> Tuple[str, None, List[np.ndarray]]:
        if self.y is None:
            raise InputError(
                f"{label} has no output y: replay the experiment on the plant first "
                f"(Experiment.replay or with_output)"
            )
        cols = [self.level.astype(np.float64), self.realization.astype(np.float64),
                self.period.astype(np.float64), self.u, self.y]
        return label, None, cols


def design(
    kind: str = "random-odd",
    samples: int = 1024,
    band: Tuple[float, float] = (0.01, 0.2),
    group: int = 4,
    levels: Sequence[float] = (0.25, 0.5, 1.0),
    realizations: int = 4,
    periods: int = 2,
    seed: int = 7,
    *,
    ts: Optional[float] = None,
) -> Experiment:
    """A random-phase multisine experiment, as ``hammerstein design`` writes it.

    ``kind``: ``"random-odd"`` (odd lines, one per ``group`` left out as a detection line)
    or ``"full"`` (every line of the band); ``samples`` per period; ``band`` (lo, hi):
    fractions of the sampling frequency, or Hz with ``ts``; ``levels``: the RMS value of
    each level, increasing; ``realizations`` per level (a new random phase each); ``periods``
    steady periods per realization (one transient period comes before them); ``seed`` of
    the lines and phases. Returns an :class:`Experiment` (numpy columns ``level``,
    ``realization``, ``period``, ``u``) to replay on the plant.
    """
    lo, hi = _pair(band, "band")
    t = _ts(ts)
    if t is not None:
        lo, hi = lo * t, hi * t
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise InputError(f"seed must be a whole number in [0, 2^64), got {seed!r}")
    try:
        lv = [float(x) for x in levels]
    except Exception:
        raise InputError(f"levels must be a list of RMS values, got {levels!r}") from None
    cols, excited = _h.design(
        str(kind), _positive_int(samples, "samples"), (lo, hi),
        _positive_int(group, "group"), lv, _positive_int(realizations, "realizations"),
        _positive_int(periods, "periods"), int(seed),
    )
    level, realization, period, u = cols
    return Experiment(level, realization, period, u, samples=int(samples), excited=excited, ts=t)


RecordLike = Union[Experiment, Sequence[Experiment]]


def _parts(
    record: Union[RecordLike, ArrayLike], y: Optional[ArrayLike], period: Optional[int]
) -> Tuple[List[Any], Optional[float]]:
    """The record's parts for the compiled module and the sampling time they carry."""
    if isinstance(record, Experiment):
        if y is not None or period is not None:
            raise InputError("give either an Experiment or the arrays u, y with period, not both")
        return [record._part("the record")], record.ts
    if isinstance(record, (list, tuple)) and record and all(isinstance(r, Experiment) for r in record):
        ts = {r.ts for r in record}
        return [r._part(f"record {i + 1}") for i, r in enumerate(record)], (
            ts.pop() if len(ts) == 1 else None
        )
    if y is None or period is None:
        raise InputError(
            "a record is an Experiment (from design(...).replay(plant) or Experiment.from_csv), "
            "or the arrays u, y of a plain periodic record with its period"
        )
    u, yy = _vector(record, "u"), _vector(y, "y")
    if len(u) != len(yy):
        raise InputError(f"length mismatch: u has {len(u)} samples, y has {len(yy)}")
    return [("the record", _positive_int(period, "period"), [u, yy])], None


@dataclass(frozen=True)
class NonlinearityTest:
    """Whether a level shows nonlinear distortion above the noise: ``detected``,
    ``db_above_noise`` (mean distortion over mean noise), ``lines`` significant at 1 % of
    ``of`` tested, ``p_value`` (binomial tail under linearity), ``basis`` (which lines)."""

    detected: bool
    db_above_noise: float
    lines: int
    of: int
    p_value: float
    basis: str


@dataclass(frozen=True)
class LevelBla:
    """The BLA of one level: ``level`` index, input ``rms``, ``realizations``, ``periods``,
    ``method`` (robust, fast, noise-only, total-only), and per excited line the ``lines``
    (index k), ``frequencies`` (Hz with ``ts``, else fractions of the sampling frequency),
    ``bla`` (complex), ``var_total``, ``var_noise`` and ``var_distortion`` (variances of the
    BLA estimate; NaN where the record cannot separate them); ``even_db`` / ``odd_db``: output
    power at the detection lines above the noise there; ``nonlinearity``: the verdict
    (``None`` when the record cannot tell)."""

    level: int
    rms: float
    realizations: int
    periods: int
    method: str
    lines: np.ndarray = field(repr=False)
    frequencies: np.ndarray = field(repr=False)
    bla: np.ndarray = field(repr=False)
    var_total: np.ndarray = field(repr=False)
    var_noise: np.ndarray = field(repr=False)
    var_distortion: np.ndarray = field(repr=False)
    even_db: Optional[float]
    odd_db: Optional[float]
    nonlinearity: Optional[NonlinearityTest]

    @property
    def nonlinear(self) -> Optional[bool]:
        """Distortion detected above the noise (``None``: not testable)."""
        return None if self.nonlinearity is None else self.nonlinearity.detected


@dataclass(frozen=True)
class Bla:
    """The best linear approximation per level (what ``hammerstein bla --json`` prints):
    ``period`` (samples), ``excited`` lines, ``levels`` (:class:`LevelBla`, lowest RMS
    first), ``ts``; ``raw``: the command line's JSON."""

    period: int
    excited: np.ndarray = field(repr=False)
    levels: List[LevelBla] = field(default_factory=list)
    ts: Optional[float] = None
    raw: Dict[str, Any] = field(default_factory=dict, repr=False, compare=False)


def _num(v: Any) -> float:
    return float("nan") if v is None else float(v)


def bla(
    record: Union[RecordLike, ArrayLike],
    y: Optional[ArrayLike] = None,
    *,
    period: Optional[int] = None,
    ts: Optional[float] = None,
    plot: Union[str, "os.PathLike[str]", None] = None,
) -> Bla:
    """The best linear approximation of a multisine record per level, its noise and
    distortion variances and whether the system is nonlinear, as ``hammerstein bla``.

    ``record``: an :class:`Experiment` with its output (``design(...).replay(plant)`` or
    :meth:`Experiment.from_csv`), a list of them (joined, levels ordered by input RMS), or
    the input of a plain periodic record with its output ``y`` and ``period`` (samples per
    period, the first period a transient). ``ts``: the sampling time (frequencies in Hz);
    by default the experiment's. ``plot``: a path where the BLA plot of ``hammerstein bla
    --plot`` is written (SVG: |BLA|, noise and distortion against frequency per level).
    """
    parts, t = _parts(record, y, period)
    t = _ts(ts) if ts is not None else t
    d = json.loads(_h.bla_json(parts, t, None if plot is None else os.fspath(plot)))
    scale = 1.0 / t if t else 1.0
    levels = []
    for lv in d["levels"]:
        ls = lv["lines"]
        nl = lv.get("nonlinearity")
        levels.append(LevelBla(
            level=int(lv["level"]),
            rms=float(lv["rms"]),
            realizations=int(lv["realizations"]),
            periods=int(lv["periods"]),
            method=str(lv["method"]),
            lines=np.array([x["k"] for x in ls], dtype=np.int64),
            frequencies=np.array([x["freq"] for x in ls], dtype=float) * scale,
            bla=np.array([complex(*x["g"]) for x in ls], dtype=complex),
            var_total=np.array([_num(x["var_total"]) for x in ls]),
            var_noise=np.array([_num(x["var_noise"]) for x in ls]),
            var_distortion=np.array([_num(x["var_distortion"]) for x in ls]),
            even_db=lv.get("even_db"),
            odd_db=lv.get("odd_db"),
            nonlinearity=None if nl is None else NonlinearityTest(
                bool(nl["detected"]), _num(nl["db_above_noise"]), int(nl["lines"]),
                int(nl["of"]), _num(nl["p_value"]), str(nl["basis"]),
            ),
        ))
    return Bla(int(d["period"]), np.array(d["excited"], dtype=np.int64), levels, t, d)


@dataclass(frozen=True)
class Root:
    """A pole or zero: natural ``freq`` (Hz with the sampling time, else cycles per sample)
    and ``damping`` ratio with their standard errors; ``real`` (a complex pair is listed
    once)."""

    freq: float
    freq_se: float
    damping: float
    damping_se: float
    real: bool


@dataclass(frozen=True)
class LevelStructure:
    """One level's parametric BLA: input ``rms``, ``poles``, ``zeros``, ``distortion_db``
    (above the noise, when known)."""

    rms: float
    poles: List[Root]
    zeros: List[Root]
    distortion_db: Optional[float]


@dataclass(frozen=True)
class Movement:
    """A pole or zero (``kind``) of level ``from_level`` matched at ``to_level``: ``from``
    and ``to`` roots (``from_root``, ``to_root``), the shifts in standard errors."""

    kind: str
    from_level: int
    to_level: int
    from_root: Root
    to_root: Root
    freq_shift_se: float
    damping_shift_se: float


@dataclass(frozen=True)
class Structure:
    """The structure verdict (what ``hammerstein structure --json`` prints): ``verdict``
    (``"linear"``, ``"single-branch"``, ``"parallel"`` or ``"feedback"``), the ``order`` of
    every level's model, ``freq_unit``, ``levels`` (:class:`LevelStructure` with poles and
    zeros), the nested F ``tests`` (dicts), the roots that ``moved``, the model families
    consistent with the verdict (``candidates``), ``notes`` (what the analysis could not
    tell); ``raw``: the command line's JSON."""

    verdict: str
    order: int
    freq_unit: str
    levels: List[LevelStructure]
    tests: List[Dict[str, Any]] = field(repr=False)
    moved: List[Movement] = field(repr=False)
    candidates: List[str]
    notes: List[str] = field(repr=False)
    raw: Dict[str, Any] = field(default_factory=dict, repr=False, compare=False)


def _root(r: Dict[str, Any]) -> Root:
    return Root(_num(r["freq"]), _num(r["freq_se"]), _num(r["damping"]), _num(r["damping_se"]), bool(r["real"]))


def _structure(d: Dict[str, Any]) -> Structure:
    return Structure(
        verdict=str(d["verdict"]),
        order=int(d["order"]),
        freq_unit=str(d["freq_unit"]),
        levels=[
            LevelStructure(_num(lv["rms"]), [_root(r) for r in lv["poles"]],
                           [_root(r) for r in lv["zeros"]], lv.get("distortion_db"))
            for lv in d["levels"]
        ],
        tests=list(d["tests"]),
        moved=[
            Movement(m["kind"], int(m["from_level"]), int(m["to_level"]), _root(m["from"]),
                     _root(m["to"]), _num(m["freq_shift_se"]), _num(m["damping_shift_se"]))
            for m in d["moved"]
        ],
        candidates=list(d["candidates"]),
        notes=list(d["notes"]),
        raw=d,
    )


def structure(
    record: Union[RecordLike, ArrayLike],
    y: Optional[ArrayLike] = None,
    *,
    period: Optional[int] = None,
    ts: Optional[float] = None,
    order: Optional[int] = None,
    max_order: int = 8,
    alpha: float = 1e-3,
    band: Optional[Tuple[float, float]] = None,
    by_rms: Optional[int] = None,
    window: int = 1000,
) -> Structure:
    """What kind of system is this: the structure verdict from the BLAs of a multisine record
    at several levels, as ``hammerstein structure``.

    ``record``: as for :func:`bla`. ``order``: every level's model order (``None``: chosen
    from the data, up to ``max_order``); ``alpha``: the level of the F tests between the
    nested joint fits; ``band`` (lo, hi): only the lines in this band (Hz with ``ts``, else
    fractions of the sampling frequency). ``by_rms``: a non-periodic record ``(u, y)`` split
    into this many amplitude classes by the input's local RMS over ``window`` samples, ARX
    models of the classes compared (weaker evidence).
    """
    if not (isinstance(alpha, (int, float)) and 0.0 < alpha < 1.0):
        raise InputError(f"alpha must lie in (0, 1), got {alpha!r}")
    if order is not None:
        order = _positive_int(order, "order")
    max_order = _positive_int(max_order, "max_order")
    if by_rms is not None:
        if isinstance(record, Experiment) or y is None or period is not None:
            raise InputError("by_rms takes one non-periodic record: the arrays u and y")
        u, yy = _vector(record, "u"), _vector(y, "y")
        if len(u) != len(yy):
            raise InputError(f"length mismatch: u has {len(u)} samples, y has {len(yy)}")
        text = _h.structure_by_rms_json(
            u, yy, _ts(ts), _positive_int(by_rms, "by_rms"), _positive_int(window, "window"),
            order, max_order, float(alpha),
        )
        return _structure(json.loads(text))
    parts, t = _parts(record, y, period)
    t = _ts(ts) if ts is not None else t
    b = None
    if band is not None:
        b = _pair(band, "band")
        if not (np.isfinite(b[0]) and np.isfinite(b[1]) and b[0] < b[1]):
            raise InputError(f"band must satisfy lo < hi, got {band!r}")
    text = _h.structure_json(parts, t, order, max_order, float(alpha), b)
    return _structure(json.loads(text))
