"""The critical speed as a distribution over a fit's uncertainty.  SI units inside.

A fitted file (``feeddrive fit --out``) records its free parameters, estimates and
covariance in ``[fit]``.  Monte Carlo: parameter vectors drawn from the multivariate normal
N(estimates, covariance) (seeded; a draw outside a parameter's declared range, or refused
by the set's own checks such as F_s ≥ F_c, is drawn again and counted), each one point of a
sweep (:mod:`feeddrive.sweep`) whose quantity is the critical speed from rest on the shared
protocol, so the points run on a local process pool or Dask and are kept in a resumable
store.  Percentiles come with their Monte Carlo error: the distribution-free 95 % interval
of the order statistics (binomial ranks), and the convergence of each percentile with the
number of samples is plotted.  A sample whose drive creeps over the whole range (or none of
it) is censored at that end; a percentile that falls among them is reported as such.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from ..parameters import DriveParameters, ParameterError, load
from ..parameters.toml_io import read_toml_file
from ..parameters.validation import MISSING

__all__ = ["FitRecord", "Prediction", "plot_prediction", "predict", "read_fit_record"]

PERCENTILES = (5.0, 50.0, 95.0)


@dataclass(frozen=True)
class FitRecord:
    """A fitted parameter set with its ``[fit]`` table, as ``feeddrive predict`` reads it.

    Parameters
    ----------
    path : Path
        The fitted file.
    parameters : DriveParameters
        The fitted set.
    drive : str
        The drive it was fitted on.
    table_position : float
        Table position [m]; the default 0.4 for a drive whose model does not read it,
        whatever the record holds.
    free : tuple of str
        The fitted parameters' paths.
    estimates : numpy.ndarray
        Their estimates [SI unit of each].
    covariance : numpy.ndarray
        Their covariance [SI, per pair].
    """
    path: Path
    parameters: DriveParameters
    drive: str
    table_position: float  # [m]
    free: tuple[str, ...]
    estimates: np.ndarray
    covariance: np.ndarray


def read_fit_record(path: str | os.PathLike[str]) -> FitRecord:
    """The fitted set and its ``[fit]`` table; one-line refusals naming the key.

    Parameters
    ----------
    path : str or os.PathLike
        The fitted file.

    Returns
    -------
    FitRecord
        The record.

    Raises
    ------
    ParameterError
        For a file without a ``[fit]`` table, a missing key, a covariance that does not match
        the estimates, is not finite or is no covariance matrix (a negative variance), or an
        interrupted fit.
    """
    p = Path(path)
    data = read_toml_file(p, field="FIT")
    rec = data.get("fit")
    if not isinstance(rec, dict):
        raise ParameterError("FIT", str(p), "has no [fit] table; expected a file written by "
                             "feeddrive fit --out")
    for key in ("free", "estimates", "covariance", "drive", "table_position"):
        if key not in rec:
            raise ParameterError(f"fit.{key}", MISSING, f"missing in {p}")
    free = rec["free"]
    if not (isinstance(free, list) and free and all(isinstance(n, str) for n in free)):
        raise ParameterError("fit.free", free, f"{p}: expected a list of parameter "
                             "paths (text)")
    est = _numbers(rec["estimates"], "fit.estimates", p)
    cov = _numbers(rec["covariance"], "fit.covariance", p)
    if not (len(free) == est.size and cov.shape == (est.size, est.size)):
        raise ParameterError("fit.covariance", str(p), "expected one estimate per free "
                             "parameter and a square covariance of that size")
    if not np.all(np.isfinite(est)):
        raise ParameterError("fit.estimates", str(p), "not finite; expected a number per "
                             "free parameter")
    position = rec["table_position"]
    if isinstance(position, bool) or not isinstance(position, int | float) \
            or not math.isfinite(position):
        raise ParameterError("fit.table_position", position, f"{p}: expected a "
                             "number [m]")
    if not isinstance(rec["drive"], str):
        raise ParameterError("fit.drive", rec["drive"], f"{p}: expected a drive "
                             "name (text)")
    if not np.all(np.isfinite(cov)) or np.any(np.abs(cov) >= 1e299):
        raise ParameterError("fit.covariance", str(p), "not finite: a parameter was not "
                             "determined by the fit; fix it or fit better data first")
    _check_covariance(cov, free, p)
    if rec.get("interrupted") is True:
        raise ParameterError("fit.interrupted", True, f"{p}: the fit was interrupted; its "
                             "covariance is not available")
    params = load(p)
    from ..model.mechanisms import drive_names
    from ..model.mechanisms.base import start_position

    if rec["drive"] in drive_names():
        # the fit read it nowhere on a drive whose model does not, and the DriveSystems built
        # from the record refuse another value than the default since session 30: a record
        # an earlier fit wrote (the key is written for every drive) stays readable
        position = start_position(rec["drive"], position)
    return FitRecord(path=p, parameters=params, drive=rec["drive"],
                     table_position=float(position), free=tuple(free),
                     estimates=est, covariance=cov)


def _numbers(value: object, key: str, path: Path) -> np.ndarray:
    """A fit file's array of numbers; text, booleans or ragged lists refused naming the key
    (they gave numpy's "could not convert string to float: 'x'")."""
    def plain(v: object) -> bool:
        if isinstance(v, list):
            return all(plain(x) for x in v)
        return isinstance(v, int | float) and not isinstance(v, bool)

    if not (isinstance(value, list) and plain(value)):
        raise ParameterError(key, value, f"{path}: expected numbers")
    try:
        return np.asarray(value, dtype=float)
    except ValueError:  # ragged
        raise ParameterError(key, value, f"{path}: expected a rectangular array of "
                             "numbers") from None


def _check_covariance(cov: np.ndarray, free: list[str], path: Path) -> None:
    """A covariance is symmetric and positive semi-definite: a negative variance (or a
    negative eigenvalue beyond round-off) means nothing and was drawn from silently, clipped
    to zero (issue 39 item 5)."""
    scale = float(np.max(np.abs(np.diag(cov)))) if cov.size else 0.0
    for k, name in enumerate(free):
        if cov[k, k] < 0:
            raise ParameterError("fit.covariance", float(cov[k, k]),
                                 f"{path}: the variance of {name} is negative; expected a "
                                 "covariance matrix (variances ≥ 0)")
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-12 * scale):
        raise ParameterError("fit.covariance", str(path), "not symmetric; expected a "
                             "covariance matrix")
    lowest = float(np.min(np.linalg.eigvalsh(cov))) if cov.size else 0.0
    if lowest < -1e-9 * scale:
        raise ParameterError("fit.covariance", str(path), f"not positive semi-definite "
                             f"(an eigenvalue {lowest:.3g}); expected a covariance matrix")


def _draw(record: FitRecord, samples: int, seed: int) -> tuple[list[dict[str, float]], int]:
    """``samples`` parameter vectors from N(estimates, covariance), each valid; and the
    number of draws refused (outside the range or the set's checks)."""
    from .fit import free_parameter_bounds

    rng = np.random.default_rng(seed)
    bounds = [free_parameter_bounds(record.parameters, p) for p in record.free]
    # a symmetric square root, so the draws do not depend on the parameters' order
    w, v = np.linalg.eigh(0.5 * (record.covariance + record.covariance.T))
    root = v * np.sqrt(np.clip(w, 0.0, None)) @ v.T
    out: list[dict[str, float]] = []
    refused = 0
    while len(out) < samples:
        x = record.estimates + root @ rng.standard_normal(record.estimates.size)
        ok = all(lo < xi <= hi for xi, (lo, hi) in zip(x, bounds, strict=True))
        if ok:
            try:
                p = record.parameters
                for path, xi in zip(record.free, x, strict=True):
                    p = p.replace_path(path, float(xi))
            except ParameterError:
                ok = False
        if not ok:
            refused += 1
            if refused > 100 * samples + 1000:
                raise ParameterError("FIT", str(record.path), "almost every draw from the "
                                     "fit's covariance is an invalid parameter set")
            continue
        out.append({path: float(xi) for path, xi in zip(record.free, x, strict=True)})
    return out, refused


@dataclass(frozen=True)
class Percentile:
    """One percentile of the predicted critical speed, with its Monte Carlo interval.

    Parameters
    ----------
    level : float
        The percentile [%].
    value : float
        The critical speed at it [m/s]; ±inf when censored at the range's end.
    low : float
        Lower end of its 95 % Monte Carlo interval [m/s]; nan when the draws cannot bound it
        (too few: it lies below the smallest).
    high : float
        Upper end [m/s]; nan when it lies above the largest draw.
    """
    level: float  # [%]
    value: float  # [m/s] (±inf: censored at the range's end; nan: no draw found one)
    low: float  # 95 % Monte Carlo interval [m/s] (nan: not bounded by the draws)
    high: float

    def to_dict(self) -> dict[str, Any]:
        """The percentile for the JSON report.

        Returns
        -------
        dict
            Level [%], critical speed and interval [mm/s] ("below range"/"above range" when
            censored; an interval's end the draws cannot bound "below the smallest draw" or
            "above the largest draw"; "no draw found one" when every draw failed).
        """
        def mm(x: float, unbounded: str = "no draw found one") -> float | str:
            if math.isnan(x):
                return unbounded
            return x * 1e3 if math.isfinite(x) else ("below range" if x < 0 else "above range")

        return {"percentile": self.level, "critical_speed_mm_s": mm(self.value),
                "mc_interval_mm_s": [mm(self.low, "below the smallest draw"),
                                     mm(self.high, "above the largest draw")]}


@dataclass(frozen=True)
class Prediction:
    """The Monte Carlo prediction of the critical speed from a fit's covariance.

    Parameters
    ----------
    record : FitRecord
        The fit.
    samples : int
        Parameter draws.
    seed : int
        Seed of the draws.
    values : numpy.ndarray
        Critical speed per draw [m/s]; ±inf censored, nan failed.
    statuses : tuple of str
        The search status per draw.
    refused_draws : int
        Draws outside the parameters' ranges, redrawn.
    percentiles : tuple of Percentile
        The 5/50/95 % points.
    resolution : float
        Search resolution [m/s].
    speed_range : tuple of (float, float)
        Speeds searched [m/s].
    store : str
        The sweep store used.
    executor : str
        Where the points ran.
    computed : int
        Points computed this run.
    extra : dict, optional
        Further report entries.
    """
    record: FitRecord
    samples: int
    seed: int
    values: np.ndarray  # [m/s] per sample, ±inf censored, nan failed
    statuses: tuple[str, ...]
    refused_draws: int
    percentiles: tuple[Percentile, ...]
    resolution: float  # [m/s]
    speed_range: tuple[float, float]
    store: str
    executor: str
    computed: int
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The prediction for the JSON report (``feeddrive predict --json``).

        Returns
        -------
        dict
            Fit, drive, samples, seed, free parameters, percentiles, mean [mm/s] and the counts
            found, below and above range.
        """
        fin = self.values[np.isfinite(self.values)]
        return {"fit": os.fspath(self.record.path), "drive": self.record.drive,
                "samples": self.samples, "seed": self.seed,
                "free": list(self.record.free),
                "percentiles": [p.to_dict() for p in self.percentiles],
                "mean_mm_s": float(np.mean(fin) * 1e3) if fin.size else None,
                "found": int(fin.size),
                "below_range": int(np.sum(self.values == -np.inf)),
                "above_range": int(np.sum(self.values == np.inf)),
                "failed": int(np.sum(np.isnan(self.values))),
                "refused_draws": self.refused_draws,
                "resolution_mm_s": self.resolution * 1e3,
                "speed_range_mm_s": [v * 1e3 for v in self.speed_range],
                "store": self.store, "executor": self.executor, "computed": self.computed}


def _percentile(values: np.ndarray, level: float) -> Percentile:
    """Order-statistic percentile and its distribution-free 95 % interval (binomial ranks)."""
    x = np.sort(values[~np.isnan(values)])
    n = x.size
    if n == 0:
        return Percentile(level, math.nan, math.nan, math.nan)
    q = level / 100.0
    value = float(np.quantile(x, q, method="inverted_cdf"))
    lo_rank = int(stats.binom.ppf(0.025, n, q))
    hi_rank = int(stats.binom.ppf(0.975, n, q)) + 1
    # a rank beyond the draws: the interval's end lies outside them, not at the extreme draw
    # (1 sample gave "95 % interval 1.560 … 1.560"; a bad-input sweep, session 29): the 5 %
    # and 95 % points are bounded on both sides from 72 draws on
    low = float(x[lo_rank - 1]) if lo_rank >= 1 else math.nan
    high = float(x[hi_rank - 1]) if hi_rank <= n else math.nan
    return Percentile(level, value, low, high)


def predict(fit_file: str | os.PathLike[str], *, samples: int = 100, seed: int = 0,
            store: str | os.PathLike[str] | None = None, workers: int | None = None,
            dask_workers: int | None = None, scheduler: str | None = None,
            resolution: float | None = None, speed_range: tuple[float, float] | None = None,
            max_duration: float | None = None,
            progress: Callable[[int, int], None] | None = None,
            started: Callable[[int, str], None] | None = None) -> Prediction:
    """Monte Carlo of the critical speed from rest over the fit's covariance (see the
    module); ``resolution`` and ``speed_range`` [m/s], ``max_duration`` [s] override the
    shared protocol.  Points already in ``store`` are not recomputed.

    Parameters
    ----------
    fit_file : str or os.PathLike
        The fitted parameter file (``feeddrive fit --out``).
    samples : int, default 100
        Parameter draws.
    seed : int, default 0
        Seed of the draws.
    store : str or os.PathLike, optional
        The sweep store of the points.
    workers : int, optional
        Local worker processes.
    dask_workers : int, optional
        Workers of a local Dask cluster.
    scheduler : str, optional
        Address of a Dask scheduler.
    resolution : float, optional
        Search resolution [m/s].
    speed_range : tuple of (float, float), optional
        Speeds searched [m/s].
    max_duration : float, optional
        Longest creep trial [s].
    progress : callable, optional
        ``progress(done, total)``.
    started : callable, optional
        ``started(todo, executor)``.

    Returns
    -------
    Prediction
        The percentiles and every draw's critical speed.
    """
    from ..sweep import SweepStore
    from ..sweep.design import MAX_POINTS, Axis, Point, SweepConfig
    from ..sweep.executors import check_executor, run_sweep
    from ..sweep.quantities import QuantitySettings
    from ..sweep.store import point_key
    from . import protocol

    # everything is checked before the record is drawn from or a pool started (issue 39)
    if isinstance(samples, bool) or not isinstance(samples, int) or \
            not 1 <= samples <= MAX_POINTS:
        raise ParameterError("--samples", samples, f"expected a whole number in [1, "
                                                   f"{MAX_POINTS}] (as a sweep's design)")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError("--seed", seed, "expected a whole number ≥ 0")
    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    spec: dict[str, Any] = {"kind": "critical-speed", "linear": False}
    if resolution is not None:
        spec["resolution"] = resolution * 1e3
    lo, hi = speed_range or protocol.SPEED_RANGE
    spec["low"], spec["high"] = lo * 1e3, hi * 1e3
    if max_duration is not None:
        spec["max_duration"] = max_duration
    quantity = QuantitySettings.parse(spec, names={"resolution": "--resolution",
                                                   "low": "--low", "high": "--high"})
    record = read_fit_record(fit_file)
    draws, refused = _draw(record, samples, seed)
    from .fit import free_parameter_bounds

    source = os.fspath(Path(fit_file).resolve())
    axes = tuple(Axis(name=p, low=free_parameter_bounds(record.parameters, p)[0],
                      high=free_parameter_bounds(record.parameters, p)[1])
                 for p in record.free)
    store_path = Path(store) if store is not None else Path(fit_file).with_suffix(
        ".predict.sqlite")
    config = SweepConfig(name=f"predict-{Path(fit_file).stem}-seed{seed}", source=source,
                         base=source, drive=record.drive,
                         table_position=record.table_position * 1e3, nut_speed=0.0,
                         design="random", samples=samples, seed=seed, axes=axes,
                         quantity=quantity, store=store_path,
                         raw={"fit": source, "samples": samples, "seed": seed,
                              "distribution": "multivariate normal (fit covariance)"})
    cache: dict[str, DriveParameters] = {}
    points = []
    for i, coords in enumerate(draws):
        task = config.task(coords, cache)
        points.append(Point(index=i, coords=coords, task=task, key=point_key(task)))
    with SweepStore(store_path, option="--store") as db:
        summary = run_sweep(config, db, workers=workers, scheduler=scheduler,
                            dask_workers=dask_workers, points=points, progress=progress,
                            started=started)
        values = np.full(samples, math.nan)
        statuses = []
        for i, p in enumerate(points):
            got = db.get(p.key) or {}
            v = got.get("values", {})
            status = str(v.get("status", "failed" if "error" in got else "missing"))
            statuses.append(status)
            if status == "found":
                values[i] = float(v["critical_speed"])
            elif status == "below-range":
                values[i] = -math.inf
            elif status == "above-range":
                values[i] = math.inf
    pcts = tuple(_percentile(values, q) for q in PERCENTILES)
    return Prediction(record=record, samples=samples, seed=seed, values=values,
                      statuses=tuple(statuses), refused_draws=refused, percentiles=pcts,
                      resolution=quantity.resolution, speed_range=(quantity.low, quantity.high),
                      store=os.fspath(store_path), executor=summary.executor,
                      computed=summary.computed)


def plot_prediction(pred: Prediction, path: str | os.PathLike[str],
                    true_value: float | None = None) -> Path:
    """Histogram of the critical speed [mm/s] with the 5/50/95 % points, and each
    percentile against the number of samples (convergence).

    Parameters
    ----------
    pred : Prediction
        The prediction.
    path : str or os.PathLike
        The image file.
    true_value : float, optional
        A known critical speed to mark (synthetic data) [m/s].

    Returns
    -------
    Path
        The file written.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4))
    ax, ax2 = fig.subplots(1, 2)
    fin = pred.values[np.isfinite(pred.values)] * 1e3
    if fin.size:
        edges = np.arange(fin.min() - pred.resolution * 1e3, fin.max() + 2 * pred.resolution
                          * 1e3, pred.resolution * 1e3)
        ax.hist(fin, bins=edges if edges.size > 1 else 10, color="0.6")
    for pc in pred.percentiles:
        if math.isfinite(pc.value):
            ax.axvline(pc.value * 1e3, color="C0", ls="--", lw=0.8)
            ax.text(pc.value * 1e3, ax.get_ylim()[1] * 0.95, f"{pc.level:g} %", fontsize=8)
    if true_value is not None:
        ax.axvline(true_value * 1e3, color="C3", lw=1.2, label="true value")
        ax.legend(fontsize=8)
    ax.set_xlabel(f"critical speed [mm/s] (search resolution {pred.resolution * 1e3:g} mm/s)")
    ax.set_ylabel("samples")
    ax.set_title(f"{pred.record.drive.upper()}: {pred.samples} Monte Carlo samples", fontsize=9)
    n = np.arange(1, pred.values.size + 1)
    for q in PERCENTILES:
        run = [_percentile(pred.values[:k], q).value * 1e3 for k in n]
        ax2.plot(n, run, label=f"{q:g} %")
    ax2.set_xlabel("samples")
    ax2.set_ylabel("percentile [mm/s]")
    ax2.set_title("convergence", fontsize=9)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    from ..io.outputs import save_figure

    return save_figure(fig, path, dpi=100)
