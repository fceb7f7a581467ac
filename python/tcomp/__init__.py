"""tcomp: temperature compensation of inertial sensors, from Python.

The same Rust crates as the ``tcomp`` command line, called in-process: ``fit`` trains a model
on a pandas DataFrame (or a dict of numpy arrays) with the options of ``tcomp fit`` as keyword
arguments, ``Model.evaluate`` measures it on a run, ``diagnose`` names the missing effect,
``calibrate`` runs a whole unit's spec, ``simulate`` makes chamber runs with known physics.
Nothing here computes: this module turns DataFrames into columns for the Rust extension
(``tcomp._tcomp``) and its JSON back into dicts and DataFrames. Errors are ``TcompError`` with
the command line's messages and places (``file``, ``line``, ``column``, ``option``).

    >>> import tcomp
    >>> sim = tcomp.simulate("ifog-shupe")
    >>> model = tcomp.fit(sim.train, target="gyro_dph", reference="ref_dph",
    ...                   signal="T=t_coil_c", feature=["T", "rate(T)", "T * rate(T)"])
    >>> model.evaluate(sim.verify).figures["residual_std"]
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from . import _tcomp
from ._tcomp import TcompError, __version__

__all__ = [
    "TcompError",
    "Model",
    "Evaluation",
    "Diagnosis",
    "Simulation",
    "fit",
    "diagnose",
    "calibrate",
    "simulate",
    "presets",
    "read_csv",
    "fit_keys",
    "__version__",
]

Data = Union["pandas.DataFrame", Mapping[str, Any]]  # noqa: F821


def _columns(data: Data, source: Optional[str]) -> tuple:
    """``(label, names, float64 bytes per column)`` of a DataFrame or a mapping of arrays.

    Every column is converted to float64; a cell that is not a number becomes NaN, which the
    trainer refuses with its line (row + 2, as in the CSV the data would be written to) and
    column, if the column is used.
    """
    if hasattr(data, "columns") and hasattr(data, "to_numpy"):
        import pandas as pd

        names = [str(c) for c in data.columns]
        arrays = [pd.to_numeric(data[c], errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan) for c in data.columns]
        label = source or "DataFrame"
    elif isinstance(data, Mapping):
        names = [str(k) for k in data.keys()]
        arrays = [np.asarray(v, dtype=np.float64) for v in data.values()]
        label = source or "dict"
    else:
        raise TypeError(f"data: a pandas DataFrame or a dict of arrays, not {type(data).__name__}")
    cols = [np.ascontiguousarray(a, dtype="<f8").reshape(-1).tobytes() for a in arrays]
    return (label, names, cols)


def _options(options: Dict[str, Any]) -> list:
    """Keyword arguments as ``(name, value)`` pairs in the order given (lists for ``feature``
    and ``signal`` may be given as one string)."""
    out = []
    for k, v in options.items():
        if k in ("feature", "signal") and isinstance(v, str):
            v = [v]
        if isinstance(v, np.generic):
            v = v.item()
        out.append((k, v))
    return out


def _frame(names: Sequence[str], cols: Sequence[bytes]):
    """Columns of float64 bytes as a DataFrame (a dict of arrays without pandas)."""
    arrays = {n: np.frombuffer(c, dtype="<f8") for n, c in zip(names, cols)}
    try:
        import pandas as pd
    except ImportError:
        return arrays
    return pd.DataFrame(arrays)


@dataclass(frozen=True)
class Evaluation:
    """A model measured on a run: ``residual`` (compensated − reference, one value per row, in
    the model's unit) and ``figures`` (the body of ``tcomp eval --json``: raw and residual std,
    rms, binned figures, segments, out-of-range share, faults, gaps)."""

    residual: np.ndarray
    figures: Dict[str, Any]


class Model:
    """A model blob: what ``tcomp fit`` writes and the firmware flies.

    ``Model(blob)`` / ``Model.from_bytes(blob)`` decode and validate it (``TcompError`` with the
    core's reason when it is refused); ``info`` is what ``tcomp inspect --json`` says of it.
    """

    def __init__(self, blob: bytes, summary: Optional[Dict[str, Any]] = None):
        self._blob = bytes(blob)
        self.info: Dict[str, Any] = json.loads(_tcomp.inspect(self._blob))
        #: The fit's summary (the body of ``tcomp fit --json``) when this model was fitted here.
        self.summary = summary

    @classmethod
    def from_bytes(cls, blob: bytes) -> "Model":
        """Decodes and validates a blob."""
        return cls(blob)

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Model":
        """Reads a ``.tcm`` file."""
        with open(path, "rb") as f:
            return cls(f.read())

    def to_bytes(self) -> bytes:
        """The blob's bytes, exactly as ``tcomp fit`` would write them."""
        return self._blob

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the blob to a ``.tcm`` file."""
        with open(path, "wb") as f:
            f.write(self._blob)

    @property
    def features(self) -> list:
        """The feature expressions."""
        return [f["expr"] if isinstance(f, dict) else f for f in self.info.get("features", [])]

    @property
    def unit(self) -> str:
        """The unit of the sensor output and the correction."""
        return self.info.get("unit", "")

    def evaluate(self, data: Data, *, source: Optional[str] = None, **options: Any) -> Evaluation:
        """Measures the model on a run through the core's f32 evaluator, as ``tcomp eval``.

        Keyword arguments are ``tcomp eval``'s: ``bin`` (s, default 100), ``temperature``,
        ``reference``, ``reference_value``, ``from_``, ``until``, ``gap``, ``power_on``.
        ``source`` names the data in errors (default ``"DataFrame"``). The GIL is released.
        """
        residual, figures = _tcomp.evaluate(self._blob, _columns(data, source), _options(options))
        return Evaluation(np.frombuffer(residual, dtype="<f8").copy(), json.loads(figures))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Model) and other._blob == self._blob

    def __hash__(self) -> int:
        return hash(self._blob)

    def __repr__(self) -> str:
        return f"Model({len(self._blob)} bytes, features={self.features!r})"


def fit(data: Data, *, source: Optional[str] = None, **options: Any) -> Model:
    """Trains a model on ``data`` (a DataFrame or a dict of arrays), as ``tcomp fit``.

    Keyword arguments are the keys of ``tcomp fit --spec`` (its flags with ``_`` for ``-``):
    ``target``, ``reference``, ``reference_value``, ``signal``, ``feature``, ``method``,
    ``average``, ``centers``, ``linear``, ``cubic``, ``select``, ``seed``, ``iterations``,
    ``time``, ``sensor``, ``axis``, ``unit``, ``from_``, ``until``, ``gap``, ``power_on``
    (``fit_keys()`` lists them). Each is checked as the flag is, with its message.
    ``source`` is the data's name in errors and in the blob's provenance (``tcomp fit`` records
    the ``--data`` path there: give the same path and the blob is byte for byte the CLI's).
    The GIL is released during the fit.
    """
    blob, summary = _tcomp.fit(_columns(data, source), _options(options))
    return Model(blob, json.loads(summary))


@dataclass(frozen=True)
class Diagnosis:
    """Where a model fails and which effect is missing: ``verdict`` (``"missing_effect"``,
    ``"cannot_tell"`` or ``"none"``), its sentence, the ``candidates`` table (a DataFrame, best first; records
    without pandas) and the whole body of ``tcomp diagnose --json`` in ``raw``."""

    verdict: str
    verdict_text: str
    candidates: Any
    raw: Dict[str, Any] = field(repr=False)


def diagnose(model: Model, data: Data, verify: Optional[Data] = None, *, source: Optional[str] = None, **options: Any) -> Diagnosis:
    """Diagnoses ``model`` on ``data`` (normally its training run), as ``tcomp diagnose``.

    The choice is made on ``data`` alone; ``verify`` (a held-out run) is refitted and reported,
    never used to choose. Keyword arguments are ``tcomp diagnose``'s: ``bin`` (s, default 60),
    ``min_evidence`` (5), ``min_improvement`` (%, 5), ``temperature``, ``reference``,
    ``reference_value``, ``from_``, ``until``, ``gap``, ``power_on``. The GIL is released.
    """
    v = _columns(verify, "verify") if verify is not None else None
    body = json.loads(_tcomp.diagnose(model.to_bytes(), _columns(data, source), v, _options(options)))
    records = body.get("candidates", [])
    try:
        import pandas as pd

        table = pd.DataFrame.from_records(records)
    except ImportError:
        table = records
    return Diagnosis(body.get("verdict", ""), body.get("verdict_text", ""), table, body)


def calibrate(
    spec: Union[str, os.PathLike],
    out: Union[str, os.PathLike],
    *,
    units: Optional[Union[str, os.PathLike]] = None,
    accept: bool = False,
    diagnosis: bool = True,
    gate: bool = True,
) -> Dict[str, Any]:
    """Runs ``tcomp calibrate SPEC --out OUT`` (``--units``, ``--accept``, ``--no-diagnosis``,
    ``--no-gate``) in-process: the blobs, ``image.bin``, ``report.html`` and ``summary.json`` land
    in ``out`` exactly as the command writes them; returns ``summary.json`` (``fleet.json`` with
    ``units``). The GIL is released."""
    return json.loads(
        _tcomp.calibrate(os.fspath(spec), os.fspath(out), None if units is None else os.fspath(units), accept, diagnosis, gate)
    )


@dataclass(frozen=True)
class Simulation:
    """Simulated chamber runs: ``train`` and ``verify`` (DataFrames), ``truth`` (the physics,
    ``truth.json``) and the ``dir`` they were written to."""

    train: Any
    verify: Any
    truth: Dict[str, Any]
    dir: str


def simulate(
    preset: Optional[str] = None,
    *,
    scenario: Optional[Union[str, os.PathLike]] = None,
    out: Optional[Union[str, os.PathLike]] = None,
    seed: Optional[int] = None,
    rate_hz: Optional[float] = None,
    step_s: Optional[float] = None,
) -> Simulation:
    """Runs ``tcomp simulate --preset NAME`` (or ``--scenario FILE``) into ``out`` (a new
    temporary directory by default) and reads the runs back with tcomp's CSV reader."""
    directory = os.fspath(out) if out is not None else tempfile.mkdtemp(prefix="tcomp-sim-")
    _tcomp.simulate(directory, preset, None if scenario is None else os.fspath(scenario), seed, rate_hz, step_s)
    with open(os.path.join(directory, "truth.json"), encoding="utf-8") as f:
        truth = json.load(f)
    train = read_csv(os.path.join(directory, "train.csv"))
    verify = read_csv(os.path.join(directory, "verify.csv"))
    return Simulation(train, verify, truth, directory)


def read_csv(path: Union[str, os.PathLike]):
    """Reads a measurement CSV (or ``.csv.gz``) with tcomp's reader (the same numbers, to the
    bit, and the same errors as the command line), as a DataFrame (a dict of arrays without
    pandas)."""
    names, cols = _tcomp.read_csv(os.fspath(path))
    return _frame(names, cols)


def presets() -> Dict[str, str]:
    """The simulator's presets and their descriptions (``tcomp simulate --list``)."""
    return dict(_tcomp.presets())


def fit_keys() -> list:
    """The keyword arguments ``fit`` accepts, as the spec spells them."""
    return list(_tcomp.fit_keys())
