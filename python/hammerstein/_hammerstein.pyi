"""Type stubs of the compiled module (python/src/lib.rs); use the package's public API."""

from typing import List, Optional, Sequence, Tuple

import numpy as np

__version__: str

class Model:
    """A fitted model (wrapped by :class:`hammerstein.Model`)."""

    @property
    def precision(self) -> str: ...
    @property
    def n_inputs(self) -> int: ...
    @property
    def decimation(self) -> int: ...
    def describe(self) -> str: ...
    def simulate(self, u: np.ndarray) -> np.ndarray: ...
    def compare(self, u: np.ndarray, y: np.ndarray, ts: float) -> Tuple[str, np.ndarray]: ...
    def to_json(self) -> str: ...
    def save(self, path: str) -> None: ...

class Diagnosed:
    """A diagnosis or a followed sequence (wrapped by :class:`hammerstein.Diagnosis`)."""

    def describe(self) -> str: ...
    def models(self) -> List[Model]: ...
    def write_html(self, dir: str, title: str) -> str: ...

def fit(
    u: np.ndarray, y: np.ndarray, ts: float, precision: str, settings: str
) -> Model: ...
def load(path: str) -> Model: ...
def loads(text: str) -> Model: ...
def diagnose(
    model: Optional[Model],
    settings: Optional[str],
    precision: str,
    u: np.ndarray,
    y: np.ndarray,
    ts: float,
    fraction: Optional[float],
    u_val: Optional[np.ndarray],
    y_val: Optional[np.ndarray],
    follow: bool,
    max_steps: int,
) -> Diagnosed: ...
def subspace(
    u: np.ndarray,
    y: np.ndarray,
    ts: float,
    precision: str,
    method: str,
    order: str,
    horizon: Optional[int],
    stable: bool,
    detrend: bool,
    with_d: bool,
) -> str: ...

class Feedback:
    """A fitted feedback model (wrapped by :class:`hammerstein.FeedbackModel`)."""

    @property
    def decimation(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def z_range(self) -> Tuple[float, float]: ...
    @property
    def input_name(self) -> Optional[str]: ...
    @property
    def output_name(self) -> Optional[str]: ...
    def to_json(self) -> str: ...
    def save(self, path: str) -> None: ...
    def simulate(self, u: np.ndarray) -> np.ndarray: ...
    def compare(self, u: np.ndarray, y: np.ndarray, ts: float) -> Tuple[str, np.ndarray]: ...
    def f(self, z: np.ndarray) -> np.ndarray: ...
    def input_map(self, u: np.ndarray) -> Optional[np.ndarray]: ...
    def output_map(self, l: np.ndarray) -> Optional[np.ndarray]: ...

def fit_feedback(
    u: np.ndarray,
    y: np.ndarray,
    ts: float,
    nonlinearity: str,
    on: str,
    order: str,
    horizon: Optional[int],
    feedthrough: str,
    max_iterations: int,
    tolerance: float,
    u_val: Optional[np.ndarray],
    y_val: Optional[np.ndarray],
    effects: Optional[str] = None,
    input_nonlinearity: Optional[str] = None,
    output_nonlinearity: Optional[str] = None,
) -> Tuple[Feedback, str]: ...
def loads_feedback(text: str, label: str) -> Feedback: ...
def design(
    kind: str,
    samples: int,
    band: Tuple[float, float],
    group: int,
    levels: Sequence[float],
    realizations: int,
    periods: int,
    seed: int,
) -> Tuple[List[np.ndarray], List[int]]: ...
def bla_json(
    parts: List[Tuple[str, Optional[int], List[np.ndarray]]],
    ts: Optional[float],
    plot: Optional[str],
) -> str: ...
def structure_json(
    parts: List[Tuple[str, Optional[int], List[np.ndarray]]],
    ts: Optional[float],
    order: Optional[int],
    max_order: int,
    alpha: float,
    band: Optional[Tuple[float, float]],
) -> str: ...
def structure_by_rms_json(
    u: np.ndarray,
    y: np.ndarray,
    ts: Optional[float],
    classes: int,
    window: int,
    order: Optional[int],
    max_order: int,
    alpha: float,
) -> str: ...
