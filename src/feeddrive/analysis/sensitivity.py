"""Which parameter matters: elasticities of the critical speed (or of the linear band's
upper edge) to every numeric parameter, by central finite differences through the sweep
machinery.  SI inside.

Quantity Q: the critical speed from rest (``critical-speed``, resolution 0.01 mm/s on the
shared protocol) or the upper edge of the linearly unstable band of steady sliding
(``linear-band``, bisected to 10⁻³ mm/s: cheap, no simulation).  For each parameter p with
value p₀ ≠ 0, Q is evaluated at p₀(1 ± h) and the elasticity is E = (Q₊ − Q₋)/(2h·Q₀): the
% change of Q per % change of p.  A zero-valued parameter with a stated scale s
(:data:`ZERO_SCALES`) gets the absolute derivative (Q₊ − Q₋)/(2h·s) at ±h·s instead.

The step: h starts at :data:`STEPS`\\[0] and is doubled until the step's effect |Q₊ − Q₋| is
at least 10× the quantity's resolution (the resolution ≤ 0.1× the effect); a parameter still
below that at the largest step is reported *not resolved*, with the bound |E| < 10·res/(2hQ₀).
Each resolved value is checked by halving: E at h/2 must agree within 20 % or within the
resolution's share 2·res/(h·Q₀); otherwise the response is flagged nonlinear (a knife edge
between two regimes, e.g. a speed at which a limit cycle appears).  A step that the set's own
checks refuse (F_s ≥ F_c, a range) stops the doubling.

Parameters left out, each with the reason: those without effect on the drive (the fit's
rules: :func:`feeddrive.analysis.fit._no_effect`, positive direction), structural switches
(loop periods, encoder counts, the support-bearing count), limits at the top of their range
(no limit in effect), the smoothing velocity of a LuGre site (static law only), and
zero-valued parameters without a stated scale.
"""

from __future__ import annotations

import fnmatch
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import check_flag

__all__ = ["STEPS", "ZERO_SCALES", "SensitivityResult", "parameter_paths", "plot_tornado",
           "sensitivity"]

#: relative steps tried in turn (doubling)
STEPS = (0.1, 0.2, 0.4)
#: the effect must be at least this many resolutions
MIN_EFFECT_RESOLUTIONS = 10.0
#: scale s [SI] of zero-valued parameters, for their absolute derivative
ZERO_SCALES: dict[str, float] = {"stiffness.axial_damping": 1e4,
                                 "controller.current_integral_gain": 1e3,
                                 "disturbances.load_force": 10.0}
#: parameters that switch the model's structure rather than scale a value
_STRUCTURAL = ("controller.position_period", "controller.velocity_period",
               "controller.current_period", "controller.encoder_counts",
               "controller.grating_resolution", "stiffness.support_bearing_count")
#: the linear band's bisection tolerance [m/s] (feeddrive.analysis.linear.stability_band)
LINEAR_RESOLUTION = 1e-6


def _value(params: Any, path: str) -> Any:
    obj = params
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def parameter_paths(params: DriveParameters, drive: str,
                    patterns: Sequence[str] | None = None) -> tuple[list[str], dict[str, str]]:
    """(paths to vary, {left-out path: reason}) for ``params`` on ``drive``.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        The drive (sites and motors it does not use are left out).
    patterns : sequence of str, optional
        Glob patterns of the paths to vary; every numeric one by default.

    Returns
    -------
    paths : list of str
        The paths to vary.
    skipped : dict of str to str
        Left-out path → reason.

    Raises
    ------
    ParameterError
        When the patterns match no numeric parameter.
    """
    import dataclasses

    from ..sweep.design import numeric_paths
    from .fit import Experiment, _no_effect

    t = np.array([0.0, 1.0])
    forward = Experiment(source="", time=t, signals={}, reference_time=t,
                         table_speed=np.array([1e-3, 1e-3]))
    keep: list[str] = []
    skipped: dict[str, str] = {}
    for path in numeric_paths(params):
        if patterns and not any(fnmatch.fnmatchcase(path, p) for p in patterns):
            continue
        value = float(_value(params, path))
        reason = _no_effect(params, drive, path, [forward])
        if reason is None and path in _STRUCTURAL:
            reason = "a structural switch, not a scale"
        if reason is None and path.endswith("smoothing_velocity"):
            site = _value(params, path.rsplit(".", 1)[0])
            if getattr(site, "law", "lugre") == "lugre":
                reason = "used by the static friction law only"
        if reason is None and path.endswith("_limit"):
            parent = _value(params, path.rsplit(".", 1)[0])
            meta = {f.name: f.metadata for f in dataclasses.fields(parent)}
            if value >= meta[path.rsplit(".", 1)[1]]["high"]:
                reason = "no limit in effect (the top of its range)"
        if reason is None and value == 0.0 and path not in ZERO_SCALES:
            reason = "zero-valued, no stated scale for an absolute step"
        if reason:
            skipped[path] = reason
        else:
            keep.append(path)
    if patterns and not keep and not skipped:
        raise ParameterError("--parameters", list(patterns), "matches no numeric parameter")
    return keep, skipped


@dataclass(frozen=True)
class Entry:
    """The sensitivity of the quantity to one parameter.

    Parameters
    ----------
    path : str
        The parameter's dotted path.
    value : float
        Its base value p₀ [SI unit of the parameter].
    absolute : bool
        p₀ = 0: a derivative dQ/dp, not an elasticity.
    step : float
        The relative step h (absolute: h·s is the step) [-].
    q_minus : float
        Q at p₀(1 − h) [m/s].
    q_plus : float
        Q at p₀(1 + h) [m/s].
    elasticity : float
        E = (ΔQ/Q₀)/(Δp/p₀) [-] (absolute: dQ/dp [SI/SI]); nan when not resolved.
    bound : float
        When not resolved, |E| < bound [-].
    resolved : bool
        Whether the step's effect exceeds the resolution enough.
    halved : float
        E at h/2 [-]; nan when not resolved.
    consistent : bool
        Whether E at h and h/2 agree.
    note : str, default ""
        Why it is not resolved or not consistent.
    """
    path: str
    value: float  # p₀ [SI]
    absolute: bool  # zero-valued: derivative, not elasticity
    step: float  # relative h (absolute: h·s is the step [SI])
    q_minus: float  # [SI]
    q_plus: float
    elasticity: float  # E (relative) or dQ/dp [SI/SI] (absolute); nan if not resolved
    bound: float  # |E| < bound when not resolved
    resolved: bool
    halved: float  # E at h/2 (nan if not resolved)
    consistent: bool
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The entry for the JSON report.

        Returns
        -------
        dict
            The fields, non-finite numbers as None: Q at the two steps in mm/s
            (``q_minus_mm_s``, ``q_plus_mm_s``, beside the result's ``base_mm_s``), the parameter's
            value in its SI unit, and ``elasticity`` [-] — for ``kind = "derivative"`` (a
            zero-valued parameter) dQ/dp in m/s per SI unit of the parameter.
        """
        def fin(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"path": self.path, "value": self.value, "kind": "derivative" if self.absolute
                else "elasticity", "step": self.step, "q_minus_mm_s": fin(1e3 * self.q_minus),
                "q_plus_mm_s": fin(1e3 * self.q_plus), "elasticity": fin(self.elasticity),
                "bound": fin(self.bound), "resolved": self.resolved,
                "elasticity_half_step": fin(self.halved),
                "halving_consistent": self.consistent, "note": self.note}


@dataclass(frozen=True)
class SensitivityResult:
    """Elasticities of a quantity (critical speed or the linear band's upper edge) to every
    varied parameter.

    Parameters
    ----------
    parameter_set : str
        The set's name.
    drive : str
        The drive.
    quantity : str
        ``"critical_speed"`` or ``"linear_upper"``.
    base : float
        Q₀ at the base point [m/s].
    resolution : float
        Resolution of Q [m/s].
    entries : tuple of Entry
        Ranked by |E|, resolved first.
    skipped : dict of str to str
        Left-out path → reason.
    evaluations : int
        Points evaluated.
    executor : str
        Where they ran.
    """
    parameter_set: str
    drive: str
    quantity: str  # "critical_speed" or "linear_upper"
    base: float  # Q₀ [m/s]
    resolution: float  # [m/s]
    entries: tuple[Entry, ...]  # ranked by |E|, resolved first
    skipped: dict[str, str]
    evaluations: int
    executor: str

    def to_dict(self) -> dict[str, Any]:
        """The result for the JSON report (``feeddrive sensitivity --json``).

        Returns
        -------
        dict
            Set, drive, quantity, Q₀ and resolution [mm/s], the rule, the entries, the skipped
            paths and the counts.
        """
        return {"parameter_set": self.parameter_set, "drive": self.drive,
                "quantity": self.quantity, "base_mm_s": self.base * 1e3,
                "resolution_mm_s": self.resolution * 1e3,
                "rule": (f"each step's effect ≥ {MIN_EFFECT_RESOLUTIONS:g}× the resolution "
                         f"(steps tried {', '.join(f'{h:g}' for h in STEPS)}), checked by "
                         "halving"),
                "entries": [e.to_dict() for e in self.entries], "skipped": self.skipped,
                "evaluations": self.evaluations, "executor": self.executor}


def _task(config: Any, params: DriveParameters) -> dict[str, Any]:
    """The sweep task of ``params`` (as :meth:`SweepConfig.task` builds it), with the
    integrator settings in force (:meth:`feeddrive.SolverOptions.record`): the worker runs
    its critical-speed searches at them, and the store's key carries them."""
    from ..engine.options import current
    from ..engine.simulate import DriveSystem
    from ..parameters import dumps

    position = config.table_position * 1e-3
    DriveSystem(params, drive=config.drive, table_position=position)
    return {"parameters": dumps(params), "drive": config.drive, "table_position": position,
            "nut_speed": 0.0, "quantity": config.quantity.to_dict(),
            "solver": current().record()}


def _linear_upper(task: dict[str, Any], params: DriveParameters | None) -> dict[str, Any]:
    """The linear band's upper edge of one in-process point, the only value the elasticities
    read: :func:`feeddrive.analysis.linear.upper_band_edge` (the edge
    :func:`feeddrive.sweep.quantities.evaluate` stores, bit for bit, at 15 of its 37
    linearisations on the report's grid); ``error`` as ``evaluate`` gives it."""
    from ..analysis.linear import upper_band_edge
    from ..engine.simulate import DriveSystem, SimulationError
    from ..parameters import loads

    q = task["quantity"]
    try:
        system = DriveSystem(params if params is not None else loads(task["parameters"]),
                             drive=task["drive"], table_position=task["table_position"])
        edge = upper_band_edge(system, task["nut_speed"], low=q["low"], high=q["high"],
                               points=q["linear_points"])
    except (SimulationError, ValueError, ArithmeticError) as err:
        return {"error": f"{type(err).__name__}: {err}"}
    return {"values": {"linear_upper": edge}}


def _points_for(config: Any, params: DriveParameters, path: str, value: float, h: float,
                absolute: bool, sets: dict[str, DriveParameters]) -> list[Any] | None:
    """The two points of ``path`` moved by ∓``h``, or None when the set refuses a step;
    ``sets`` receives each point's parameter set by its key."""
    from ..sweep.design import Point
    from ..sweep.store import point_key

    delta = h * (ZERO_SCALES[path] if absolute else value)
    out = []
    for sign in (-1.0, 1.0):
        coords = {path: value + sign * delta}
        try:
            moved = params.replace_path(path, value + sign * delta)
            task = _task(config, moved)
        except ParameterError:
            return None
        out.append(Point(index=0, coords=coords, task=task, key=point_key(task)))
        sets[out[-1].key] = moved
    return out


def default_store(source: str, drive: str, quantity: str) -> Path:
    """The store :func:`sensitivity` keeps its points in when given none: in the working
    folder, named after the set, the drive and the quantity.

    Parameters
    ----------
    source : str
        The parameter set's file or preset name.
    drive : str
        The drive.
    quantity : str
        ``"critical-speed"`` or ``"linear-band"``.

    Returns
    -------
    Path
        ``sensitivity-<set>-<drive>-<quantity>.sqlite``.
    """
    return Path(f"sensitivity-{Path(source).stem}-{drive}-{quantity}.sqlite")


def sensitivity(params_source: str | DriveParameters, *, drive: str = "cdfs",
                table_position: float = 0.4,
                quantity: str = "linear-band", patterns: Sequence[str] | None = None,
                linear_points: int | None = None,
                store: str | os.PathLike[str] | None = None, workers: int | None = None,
                dask_workers: int | None = None, scheduler: str | None = None,
                in_process: bool = False,
                progress: Callable[[str], None] | None = None) -> SensitivityResult:
    """Elasticities of ``quantity`` (``critical-speed`` or ``linear-band``) of the set
    ``params_source`` (a preset name or a .toml file) on ``drive`` (see the module).  Points
    run through :func:`feeddrive.sweep.run_sweep` (store, local pool or Dask), or, with
    ``in_process``, through the same :func:`feeddrive.sweep.quantities.evaluate` here (the
    ``linear-band`` edge through :func:`feeddrive.analysis.linear.upper_band_edge`: the same
    number with the operating points it needs only).

    Parameters
    ----------
    params_source : str or DriveParameters
        A preset name, a ``.toml`` file or a parameter set.
    drive : str, default "cdfs"
        The drive.
    table_position : float, default 0.4
        Table position [m].
    quantity : str, default "linear-band"
        ``"critical-speed"`` or ``"linear-band"``.
    patterns : sequence of str, optional
        Glob patterns of the paths to vary.
    linear_points : int, optional
        Speeds of the linear scan (``linear-band``; refused for ``critical-speed``, whose
        search runs without the linear band).
    store : str or os.PathLike, optional
        The sweep store.
    workers : int, optional
        Local worker processes.
    dask_workers : int, optional
        Workers of a local Dask cluster.
    scheduler : str, optional
        Address of a Dask scheduler.
    in_process : bool, default False
        Evaluate here, without a store or pool.
    progress : callable, optional
        Told in one line what is being done.

    Returns
    -------
    SensitivityResult
        The ranked elasticities.
    """
    from ..sweep import SweepStore
    from ..sweep.design import SweepConfig, _load_base
    from ..sweep.executors import check_executor, run_sweep
    from ..sweep.quantities import QuantitySettings, check_task, evaluate

    say = progress or (lambda _t: None)
    check_executor(workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    if quantity not in ("critical-speed", "linear-band"):
        raise ParameterError("--quantity", quantity, "expected critical-speed or linear-band")
    in_process = check_flag("in_process", in_process)  # "no" ran in this process
    if quantity == "critical-speed" and linear_points is not None:  # taken, hashed, unused
        raise ParameterError("linear_points", linear_points, "not read by quantity "
                             "critical-speed (its search runs without the linear band); it "
                             "sets the scan of quantity linear-band")
    if isinstance(patterns, str):  # one pattern as text: its letters were read as patterns
        raise ParameterError("patterns", patterns, f"expected a list of glob patterns, e.g. "
                             f"[{patterns[:60]!r}] (--parameters on the command line)")
    if isinstance(params_source, DriveParameters):
        params, source = params_source, params_source.name
    else:
        source = os.fspath(Path(params_source).resolve()) if params_source.endswith(".toml") \
            else params_source
        params = _load_base(source, source)
    # the position checked in metres, as given (the sweep it builds takes mm, and its message
    # said "900.0 … the configuration's positions are in mm" of 0.9 m: an outside check,
    # 2026-12-07)
    from ..engine.simulate import DriveSystem

    DriveSystem(params, drive=drive, table_position=table_position)
    paths, skipped = parameter_paths(params, drive, patterns)
    if not paths:
        raise ParameterError("--parameters", list(patterns or []), "leaves no parameter to "
                             "vary (" + "; ".join(f"{k}: {v}" for k, v in skipped.items())[:300]
                             + ")")
    spec: dict[str, Any] = {"kind": quantity}  # only what the kind reads (quantities.READS)
    if quantity == "critical-speed":
        spec["linear"] = False
    if linear_points is not None:
        spec["linear_points"] = linear_points
    settings = QuantitySettings.parse(spec)
    resolution = settings.resolution if quantity == "critical-speed" else LINEAR_RESOLUTION
    key_name = "critical_speed" if quantity == "critical-speed" else "linear_upper"
    config = SweepConfig(name=default_store(source, drive, quantity).stem,
                         source=source if source.endswith(".toml") else "sensitivity.toml",
                         base=source, drive=drive, table_position=table_position * 1e3,
                         nut_speed=0.0, design="grid", samples=None, seed=0, axes=(),
                         quantity=settings, store=None, raw={"sensitivity": True})
    results: dict[str, dict[str, Any]] = {}
    sets: dict[str, DriveParameters] = {}  # each point's set, as its task's TOML reads back
    count = 0
    rounds: list[str] = []
    where = "this process"
    base_point = next(iter(config.iter_points()), None)
    if base_point is not None:  # the base set's refusals before the store is made
        check_task(base_point.task)
    db = None if in_process else SweepStore(
        Path(store) if store is not None else default_store(source, drive, quantity),
        option="--store")

    def run(points: list[Any]) -> None:
        nonlocal count, where
        todo = [p for p in points if p.key not in results]
        todo = list({p.key: p for p in todo}.values())
        if not todo:
            return
        if db is None:
            one = _linear_upper if quantity == "linear-band" else evaluate
            for k, p in enumerate(todo, start=1):
                results[p.key] = one(p.task, sets.get(p.key))
                say(f"{k}/{len(todo)} points")
        else:
            import dataclasses

            todo = [dataclasses.replace(p, index=i) for i, p in enumerate(todo)]
            stage = dataclasses.replace(config, name=f"{config.name}-{len(rounds)}")
            rounds.append(stage.name)
            summary = run_sweep(stage, db, workers=workers, scheduler=scheduler,
                                dask_workers=dask_workers, points=todo,
                                progress=lambda d, n: say(f"{d}/{n} points"))
            where = summary.executor if summary.computed else where
            for p in todo:
                results[p.key] = db.get(p.key) or {"error": "missing"}
        count += len(todo)

    def q(point: Any) -> float:
        got = results[point.key]
        v = got.get("values", {}).get(key_name, math.nan)
        if quantity == "critical-speed" and got.get("values", {}).get("status") != "found":
            return math.nan
        return float(v) if isinstance(v, int | float) else math.nan

    try:
        from ..sweep.design import Point
        from ..sweep.store import point_key

        base_task = _task(config, params)
        base_point = Point(index=0, coords={}, task=base_task, key=point_key(base_task))
        sets[base_point.key] = params
        run([base_point])
        q0 = q(base_point)
        if not math.isfinite(q0) or q0 == 0:
            raise ParameterError("parameters", params.name, f"the base set's {key_name} is not "
                                 "found in the searched range; nothing to differentiate")
        state: dict[str, dict[str, Any]] = {p: {"k": 0, "done": False, "pts": None}
                                            for p in paths}
        for h_index, h in enumerate(STEPS):
            batch = []
            for path in paths:
                st = state[path]
                if st["done"]:
                    continue
                value = float(_value(params, path))
                pts = _points_for(config, params, path, value, h, value == 0.0, sets)
                if pts is None:
                    st["done"] = True
                    st["note"] = f"a ±{h:g} step is refused by the set's checks"
                    continue
                st["pts"], st["h"] = pts, h
                batch += pts
            say(f"step ±{h:g}: {len(batch)} points")
            run(batch)
            for path in paths:
                st = state[path]
                if st["done"] or st.get("h") != h:
                    continue
                qm, qp = q(st["pts"][0]), q(st["pts"][1])
                st["qm"], st["qp"] = qm, qp
                if math.isfinite(qm) and math.isfinite(qp) and \
                        abs(qp - qm) >= MIN_EFFECT_RESOLUTIONS * resolution:
                    st["done"], st["resolved"] = True, True
                elif h_index == len(STEPS) - 1:
                    st["done"] = True
        # halving check of the resolved ones
        batch = []
        for path in paths:
            st = state[path]
            if st.get("resolved"):
                value = float(_value(params, path))
                half = _points_for(config, params, path, value, st["h"] / 2, value == 0.0,
                                   sets)
                st["half"] = half
                batch += half or []
        say(f"halving check: {len(batch)} points")
        run(batch)
    finally:
        if db is not None:
            db.close()
    entries: list[Entry] = []
    for path in paths:
        st = state[path]
        value = float(_value(params, path))
        absolute = value == 0.0
        h = st.get("h", math.nan)
        scale = ZERO_SCALES.get(path, 1.0) if absolute else q0
        qm, qp = st.get("qm", math.nan), st.get("qp", math.nan)
        note = st.get("note", "")
        if st.get("resolved"):
            e = (qp - qm) / (2 * h * scale)
            half = st.get("half")
            if half:
                eh = (q(half[1]) - q(half[0])) / (h * scale)
            else:
                eh = math.nan
            tol = max(0.2 * abs(e), 2 * resolution / (h * scale))
            consistent = math.isfinite(eh) and abs(eh - e) <= tol
            if not consistent:
                note = note or (f"nonlinear: at half the step {eh:.3g} against {e:.3g}")
            entries.append(Entry(path, value, absolute, h, qm, qp, e, math.nan, True, eh,
                                 consistent, note))
        else:
            if not math.isfinite(h):
                bound = math.nan
            else:
                bound = MIN_EFFECT_RESOLUTIONS * resolution / (2 * h * scale)
            if not note:
                note = ("a trial failed or left the range" if not (math.isfinite(qm) and
                                                                   math.isfinite(qp))
                        else f"effect below {MIN_EFFECT_RESOLUTIONS:g}× the resolution at "
                        f"±{h:g}")
            entries.append(Entry(path, value, absolute, h, qm, qp, math.nan, bound, False,
                                 math.nan, False, note))
    entries.sort(key=lambda e: (not e.resolved, -abs(e.elasticity) if e.resolved else
                                -(e.bound if math.isfinite(e.bound) else 0.0)))
    return SensitivityResult(parameter_set=params.name, drive=drive, quantity=key_name,
                             base=q0, resolution=resolution, entries=tuple(entries),
                             skipped=skipped, evaluations=count, executor=where)


def plot_tornado(result: SensitivityResult, path: str | os.PathLike[str],
                 top: int = 20) -> Path:
    """Ranked tornado chart: for each resolved parameter, the change of Q [%] at −h and +h
    (the step beside its name); absolute derivatives are marked.

    Parameters
    ----------
    result : SensitivityResult
        The result.
    path : str or os.PathLike
        The image file.
    top : int, default 20
        Most parameters shown.

    Returns
    -------
    Path
        The file written.
    """
    from matplotlib.figure import Figure

    rows = [e for e in result.entries if e.resolved][:top]
    fig = Figure(figsize=(9, 0.32 * max(len(rows), 3) + 1.4))
    ax = fig.subplots()
    y = np.arange(len(rows))[::-1]
    for yi, e in zip(y, rows, strict=True):
        lo = 100 * (e.q_minus / result.base - 1)
        hi = 100 * (e.q_plus / result.base - 1)
        ax.barh(yi, lo, color="C0", alpha=0.8)
        ax.barh(yi, hi, color="C3", alpha=0.8)
    labels = [f"{e.path} (±{100 * e.step:g} %{', abs' if e.absolute else ''})"
              + ("" if e.consistent else " *") for e in rows]
    ax.set_yticks(y, labels, fontsize=7)
    ax.axvline(0, color="k", lw=0.8)
    what = "critical speed" if result.quantity == "critical_speed" else \
        "linear band's upper edge"
    ax.set_xlabel(f"change of the {what} [%] (blue: parameter −step, red: +step; "
                  f"base {result.base * 1e3:.3f} mm/s)", fontsize=8)
    ax.set_title(f"{result.parameter_set}, {result.drive.upper()}: {what} by parameter "
                 "(* halving check failed: nonlinear)", fontsize=9)
    fig.tight_layout()
    from ..io.outputs import save_figure

    return save_figure(fig, path, dpi=100)
