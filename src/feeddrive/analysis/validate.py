"""Held-out validation of a fitted set: simulate records the fit did not use and say how well
the model predicts them.  SI units inside.

Per fitted signal of each record (measured y, simulated ŷ at the fitted values, both on the
record's instants):

* **fit %** = 100·(1 − ‖y − ŷ‖ / ‖y − ȳ‖), the figure of the system-identification
  benchmarks (Ljung, *System Identification*, 2nd ed., Prentice Hall 1999, Sect. 16.6,
  ``compare``; the EMPS benchmark, Janot, Gautier & Brunot 2019): 100 is a perfect
  prediction, 0 no better than the record's mean;
* **NRMSE** = rms(y − ŷ) / (max y − min y), the error relative to the signal's range;
* the **fraction inside the prediction band**: ŷ ± z·√(var_θ + σ²), z the normal quantile
  of ``level``, var_θ the fit's parameter covariance carried to the output through the
  output's sensitivities (forward differences, step ``JACOBIAN_STEP`` of
  :mod:`~feeddrive.analysis.fit` times each value; the delta method) and σ the record's own
  noise (estimated from the data, as the fit weighs it).  With a right model and a
  calibrated covariance about ``level`` of the samples lie inside; far fewer says the model
  or the intervals do not carry to this record.

A fitted file made for another drive than the one asked for, or whose free parameters these
records cannot show (a negative-direction branch on records that move positive only, …),
is refused in one line before any simulation.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .fit import (
    EDGE_UNITS,
    JACOBIAN_STEP,
    Experiment,
    FitError,
    _no_effect,
    _refuse_repeated_records,
    simulate_experiment,
)

__all__ = ["SignalValidation", "ValidationResult", "plot_validation", "validate"]


@dataclass(frozen=True)
class SignalValidation:
    """How well one signal of one held-out record is predicted.

    Parameters
    ----------
    source : str
        The record.
    signal : str
        The signal.
    samples : int
        Samples compared [-].
    fit_percent : float
        100·(1 − ‖y − ŷ‖/‖y − ȳ‖) [%].
    nrmse : float
        rms(y − ŷ)/(max y − min y) [-].
    inside_band : float
        Fraction of the measured samples inside the prediction band [-].
    """

    source: str
    signal: str
    samples: int
    fit_percent: float
    nrmse: float
    inside_band: float

    def to_dict(self) -> dict[str, Any]:
        """The figures for JSON.

        Returns
        -------
        dict
            The fields.
        """
        return {"source": self.source, "signal": self.signal, "samples": self.samples,
                "fit_percent": self.fit_percent, "nrmse": self.nrmse,
                "inside_band": self.inside_band}


@dataclass(frozen=True)
class ValidationResult:
    """What :func:`validate` found.

    Parameters
    ----------
    fit_file : str
        The fitted file.
    drive : str
        The drive.
    level : float
        Level of the prediction band [-].
    signals : tuple of SignalValidation
        One per record and signal.
    predicted : tuple of dict
        Per record, the simulated signals at the fitted values [SI].
    band : tuple of dict
        Per record, each signal's band half-width [SI].
    experiments : tuple of Experiment
        The records.
    """

    fit_file: str
    drive: str
    level: float
    signals: tuple[SignalValidation, ...]
    predicted: tuple[dict[str, np.ndarray], ...]
    band: tuple[dict[str, np.ndarray], ...]
    experiments: tuple[Experiment, ...]

    def to_dict(self) -> dict[str, Any]:
        """The result for ``feeddrive validate --json``.

        Returns
        -------
        dict
            The fitted file, drive, band level and the figures per signal.
        """
        return {"fit": self.fit_file, "drive": self.drive, "band_level": self.level,
                "signals": [s.to_dict() for s in self.signals]}


def validate(fit_file: str | Path, experiments: Sequence[Experiment], *,
             drive: str | None = None, level: float = 0.95,
             progress: Callable[[str], None] | None = None) -> ValidationResult:
    """Simulate held-out records with a fitted set and score the prediction (module
    docstring).

    Parameters
    ----------
    fit_file : str or Path
        A fitted file (``feeddrive fit --out``).
    experiments : sequence of Experiment
        The held-out records.
    drive : str, optional
        The drive the records come from; refused when the fit was made for another.
    level : float, default 0.95
        Level of the prediction band [-].
    progress : callable, optional
        Told in one line what is being done.

    Returns
    -------
    ValidationResult
        The figures per record and signal, and the prediction with its band.

    Raises
    ------
    FitError
        Another drive, a free parameter these records cannot show, no record.
    ParameterError
        A fitted file that cannot be read (:func:`~feeddrive.analysis.predict.read_fit_record`).
    """
    from scipy import stats

    from ..engine.options import current
    from .predict import read_fit_record

    say = progress or (lambda _t: None)
    if not experiments:
        raise FitError("no record given")
    # one record twice was scored twice, its rows repeated (an earlier sweep, session 30)
    _refuse_repeated_records(experiments, "each held-out record is scored once (twice, its "
                             "rows would repeat)")
    if not 0 < level < 1:
        raise FitError(f"--level {level!r}: expected a fraction in (0, 1)")
    rec = read_fit_record(fit_file)
    if drive is not None and drive != rec.drive:
        raise FitError(f"{fit_file}: fitted on the {rec.drive.upper()}; these records are "
                       f"of the {drive.upper()} (--drive {drive})")
    for path in rec.free:
        reason = _no_effect(rec.parameters, rec.drive, path, experiments)
        if reason:
            raise FitError(f"{fit_file}: frees {path}, which these records cannot show "
                           f"({reason})")
    from ..parameters import dumps

    solver = current().record()

    def run(params: Any) -> list[dict[str, np.ndarray]]:
        text = dumps(params)
        outs = []
        for e in experiments:
            task = {"parameters": text, "drive": rec.drive,
                    "table_position": rec.table_position,
                    "reference_time": e.reference_time, "table_speed": e.table_speed,
                    "nut_speed": e.nut_speed, "input": e.input, "input_value": e.input_value,
                    "time": e.time, "signals": list(e.signals),
                    "output_interval": min(1e-3, float(np.median(np.diff(e.time)))),
                    "solver": solver}
            out = simulate_experiment(task)
            if "error" in out:
                raise FitError(f"{e.source}: the fitted set does not simulate: {out['error']}")
            outs.append(out["signals"])
        return outs

    say("simulating the records at the fitted values")
    predicted = run(rec.parameters)
    steps = JACOBIAN_STEP * np.where(rec.estimates != 0, np.abs(rec.estimates), 1.0)
    columns = []
    for j, path in enumerate(rec.free):
        say(f"sensitivity to {path}")
        moved = run(rec.parameters.replace_path(path, float(rec.estimates[j] + steps[j])))
        columns.append([{k: (m[k] - p[k]) / steps[j] for k in p}
                        for m, p in zip(moved, predicted, strict=True)])
    z = float(stats.norm.ppf(0.5 + level / 2.0))
    rows: list[SignalValidation] = []
    bands: list[dict[str, np.ndarray]] = []
    for i, e in enumerate(experiments):
        band = {}
        for name, y in e.signals.items():
            yhat = predicted[i][name]
            sens = np.column_stack([col[i][name] for col in columns]) if columns \
                else np.zeros((y.size, 0))
            var = np.einsum("kj,jl,kl->k", sens, rec.covariance, sens)
            half = z * np.sqrt(np.maximum(var, 0.0) + float(e.noise[name]) ** 2)
            band[name] = half
            err = y - yhat
            spread = float(np.linalg.norm(y - y.mean()))
            fit = 100.0 * (1.0 - float(np.linalg.norm(err)) / spread) if spread > 0 \
                else math.nan
            span = float(np.ptp(y))
            rows.append(SignalValidation(
                source=e.source, signal=name, samples=int(y.size), fit_percent=fit,
                nrmse=float(np.sqrt(np.mean(err ** 2))) / span if span > 0 else math.nan,
                inside_band=float(np.mean(np.abs(err) <= half))))
        bands.append(band)
    return ValidationResult(fit_file=str(fit_file), drive=rec.drive, level=level,
                            signals=tuple(rows), predicted=tuple(predicted),
                            band=tuple(bands), experiments=tuple(experiments))


def plot_validation(result: ValidationResult, path: str | Path) -> Path:
    """One row per record and signal: measured, predicted and the prediction band (left), the
    prediction error with the band's half-width (right); fit % in the title.

    Parameters
    ----------
    result : ValidationResult
        The validation.
    path : str or Path
        The image file.

    Returns
    -------
    Path
        The file written.
    """
    from matplotlib.figure import Figure

    from ..io.outputs import save_figure

    rows = [(e, name, pred, band) for e, pred, band in zip(
        result.experiments, result.predicted, result.band, strict=True) for name in pred]
    fig = Figure(figsize=(12, 2.6 * len(rows) + 0.6))
    axes = fig.subplots(len(rows), 2, squeeze=False)
    scores = {(s.source, s.signal): s for s in result.signals}
    for (e, name, pred, band), ax in zip(rows, axes, strict=True):
        unit, k = EDGE_UNITS.get(name, ("SI", 1.0))
        y, yhat, half = e.signals[name], pred[name], band[name]
        score = scores[(e.source, name)]
        ax[0].fill_between(e.time, k * (yhat - half), k * (yhat + half), color="C1",
                           alpha=0.25, lw=0, label=f"{100 * result.level:.0f} % band")
        ax[0].plot(e.time, k * y, lw=0.6, label="measured")
        ax[0].plot(e.time, k * yhat, lw=0.8, label="predicted")
        ax[0].set_ylabel(f"{name} [{unit}]", fontsize=8)
        ax[0].set_title(f"{Path(e.source).name}: fit {score.fit_percent:.1f} %, NRMSE "
                        f"{score.nrmse:.3g}, {100 * score.inside_band:.0f} % inside the band",
                        fontsize=8)
        ax[0].legend(fontsize=7, loc="best")
        ax[1].plot(e.time, k * (y - yhat), lw=0.5)
        ax[1].plot(e.time, k * half, "k--", lw=0.6)
        ax[1].plot(e.time, -k * half, "k--", lw=0.6)
        ax[1].set_ylabel(f"measured − predicted [{unit}]", fontsize=8)
    axes[-1][0].set_xlabel("time [s]")
    axes[-1][1].set_xlabel("time [s] (dashed: the band's half-width)")
    fig.suptitle(f"feeddrive validate — {Path(result.fit_file).name} on held-out records",
                 fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=100)
