"""What the page shows, computed with the public API from checked settings.  Results are
plain JSON-ready dicts in the page's units (mm/s, mm, µm, N, Hz); the work is SI inside.

* :func:`run_simulation` — one constant-speed run: traces (table speed and its command, motor
  speeds), the summary (following error among it), the creep verdict with its kind
  (:func:`verdict_of`), and the steady
  friction curves of the sites the drive uses with their negative-slope bands and operating
  points;
* :func:`run_linear` — the linear stability band over table speed and the loop poles at the
  operating point (friction linearised there, rigid-body poles marked by
  :func:`feeddrive.analysis.linear.classify_poles`), loop margins and the loops' Bode curves;
* :func:`run_critical` — the critical-speed search from rest, the protocol `feeddrive creep`
  uses (``feeddrive.analysis.protocol``), with progress and cancellation at every trial.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from .._kept import Kept
from .settings import Checked

#: traces sent to the page keep at most this many samples (min/max per bucket, so that
#: stick-slip peaks survive)
MAX_POINTS = 4000

Report = Callable[[float, float, str], None]


def _f(value: Any) -> float | None:
    """A JSON number: None for None, NaN or ±inf."""
    if value is None:
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def _list(values: np.ndarray, scale: float = 1.0, digits: int = 7) -> list[float | None]:
    arr = np.asarray(values, dtype=float) * scale
    return [None if not math.isfinite(x) else float(f"{x:.{digits}g}") for x in arr.tolist()]


def decimate(n: int, key: np.ndarray, max_points: int = MAX_POINTS) -> np.ndarray:
    """Indices of at most ``max_points`` samples of ``n``: the minimum and maximum of ``key``
    in each bucket, in time order (peaks of a stick-slip trace stay visible).

    Parameters
    ----------
    n : int
        Number of samples.
    key : numpy.ndarray
        The signal the extremes are taken of [its unit].
    max_points : int, default 4000
        Most indices returned.

    Returns
    -------
    numpy.ndarray of int
        Sample indices, increasing.
    """
    if n <= max_points:
        return np.arange(n)
    buckets = max_points // 2
    edges = np.linspace(0, n, buckets + 1).astype(int)
    out = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        seg = key[a:b]
        i, j = a + int(np.argmin(seg)), a + int(np.argmax(seg))
        out.extend(sorted({i, j}))
    return np.asarray(out, dtype=int)


def diverged_verdict(at: float, duration: float) -> dict[str, Any]:
    """The verdict of a run that diverged: ``unstable``, where it stopped.

    Parameters
    ----------
    at : float
        When the run stopped [s].
    duration : float
        The simulated time asked for [s].

    Returns
    -------
    dict
        As :func:`verdict_of`, the kind ``unstable``.
    """
    from ..analysis.verdict_words import MEANING, UNSTABLE

    reason = (f"a speed left its bound at {at:.3g} s of the {duration:g} s asked for, and the "
              "run stopped there")
    return {"verdict": UNSTABLE, "kind": UNSTABLE,
            "text": f"{MEANING[UNSTABLE]}; {reason}", "reason": reason,
            "frequency_hz": None, "decided_at_s": _f(at), "ripple_ratio": None}


def verdict_of(time: np.ndarray, speed: np.ndarray, command_speed: float) -> dict[str, Any]:
    """The creep verdict and its kind, from the window-independent rule `feeddrive creep`
    judges every trial by (:func:`feeddrive.analysis.cycle_verdict.trace_verdict`): a limit cycle
    is *stick-slip* (the table stops) or *oscillation* (it does not); a decayed trace is
    *smooth*; a trace that has done neither yet is *undecided* (a longer run decides).

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    speed : numpy.ndarray
        Table speed [m/s].
    command_speed : float
        The commanded speed [m/s].

    Returns
    -------
    dict
        The verdict word, kind, a sentence, the reason, the limit cycle's frequency [Hz],
        when it was decided [s] and the ripple ratio [-].
    """
    from ..analysis.cycle_verdict import trace_verdict

    v = trace_verdict(time, speed, command_speed)
    ripple = f"ripple {100 * v.ripple_ratio:.3g} % of the command"
    at = f" at {v.frequency:.3g} Hz" if v.frequency else ""
    if v.kind == "stick-slip":
        text = f"the table stops and slips{at}, {ripple}; {v.reason}"
    elif v.kind == "oscillation":
        text = f"a sustained oscillation{at} without stopping, {ripple}; {v.reason}"
    elif v.kind == "smooth":
        text = f"settled by {v.decided_at:.3g} s: {v.reason}"
    else:
        text = (f"{v.reason} after {float(time[-1]):g} s ({ripple}{at}); a longer simulated "
                "time decides")
    # the rule named beside the word, as in every command (issue 24 item 4)
    text += " (limit-cycle rule of feeddrive creep)"
    return {"verdict": "creeping" if v.creeping else v.kind, "kind": v.kind, "text": text,
            "reason": v.reason, "frequency_hz": _f(v.frequency),
            "decided_at_s": _f(v.decided_at), "ripple_ratio": _f(v.ripple_ratio)}


def _sites(checked: Checked) -> dict[str, tuple[str, Any]]:
    """The friction sites that act in the checked drive, as the topology declares them (a
    held nut's friction does not): label → (parameter path, the site's parameters).  A site
    is labelled by the ``[friction]`` key of its parameters (the ball–nut contact shares the
    screw's) or, for a part's own section, by its name."""
    assert checked.system is not None and checked.params is not None
    out: dict[str, tuple[str, Any]] = {}
    for site in checked.system.topology().acting_sites():
        key = site.parameters_key
        label, path = (site.name, key) if "." in key else (key, f"friction.{key}")
        out.setdefault(label, (path, site.parameters(checked.params)))
    return out


def friction_curves(checked: Checked, operating: dict[str, float] | None = None
                    ) -> dict[str, Any]:
    """Steady friction force [N] against sliding speed [mm/s] at each site the drive uses,
    the speed bands where it falls (negative damping), and the sites' operating speeds.

    Parameters
    ----------
    checked : Checked
        The page's checked settings (:func:`feeddrive.explore.settings.check`).
    operating : dict of str to float, optional
        Site → its sliding speed at the operating point [m/s].

    Returns
    -------
    dict
        Per site: speeds [mm/s], forces [N] per branch, negative-slope bands [mm/s] and the
        operating speed [mm/s].
    """
    from ..model.friction.lugre_parameters import LuGreParameters
    from ..model.friction.stribeck import negative_slope_band, steady_friction

    params = checked.params
    assert params is not None
    sites = _sites(checked)
    bands: dict[str, list[list[float]]] = {}
    top = 2e-3
    for site, (path, site_params) in sites.items():
        lugre = site_params.require(LuGreParameters, path, "the explorer's friction curves")
        bands[site] = []
        for name, sign in (("positive", 1.0), ("negative", -1.0)):
            band = negative_slope_band(lugre.branch(name))
            if band is not None:
                lo, hi = sorted((sign * band.lower, sign * band.upper))
                bands[site].append([1e3 * lo, 1e3 * hi])
                if band.bounded:
                    top = max(top, 2.0 * band.upper)
    for speed in (operating or {}).values():
        top = max(top, 1.25 * abs(speed) * 1e-3)
    for site_bands in bands.values():  # an unbounded band (σ2 = 0) ends with the curves
        site_bands[:] = [[max(lo, -1e3 * top), min(hi, 1e3 * top)] for lo, hi in site_bands]
    v = np.linspace(-top, top, 801)
    curves = []
    for site, (_, lugre) in sites.items():
        curves.append({"site": site, "law": lugre.law, "speed_mm_s": _list(v, 1e3),
                       "force_n": _list(steady_friction(v, lugre)),
                       "negative_slope_mm_s": bands[site],
                       "operating_speed_mm_s": _f((operating or {}).get(site)),
                       "operating_force_n": _f(steady_friction(
                           np.array([1e-3 * operating[site]]), lugre)[0])
                       if operating and operating.get(site) is not None else None})
    return {"sites": curves, "ball_nut_share": params.friction.ball_nut_share}


def run_simulation(checked: Checked, report: Report,
                   keep: Callable[[Any], None] | None = None) -> dict[str, Any]:
    """One run at constant speed from rest; see the module docstring.  Progress is the
    simulated time reached, reported after each chunk of the solver (the compiled solver
    releases the GIL, so the server answers polls meanwhile); ``keep(result)`` receives the
    full Result (the explorer keeps it for the signal picker and the downloads).

    Parameters
    ----------
    checked : Checked
        The page's checked settings (:func:`feeddrive.explore.settings.check`).
    report : callable
        ``report(done, total, text)``: the job's progress (raises ``Cancelled`` once the page
        cancelled).
    keep : callable, optional
        Receives the full :class:`~feeddrive.engine.result.Result`.

    Returns
    -------
    dict
        Drive, parameter set, speeds [mm/s], duration [s], sample counts, the run's summary,
        the verdict (:func:`verdict_of`), the decimated traces and the friction curves
        (:func:`friction_curves`).
    """
    from ..cli import _units
    from ..engine.simulate import Simulation, SimulationInterrupted
    from ..model.reference import ConstantSpeed

    # a zero command refused before the run, in the words of `feeddrive simulate`
    _units.speed("--table-speed", checked.table_speed / _units.MM_PER_S, nonzero=True,
                 warn_small=False)
    what = f"simulating {checked.duration:g} s of the {checked.drive.upper()}"
    report(0.0, checked.duration, what)  # raises if the page cancelled before the start

    def progress(t: float, t_end: float) -> None:
        report(t, t_end, f"{what}: {t:.3g} s done")  # raises Cancelled between chunks

    sim = Simulation(checked.system, ConstantSpeed(checked.table_speed, checked.nut_speed))
    finished = threading.Event()

    def watch() -> None:
        # inside a long solver call: the time its compiled loop has reached, 10 times a
        # second; a cancel stops the compiled loop after the step it is in
        while not finished.wait(0.1):
            try:
                report(sim.live_time(), checked.duration,
                       f"{what}: {sim.live_time():.3g} s done")
            except Exception:  # the page cancelled (report raises Cancelled)
                sim.request_stop()
                return

    watcher = threading.Thread(target=watch, name="feeddrive-explore-progress", daemon=True)
    watcher.start()
    try:
        result = sim.run(checked.duration, progress=progress)
    except SimulationInterrupted:
        # stopped on the page's cancel: report raises its Cancelled
        report(sim.live_time(), checked.duration, "cancelled")
        raise RuntimeError("the run was stopped") from None
    finally:
        finished.set()
    if keep is not None:
        keep(result)
    summary = result.summary()
    t = result.time
    speed = result["table_speed"]
    idx = decimate(t.size, speed)
    traces: dict[str, Any] = {
        "time_s": _list(t[idx]),
        "table_speed_mm_s": _list(speed[idx], 1e3),
        "table_speed_reference_mm_s": _list(result["table_speed_reference"][idx], 1e3),
    }
    for name in ("screw_linear_speed", "nut_linear_speed"):
        if name in result:  # without building the xarray Dataset
            traces[f"{name}_mm_s"] = _list(result[name][idx], 1e3)
    operating = {"guide": summary.get("mean_table_speed_mm_s"),  # none if diverged at once
                 "screw": summary.get("mean_screw_speed_mm_s"),
                 "nut": summary.get("mean_nut_speed_mm_s")}
    clean = {k: v for k, v in summary.items() if k != "solver"}
    clean["solver"] = {k: summary["solver"][k] for k in ("method", "steps", "rejected_steps",
                                                         "wall_time_s", "diverged",
                                                         "diverged_at_s")
                       if k in summary["solver"]}
    stats = result.solver_stats
    # a diverged run stopped early: its verdict is that, not the limit-cycle rule's reading
    # of the cut trace ("undecided … a longer simulated time decides": an outside check,
    # 2026-12-07)
    verdict = (diverged_verdict(float(stats.get("diverged_at_s", t[-1])), checked.duration)
               if stats.get("diverged") else verdict_of(t, speed, checked.table_speed))
    return {
        "drive": checked.drive, "parameter_set": checked.params.name if checked.params else "",
        # whether the drive follows the nut command (its topology says; the page shows it then)
        "nut_driven": checked.system.topology().follows("nut"),
        "table_speed_mm_s": 1e3 * checked.table_speed,
        "nut_speed_mm_s": 1e3 * checked.nut_speed, "duration_s": checked.duration,
        "reached_s": float(t[-1]),
        "samples": int(t.size), "samples_sent": int(idx.size),
        "summary": _json(clean), "verdict": verdict,
        "traces": traces,
        "friction": friction_curves(checked, {k: v for k, v in operating.items()
                                              if v is not None}),
    }


def _json(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json(v) for v in value]
    if isinstance(value, float | np.floating):
        return _f(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def loop_json(values: dict[str, Any]) -> dict[str, Any]:
    """A loop's margins (:meth:`LoopResult.as_dict`) for the page, with ``infinite``: the
    names of its values that are +∞ — a gain margin without phase crossover, None in the
    analysis (:func:`feeddrive.units.absent_value`) — which JSON, without an infinity, sends
    as null; any other null is a value the loop has not (no gain crossover: no crossover
    frequency, phase margin or bandwidth), which the page prints "—", as `feeddrive loops`.

    Parameters
    ----------
    values : dict
        The loop's values, None where the analysis found none.

    Returns
    -------
    dict
        The same values and ``infinite`` (a list of names).
    """
    from ..units import absent_value

    infinite = [name for name, v in values.items()
                if (absent_value(name) if v is None else v) == math.inf]
    return {**values, "infinite": infinite}


#: stability bands by (parameters, drive, position, nut speed): a band does not depend on the
#: table speed, so moving that knob recomputes only the poles
BANDS = Kept(16)


def run_linear(checked: Checked, report: Report) -> dict[str, Any]:
    """Linear stability band over table speed and loop poles at the operating point.

    Parameters
    ----------
    checked : Checked
        The page's checked settings (:func:`feeddrive.explore.settings.check`).
    report : callable
        ``report(done, total, text)``: the job's progress (raises ``Cancelled`` once the page
        cancelled).

    Returns
    -------
    dict
        The Bode data of the loops, the stability band (:meth:`StabilityBand.as_dict` with
        the scan's speeds [mm/s], rightmost real parts [1/s] and frequencies [Hz]), whether
        the operating speed lies inside it, and the poles, least-damped mode and loop
        margins at the operating point (each loop's +∞ values, null in JSON, named in its
        ``infinite``: :func:`loop_json`).
    """
    from ..analysis.linear import loop_analysis, stability_band

    system = checked.system
    key = (checked.params, checked.drive, system.table_position, checked.nut_speed)
    band = BANDS.get(key)
    if band is None:
        def progress(k: int, n: int) -> None:
            report(k, n + 1, f"stability band: speed {k} of {n}")

        band = stability_band(system, checked.nut_speed, progress=progress)
        BANDS.put(key, band)
    v = checked.table_speed
    report(1.0, 1.0, "loop poles")
    loops = loop_analysis(system, v, checked.nut_speed, frictionless=False)
    d = loops.as_dict()
    inside = any(lo <= abs(v) <= hi for lo, hi in band.intervals)
    bode = [{"loop": lp.name, "frequency_hz": _list(lp.frequency_hz, digits=6),
             "magnitude_db": _list(lp.magnitude_db, digits=6),
             "phase_deg": _list(lp.phase_deg, digits=6), **loop_json(lp.as_dict())}
            for lp in loops.loops]
    return _json({
        "bode": bode, "notes": d["notes"], "pole_rule": d["pole_rule"],
        "band": {**band.as_dict(), "speeds_mm_s": _list(band.speeds, 1e3),
                 "max_real_part_1_per_s": _list(band.max_real_part),
                 "frequency_hz": _list(band.frequency_hz)},
        "inside_band": inside,
        "table_speed_mm_s": 1e3 * v,
        "poles": d["poles"], "least_damped_mode": d["least_damped_mode"],
        "loops": [loop_json(lp) for lp in d["loops"]],
        "friction": d["friction"],
    })


def estimated_trials() -> int:
    """Trials of a search from rest on the protocol's grid: the scan, then the bisection.

    Returns
    -------
    int
        Number of creep trials, for the progress bar.
    """
    from ..analysis import protocol

    lo, hi = protocol.SPEED_RANGE
    scan = int(math.floor((hi - lo) / protocol.COARSE_STEP + 1e-9)) + 1
    return scan + math.ceil(math.log2(protocol.COARSE_STEP / protocol.RESOLUTION))


def run_critical(checked: Checked, report: Report) -> dict[str, Any]:
    """Critical speed from rest, as `feeddrive creep` searches it (its grid, resolution and
    verdict rule), reporting every trial.

    Parameters
    ----------
    checked : Checked
        The page's checked settings (:func:`feeddrive.explore.settings.check`).
    report : callable
        ``report(done, total, text)``: the job's progress (raises ``Cancelled`` once the page
        cancelled).

    Returns
    -------
    dict
        The search's result as JSON-safe values, in engineering units (critical speed
        [mm/s], kind, trials, the deciding trials' integration error and its text as
        ``feeddrive creep`` writes it).
    """
    from ..analysis import protocol
    from ..analysis.critical import (
        critical_speed_from_rest,
        format_bands,
        format_integration_error,
        shadow_possible,
    )

    total = estimated_trials()
    report(0, total, f"trial 1 of about {total}")  # raises if cancelled before the start

    def progress(done: int, _: int) -> None:
        report(done, max(total, done + 1), f"trial {done + 1} of about {max(total, done + 1)}")

    found = critical_speed_from_rest(
        checked.system, nut_speed=checked.nut_speed, speed_range=protocol.SPEED_RANGE,
        coarse_step=protocol.COARSE_STEP, resolution=protocol.RESOLUTION, progress=progress,
        error_estimate=shadow_possible())  # as `feeddrive creep` states it
    out = found.to_dict()
    out["protocol"] = protocol.describe("rest")
    out["bands_text"] = format_bands(out)
    out["integration_error_text"] = format_integration_error(out).strip(" []")
    return _json(out)
