"""hammerstein: Hammerstein system identification with model diagnosis, on numpy arrays.

A static, often discontinuous input nonlinearity (the UDN: hysteresis, dead zone,
saturation, preload; or a polynomial, dynamic hysteresis) into a linear state-space block,
identified from measured input/output records by the Rust crate ``hammerstein``; the
diagnosis names the physical effects a model still misses, each checked by a refit.

>>> import numpy as np, hammerstein
>>> model = hammerstein.Hammerstein(effects=["saturation"]).fit(u, y)     # doctest: +SKIP
>>> hammerstein.compare(model, u_val, y_val).fit_percent                  # doctest: +SKIP
>>> d = hammerstein.diagnose(model, u, y, validate=0.3, follow=True)      # doctest: +SKIP

Functions: :class:`Hammerstein` (the estimator), :func:`compare`, :func:`diagnose`,
:func:`subspace`, :func:`load` / :func:`loads`; data: :class:`IoData` or plain arrays
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
from ._hammerstein import __version__

# The structure tools (design, bla, structure) and the feedback models of the crate get their
# wrappers here, one module each (``_structure.py``, ``_feedback.py``), as they are bound.

__all__ = [
    "EFFECTS",
    "Comparison",
    "Diagnosis",
    "Estimate",
    "Hammerstein",
    "HammersteinError",
    "InputError",
    "IoData",
    "Model",
    "StateSpace",
    "Step",
    "Subspace",
    "Suggestion",
    "TransferFunction",
    "Unexplained",
    "__version__",
    "compare",
    "diagnose",
    "load",
    "loads",
    "subspace",
]
