"""What a sweep computes at each point, and the function a worker runs.  SI inside.

Quantities (``[quantity] kind``):

* ``critical-speed``: the critical creeping speed and bands (:mod:`feeddrive.analysis.critical`),
  ``start = "rest"`` (scan + bisection) or ``"running"`` (the paper's step-down), on the
  protocol of ``feeddrive.analysis.protocol`` unless overridden;
* ``creep-trial``: one trial from rest at ``table_speed``: verdict kind, ripple ratio, stick
  fraction, frequency (:func:`~feeddrive.analysis.critical.creep_trial`);
* ``linear-band``: the speeds at which steady sliding is linearly unstable
  (:func:`feeddrive.analysis.linear.stability_band`);
* ``loop-margins``: least-damped mode and every loop's margins
  (:func:`feeddrive.analysis.linear.loop_analysis`) at ``table_speed``.

``linear = true`` (default for ``critical-speed`` and ``creep-trial``) adds the linear
prediction at each point, which maps draw over the simulated boundary: the linear band's
upper edge beside a critical speed, the sign of the rightmost pole's real part at the trial
speed beside a trial's verdict.

:func:`evaluate` takes a task (:meth:`.design.SweepConfig.task`: parameter TOML text, drive,
position, nut speed, settings) and returns ``{"values": {name: scalar (SI)}, "details": …}``,
or ``{"error": message}`` when the point's simulation fails — so a local process and a Dask
worker on another machine run exactly the same function on exactly the same inputs.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, replace
from typing import Any

from .. import units
from ..analysis import protocol
from ..parameters import DriveParameters, ParameterError
from ..units import absent_value

QUANTITIES = ("critical-speed", "creep-trial", "linear-band", "loop-margins")
_KEYS = ("kind", "start", "low", "high", "coarse_step", "resolution", "initial_duration",
         "max_duration", "table_speed", "linear", "linear_points")
#: kind → the ``[quantity]`` settings its computation reads (:meth:`QuantitySettings.to_dict`
#: keeps these; :meth:`QuantitySettings.parse` refuses any other: a ``table_speed`` given to
#: ``linear-band`` was dropped without a word)
READS: dict[str, tuple[str, ...]] = {
    "critical-speed": ("start", "low", "high", "coarse_step", "resolution", "initial_duration",
                       "max_duration", "linear", "linear_points"),
    "creep-trial": ("table_speed", "initial_duration", "max_duration", "linear"),
    "linear-band": ("low", "high", "linear_points"),
    "loop-margins": ("table_speed",),
}
#: kind → the settings of :data:`READS` it reads only with ``linear`` on: a critical-speed
#: search's linear band scans ``linear_points`` speeds; without the band nothing reads them
#: (they were taken, and hashed into the store key, unused: session 29)
LINEAR_ONLY: dict[str, tuple[str, ...]] = {"critical-speed": ("linear_points",)}


def reads(kind: str, linear: bool = True) -> tuple[str, ...]:
    """The ``[quantity]`` settings kind ``kind`` reads, given its ``linear`` setting:
    :data:`READS`, less :data:`LINEAR_ONLY` with ``linear`` off.

    Parameters
    ----------
    kind : str
        One of :data:`QUANTITIES`.
    linear : bool, default True
        The settings' ``linear``.

    Returns
    -------
    tuple of str
        The settings read, in :data:`READS`'s order.
    """
    unread = () if linear else LINEAR_ONLY.get(kind, ())
    return tuple(k for k in READS[kind] if k not in unread)

#: value name → SI unit (for exports; speeds become mm/s at the edges)
UNITS: dict[str, str] = {
    "critical_speed": "m/s", "linear_lower": "m/s", "linear_upper": "m/s",
    "linear_mode_frequency": "Hz", "simulated_time": "s", "trials": "1", "creep_bands": "1",
    "linear_bands": "1",
    "creeping": "1", "ripple_ratio": "1", "stick_fraction": "1", "frequency": "Hz",
    "duration": "s", "linear_growth_rate": "1/s", "linear_unstable": "1",
    "mode_frequency": "Hz", "damping_ratio": "1", "seconds": "s",
}

#: values whose absence is a bound, not a gap: ``…gain_margin_db`` of a loop whose phase does
#: not cross −180° above its gain crossover — an infinite gain margin (+inf here, ``inf`` in
#: the CSV, "∞" in `feeddrive loops` and the map's cells); the rule of
#: :func:`absent_value`, kept in ``feeddrive.units`` for every output
INFINITE_WHEN_ABSENT = units.INFINITE_WHEN_ABSENT


def stored_value(name: str, value: Any) -> Any:
    """A value as read back from a sweep store: JSON has no infinity, so the store keeps every
    non-finite number as null (``feeddrive.sweep.store``); a null is :func:`absent_value`
    (a gain margin's null is +inf: :func:`compute` gives no NaN for it).

    Parameters
    ----------
    name : str
        The value's name.
    value : object
        The stored value (None for null).

    Returns
    -------
    object
        ``value``, or the number a null stands for.
    """
    return absent_value(name) if value is None else value


@dataclass(frozen=True)
class QuantitySettings:
    """The ``[quantity]`` table of a sweep, in SI (the file gives speeds in mm/s).

    Parameters
    ----------
    kind : str, default "critical-speed"
        ``"critical-speed"``, ``"creep-trial"``, ``"linear-band"`` or ``"loop-margins"``.
    start : str, default "rest"
        Critical-speed search from ``"rest"`` or on a ``"running"`` table.
    low : float
        Lowest speed searched [m/s].
    high : float
        Highest speed searched [m/s].
    coarse_step : float
        Step of the coarse scan [m/s].
    resolution : float
        Bisection resolution [m/s].
    initial_duration : float
        First trial duration [s].
    max_duration : float
        Longest trial duration [s].
    table_speed : float, default 1e-3
        Table speed of a creep trial or loop-margin point [m/s].
    linear : bool, default True
        Also compute the linear stability band.
    linear_points : int, default 40
        Speeds of the linear scan.
    """

    kind: str = "critical-speed"
    start: str = "rest"
    low: float = protocol.SPEED_RANGE[0]  # [m/s]
    high: float = protocol.SPEED_RANGE[1]  # [m/s]
    coarse_step: float = protocol.COARSE_STEP  # [m/s]
    resolution: float = protocol.RESOLUTION  # [m/s]
    initial_duration: float = protocol.TRIAL_DURATION  # [s]
    max_duration: float = protocol.TRIAL_MAX_DURATION  # [s]
    table_speed: float = 1.0e-3  # [m/s] creep-trial, loop-margins
    linear: bool = True
    linear_points: int = 40

    @classmethod
    def parse(cls, spec: Any, names: dict[str, str] | None = None) -> QuantitySettings:
        """The settings from a ``[quantity]`` table, speeds converted from mm/s.

        A critical-speed search whose work is not bounded is refused
        (:func:`feeddrive.analysis.protocol.check_search`).

        Parameters
        ----------
        spec : dict
            The parsed table.
        names : dict of str to str, optional
            The name a search setting has in messages (``{"resolution": "--resolution"}``);
            ``quantity.<key>`` by default.

        Returns
        -------
        QuantitySettings
            The settings.

        Raises
        ------
        ParameterError
            For an unknown key, a key the kind does not read
            (``feeddrive.sweep.quantities.READS``) or a bad value, naming
            ``quantity.<key>``.
        """
        if not isinstance(spec, dict):
            raise ParameterError("quantity", spec, "expected a table")
        for k in spec:
            if k not in _KEYS:
                raise ParameterError(f"quantity.{k}", spec[k],
                                     f"unknown key; expected one of {', '.join(_KEYS)}")
        kind = spec.get("kind", "critical-speed")
        if kind not in QUANTITIES:
            raise ParameterError("quantity.kind", kind, f"expected one of {', '.join(QUANTITIES)}")
        linear_off = spec.get("linear") is False  # checked a bool below
        read = reads(kind, not linear_off)
        for k in spec:
            if k != "kind" and k not in read:
                with_linear = " with linear = false" if k in READS[kind] else ""
                raise ParameterError(f"quantity.{k}", spec[k],
                                     f"not read by kind {kind}{with_linear}, which reads "
                                     f"{', '.join(read)}")
        start = spec.get("start", "rest")
        if start not in ("rest", "running"):
            raise ParameterError("quantity.start", start, "expected rest or running")
        values: dict[str, Any] = {"kind": kind, "start": start}
        for k, factor in (("low", units.MM_PER_S), ("high", units.MM_PER_S),
                          ("coarse_step", units.MM_PER_S), ("resolution", units.MM_PER_S),
                          ("table_speed", units.MM_PER_S), ("initial_duration", 1.0),
                          ("max_duration", 1.0)):
            if k in spec:
                v = spec[k]
                # speeds up to the largest any feed drive has (units.LARGEST_SPEED; a high of
                # 1e300 mm/s failed every point and exited 0), times up to a day
                high = 86400.0 if factor == 1.0 else units.LARGEST_SPEED / factor
                if isinstance(v, bool) or not isinstance(v, int | float) \
                        or not math.isfinite(v) or not 0 < v <= high:
                    unit = "s" if factor == 1.0 else "mm/s"
                    raise ParameterError(f"quantity.{k}", v, f"expected a number > 0, ≤ "
                                         f"{high:g} [{unit}]")
                values[k] = float(v) * factor
        if "linear" in spec:
            if not isinstance(spec["linear"], bool):
                raise ParameterError("quantity.linear", spec["linear"], "expected true or false")
            values["linear"] = spec["linear"]
        if "linear_points" in spec:
            n = spec["linear_points"]
            if isinstance(n, bool) or not isinstance(n, int) \
                    or not 2 <= n <= protocol.MAX_LINEAR_POINTS:
                raise ParameterError("quantity.linear_points", n, f"expected a whole number 2 … "
                                     f"{protocol.MAX_LINEAR_POINTS}")
            values["linear_points"] = n
        if start == "running" and "coarse_step" not in spec:
            values["coarse_step"] = protocol.STAIRCASE_COARSE_STEP
        if kind == "linear-band":  # the scan `feeddrive stability` runs by default
            values.setdefault("low", protocol.LINEAR_SPEED_RANGE[0])
            values.setdefault("high", protocol.LINEAR_SPEED_RANGE[1])
            values.setdefault("linear_points", protocol.LINEAR_POINTS)
        out = cls(**values)
        if out.high <= out.low:
            raise ParameterError("quantity.high", out.high / units.MM_PER_S,
                                 f"empty range: expected > low = {out.low / units.MM_PER_S:g} "
                                 "[mm/s]")
        if out.max_duration < out.initial_duration:
            raise ParameterError("quantity.max_duration", out.max_duration,
                                 f"expected ≥ initial_duration = {out.initial_duration:g} [s]")
        if kind == "critical-speed":
            protocol.check_search(
                low=out.low, high=out.high, coarse_step=out.search_coarse_step,
                resolution=out.resolution,
                names={k: f"quantity.{k}" for k in ("low", "high", "coarse_step",
                                                    "resolution")} | (names or {}))
        return out

    @property
    def search_coarse_step(self) -> float:
        """The coarse step the critical-speed search scans with [m/s] (from rest: at most
        half the range)."""
        if self.start == "rest":
            return min(self.coarse_step, (self.high - self.low) / 2)
        return self.coarse_step

    def with_table_speed(self, speed: float) -> QuantitySettings:
        """These settings with another table speed (a ``table_speed`` axis).

        Parameters
        ----------
        speed : float
            Table speed [m/s].

        Returns
        -------
        QuantitySettings
            The new settings.
        """
        return replace(self, table_speed=speed)

    def to_dict(self) -> dict[str, Any]:
        """Only what the quantity depends on (the store key is a hash of it).

        Returns
        -------
        dict
            ``kind`` and the settings its computation reads [SI] (``reads``: a
            critical-speed search without its linear band has no ``linear_points``).
        """
        d = asdict(self)
        return {"kind": self.kind, **{k: d[k] for k in reads(self.kind, self.linear)}}


def _linear_band(system: Any, nut_speed: float, q: dict[str, Any]) -> dict[str, Any]:
    from ..analysis.linear import stability_band

    band = stability_band(system, nut_speed, low=q["low"], high=q["high"],
                          points=q["linear_points"])
    top = band.intervals[-1] if band.intervals else (math.nan, math.nan)
    return {"values": {"linear_lower": top[0], "linear_upper": top[1],
                       "linear_mode_frequency": (band.mode_frequency_hz[-1]
                                                 if band.mode_frequency_hz else math.nan),
                       "linear_bands": len(band.intervals)},
            "details": {"linear": band.as_dict()}}


def _growth_rate(system: Any, speed: float, nut_speed: float) -> tuple[float, float]:
    """Real part [1/s] and frequency [Hz] of the rightmost pole at steady sliding
    (:func:`feeddrive.analysis.linear.rightmost_pole`)."""
    from ..analysis.linear import rightmost_pole

    return rightmost_pole(system, speed, nut_speed)


def compute(system: Any, nut_speed: float, q: dict[str, Any]) -> dict[str, Any]:
    """Compute one sweep quantity of a drive.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    nut_speed : float
        Nut speed [m/s].
    q : dict
        The quantity settings (:meth:`QuantitySettings.to_dict`).

    Returns
    -------
    dict
        The quantity's values by name [SI].
    """
    from ..analysis.cycle_verdict import VerdictRule

    kind = q["kind"]
    if kind == "linear-band":
        return _linear_band(system, nut_speed, q)
    if kind == "loop-margins":
        from ..analysis.linear import loop_analysis

        la = loop_analysis(system, q["table_speed"], nut_speed).as_dict()
        values: dict[str, Any] = {
            "mode_frequency": la["least_damped_mode"]["frequency_hz"],
            "damping_ratio": la["least_damped_mode"]["damping_ratio"]}
        for loop in la["loops"]:
            stem = loop["loop"].replace(" ", "_")
            for k in ("gain_margin_db", "phase_margin_deg", "crossover_hz",
                      "closed_loop_bandwidth_hz"):
                name, v = f"{stem}_{k}", loop[k]
                values[name] = absent_value(name) if v is None else v
        return {"values": values, "details": {"loops": la["loops"]}}
    rule = VerdictRule(initial_duration=q["initial_duration"], max_duration=q["max_duration"])
    if kind == "creep-trial":
        from ..analysis.critical import creep_trial

        trial = creep_trial(system, q["table_speed"], nut_speed=nut_speed, rule=rule)
        values = {"kind": trial.kind, "creeping": int(trial.creeping),
                  "ripple_ratio": trial.ripple_ratio, "stick_fraction": trial.stick_fraction,
                  "frequency": (math.nan if trial.stick_slip_frequency is None
                                else trial.stick_slip_frequency),
                  "duration": trial.duration}
        if q["linear"]:
            growth, freq = _growth_rate(system, q["table_speed"], nut_speed)
            values.update(linear_growth_rate=growth, linear_unstable=int(growth > 0),
                          linear_mode_frequency=freq)
        return {"values": values, "details": {"trial": trial.to_dict()}}
    from ..analysis.critical import critical_speed_from_rest, critical_speed_stepdown

    if q["start"] == "rest":
        search = critical_speed_from_rest(
            system, nut_speed=nut_speed, speed_range=(q["low"], q["high"]),
            coarse_step=QuantitySettings(**q).search_coarse_step,
            resolution=q["resolution"], rule=rule)
    else:
        search = critical_speed_stepdown(
            system, nut_speed=nut_speed, start_speed=q["high"], lowest_speed=q["low"],
            step=q["resolution"], coarse_step=q["coarse_step"], rule=rule)
    d = search.to_dict()
    values = {"critical_speed": (math.nan if search.critical_speed is None
                                 else search.critical_speed),
              "status": search.status, "kind": search.kind or "",
              "creep_bands": len(d["bands"]), "trials": len(search.trials),
              "simulated_time": search.simulated_time}
    details: dict[str, Any] = {"bands": d["bands"], "display": d["display"]}
    if q["linear"]:
        lin = _linear_band(system, nut_speed, {**q, "low": min(q["low"], 1e-5),
                                               "high": max(q["high"], 5e-3)})
        values.update(lin["values"])
        details.update(lin["details"])
    return {"values": values, "details": details}


def evaluate(task: dict[str, Any], params: DriveParameters | None = None) -> dict[str, Any]:
    """Run one point (see the module).  Module-level and picklable: the function every
    executor runs, in a local process or on a Dask worker.

    Parameters
    ----------
    task : dict
        The point's task (``SweepConfig.task``).
    params : DriveParameters, optional
        The set ``task["parameters"]`` reads back, when the caller holds it (an in-process
        run: no TOML parse, ≈ 5 ms a point; the written text reads back equal to the set).

    Returns
    -------
    dict
        The values and ``seconds`` (CPU time of the point [s]); ``error`` instead of the values
        when the simulation failed.
    """
    from ..engine.options import SolverOptions, using
    from ..engine.simulate import DriveSystem, SimulationError
    from ..parameters import loads

    t0 = time.perf_counter()
    try:
        if params is None:
            params = loads(task["parameters"])
        system = DriveSystem(params, drive=task["drive"], table_position=task["table_position"])
        solver = task.get("solver")
        with using(None if solver is None else SolverOptions.from_record(solver)):
            out = compute(system, task["nut_speed"], task["quantity"])
    except (SimulationError, ValueError, ArithmeticError) as err:
        return {"error": f"{type(err).__name__}: {err}",
                "seconds": time.perf_counter() - t0}
    out["seconds"] = time.perf_counter() - t0
    return out


#: the quantities judged by a creep verdict on the runs' samples
VERDICT_KINDS = ("critical-speed", "creep-trial")


def _system(task: dict[str, Any]) -> Any:
    """``task``'s drive (a DriveSystem of its parameter set, drive and table position)."""
    from ..engine.simulate import DriveSystem
    from ..parameters import loads

    return DriveSystem(loads(task["parameters"]), drive=task["drive"],
                       table_position=task["table_position"])


def check_task(task: dict[str, Any]) -> None:
    """Refuse, before a store is opened or a run made, what no point of ``task``'s structure
    can compute: a creep quantity whose parameter set's ``[solver]`` output interval is
    coarser than a verdict's (:func:`feeddrive.analysis.critical.check_verdict_interval`).
    A sweep's design check (``feeddrive.sweep.executors.check_design``) and a sensitivity
    study call it; :func:`warm` does not (a fit warms its kernels with a creep-trial task and
    judges no verdict: its set's interval is its own).

    Parameters
    ----------
    task : dict
        A task of the structure.

    Raises
    ------
    ParameterError
        Naming the setting where it was set.
    """
    from ..analysis.critical import check_verdict_interval

    if task["quantity"]["kind"] in VERDICT_KINDS:
        check_verdict_interval(_system(task), None)


def warm(task: dict[str, Any]) -> None:
    """Compile (or load from numba's disk cache) the kernels ``task``'s quantity uses, with
    a 20-ms run and, for linear quantities, one linearisation: cheap, and it leaves the
    compiled modules on disk for every worker.

    Parameters
    ----------
    task : dict
        A task of the model structure to compile.
    """
    from ..engine.simulate import simulate
    from ..model.reference import ConstantSpeed

    system = _system(task)
    q = task["quantity"]
    speed = q.get("table_speed", 1e-3)
    if q["kind"] in VERDICT_KINDS:
        simulate(system, ConstantSpeed(speed, task["nut_speed"], ramp_time=0.01), 0.02)
    if q["kind"] in ("linear-band", "loop-margins") or q.get("linear"):
        from ..analysis.linear import linearize

        linearize(system, speed, task["nut_speed"])


__all__ = ["INFINITE_WHEN_ABSENT", "QUANTITIES", "UNITS", "VERDICT_KINDS", "QuantitySettings",
           "absent_value", "check_task", "compute", "evaluate", "stored_value", "warm"]
