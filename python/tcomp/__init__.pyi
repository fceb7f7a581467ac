"""Type stubs of the tcomp package (see __init__.py for the documentation)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
Data = Union["pandas.DataFrame", Mapping[str, npt.ArrayLike]]  # noqa: F821

class TcompError(ValueError):
    """An error of tcomp with the command line's message and its place (None where none)."""

    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    option: Optional[str]

class Evaluation:
    residual: np.ndarray
    figures: Dict[str, Any]

class Model:
    info: Dict[str, Any]
    summary: Optional[Dict[str, Any]]
    def __init__(self, blob: bytes, summary: Optional[Dict[str, Any]] = ...) -> None: ...
    @classmethod
    def from_bytes(cls, blob: bytes) -> "Model": ...
    @classmethod
    def load(cls, path: PathLike) -> "Model": ...
    def to_bytes(self) -> bytes: ...
    def save(self, path: PathLike) -> None: ...
    @property
    def features(self) -> List[str]: ...
    @property
    def unit(self) -> str: ...
    def evaluate(
        self,
        data: Data,
        *,
        source: Optional[str] = ...,
        bin: float = ...,
        temperature: Optional[str] = ...,
        reference: Optional[str] = ...,
        reference_value: Optional[float] = ...,
        from_: Optional[float] = ...,
        until: Optional[float] = ...,
        gap: Optional[float] = ...,
        power_on: Optional[float] = ...,
    ) -> Evaluation: ...

def fit(
    data: Data,
    *,
    source: Optional[str] = ...,
    target: Optional[str] = ...,
    reference: Optional[str] = ...,
    reference_value: Optional[float] = ...,
    signal: Union[str, List[str], None] = ...,
    feature: Union[str, List[str], None] = ...,
    method: Optional[str] = ...,
    average: Optional[float] = ...,
    centers: Optional[int] = ...,
    linear: Optional[bool] = ...,
    cubic: Optional[bool] = ...,
    select: Optional[str] = ...,
    seed: Optional[int] = ...,
    iterations: Optional[int] = ...,
    time: Optional[str] = ...,
    sensor: Optional[str] = ...,
    axis: Optional[str] = ...,
    unit: Optional[str] = ...,
    from_: Optional[float] = ...,
    until: Optional[float] = ...,
    gap: Optional[float] = ...,
    power_on: Optional[float] = ...,
) -> Model: ...

class Diagnosis:
    verdict: str
    verdict_text: str
    candidates: Any
    raw: Dict[str, Any]

def diagnose(
    model: Model,
    data: Data,
    verify: Optional[Data] = ...,
    *,
    source: Optional[str] = ...,
    bin: float = ...,
    min_evidence: float = ...,
    min_improvement: float = ...,
    temperature: Optional[str] = ...,
    reference: Optional[str] = ...,
    reference_value: Optional[float] = ...,
    from_: Optional[float] = ...,
    until: Optional[float] = ...,
    gap: Optional[float] = ...,
    power_on: Optional[float] = ...,
) -> Diagnosis: ...
def calibrate(
    spec: PathLike,
    out: PathLike,
    *,
    units: Optional[PathLike] = ...,
    accept: bool = ...,
    diagnosis: bool = ...,
    gate: bool = ...,
) -> Dict[str, Any]: ...

class Simulation:
    train: Any
    verify: Any
    truth: Dict[str, Any]
    dir: str

def simulate(
    preset: Optional[str] = ...,
    *,
    scenario: Optional[PathLike] = ...,
    out: Optional[PathLike] = ...,
    seed: Optional[int] = ...,
    rate_hz: Optional[float] = ...,
    step_s: Optional[float] = ...,
) -> Simulation: ...
def read_csv(path: PathLike) -> Any: ...
def presets() -> Dict[str, str]: ...
def fit_keys() -> List[str]: ...
