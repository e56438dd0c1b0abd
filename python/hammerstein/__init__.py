"""hammerstein: Hammerstein system identification with model diagnosis, on numpy arrays.

A static, often discontinuous input nonlinearity (the UDN: hysteresis, dead zone,
saturation, preload; or a polynomial, dynamic hysteresis) into a linear state-space block,
identified from measured input/output records by the Rust crate ``hammerstein``; the
diagnosis names the physical effects a model still misses, each checked by a refit.

>>> import numpy as np, hammerstein
>>> model = hammerstein.Hammerstein(effects=["saturation"]).fit(u, y)     # doctest: +SKIP
>>> hammerstein.compare(model, u_val, y_val).fit_percent                  # doctest: +SKIP
>>> d = hammerstein.diagnose(model, u, y, validate=0.3, follow=True)      # doctest: +SKIP

Functions: :class:`Hammerstein` (the estimator), :class:`Feedback` (a nonlinearity in
feedback), :func:`compare`, :func:`diagnose`, :func:`subspace`, :func:`load` /
:func:`loads`; the structure tools :func:`design` (a multisine experiment), :func:`bla` and
:func:`structure` (what kind of system is this); data: :class:`IoData` or plain arrays
(1-D for one input, 2-D with one column per input). Bad input raises :class:`InputError`
(a ``ValueError``); a failed fit :class:`HammersteinError`. See docs/python.md.
"""

from ._errors import HammersteinError, InputError
from ._data import IoData
from ._model import EFFECTS, Hammerstein, Model, StateSpace, TransferFunction, load, loads
from ._diagnosis import (
    Comparison,
    Diagnosis,
    Estimate,
    Step,
    Suggestion,
    Unexplained,
    compare,
    diagnose,
)
from ._subspace import Subspace, subspace
from ._structure import (
    Bla,
    Experiment,
    LevelBla,
    LevelStructure,
    Movement,
    NonlinearityTest,
    Root,
    Structure,
    bla,
    design,
    structure,
)
from ._feedback import FEEDBACK_NONLINEARITIES, Feedback, FeedbackModel
from ._hammerstein import __version__

__all__ = [
    "EFFECTS",
    "FEEDBACK_NONLINEARITIES",
    "Bla",
    "Comparison",
    "Diagnosis",
    "Estimate",
    "Experiment",
    "Feedback",
    "FeedbackModel",
    "Hammerstein",
    "HammersteinError",
    "InputError",
    "IoData",
    "LevelBla",
    "LevelStructure",
    "Model",
    "Movement",
    "NonlinearityTest",
    "Root",
    "StateSpace",
    "Step",
    "Structure",
    "Subspace",
    "Suggestion",
    "TransferFunction",
    "Unexplained",
    "__version__",
    "bla",
    "compare",
    "design",
    "diagnose",
    "load",
    "loads",
    "structure",
    "subspace",
]
