"""Every friction compensation side by side (issue 37 item 4): none, the static feed-forward,
the LuGre observer, the disturbance observer, the reset integrator and the reversal
feed-forward, each on the same sampled drive, on four numbers — the critical creeping speed
(a coarse search), the circular test's largest reversal spike (ISO 230-4 on an XY table of two
such axes), the ISO 230-2 reversal value B, and the settling time of a small move to a band.
Where a quantity is not defined for a scheme's run the row says why instead of a figure: B
read while the axis still moves (``not at rest``), a critical speed where the reset
integrator's own cycle, not friction, keeps the motion from being smooth (``reset cycle``).

Each scheme's settings come from its part's documentation (docs/extending.md, docs/linear.md),
derived from the drive's parameters where the docs give a rule; none is tuned here:

* static feed-forward and LuGre observer: :class:`feeddrive.model.loops.Compensation` with the
  exact friction model (mismatch 1, observer gain k = 0, the only k stable at every speed);
* disturbance observer: Q-filter bandwidth g = 300 rad/s (the figure docs/extending.md
  measures), nominal J_n/K_t = (J_m + J_s + m_t·H²)/K_t;
* reset integrator: γ = 0 (a full reset, Beerens et al. 2019/2021);
* reversal feed-forward: I_r = F_c·H/K_t (the screw's and the guide's Coulomb friction as motor
  current), v_w = 2 mm/s, at the velocity loop's period.

The disturbance observer and the reset integrator refuse a continuous velocity loop, while the
static feed-forward and the LuGre observer are modelled with continuous current and velocity
loops only.  So the rows rest on one parameter set with sampled loops (by default
``wang2021-drive``: 8/4/2 kHz, 0.05-µm scale): ``none``, the disturbance observer, the reset
integrator and the reversal feed-forward run on it as it is; ``none-continuous``, the static
feed-forward and the LuGre observer on it with continuous loops and exact feedback (all three
periods, ``encoder_counts`` and ``grating_resolution`` set to 0: the model refuses
quantisation without sampled loops), limits kept.  Each row states its loops.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..model.loops import Compensation
from ..parameters import DriveParameters, ParameterError
from ..parameters.validation import refuse_repeats

#: the schemes in the order of the table
SCHEMES = ("none", "none-continuous", "feedforward", "observer", "disturbance-observer",
           "reset-integrator", "reversal-feedforward")
#: the schemes that run with continuous current and velocity loops (the static feed-forward
#: and the LuGre observer are modelled with continuous loops only); ``none-continuous`` is
#: their baseline
CONTINUOUS = ("none-continuous", "feedforward", "observer")
#: the quantities of a row, in the order of the table
METRICS = ("critical", "spike", "reversal", "settling")
#: what a list of schemes or of quantities holds, said when one is given twice
#: (:func:`~feeddrive.parameters.validation.refuse_repeats`)
SCHEME_ONCE = "each scheme once (twice, it would run twice and its row repeat)"
METRIC_ONCE = "each quantity once (it is measured once per scheme)"
#: the disturbance observer's Q-filter bandwidth [rad/s] (docs/extending.md's measured figure)
DOB_BANDWIDTH = 300.0
#: the reversal feed-forward's width v_w [m/s] (docs/extending.md's measured figure)
REVERSAL_WIDTH = 2e-3
#: the coarse critical-speed search: range, scan step and bisection resolution [m/s]
CRITICAL_RANGE = (2e-4, 3.2e-3)
CRITICAL_STEP = 1e-3
CRITICAL_RESOLUTION = 2.5e-4
#: the settling move [m], its feed [m/s], acceleration [m/s²] and dwell after it [s]
SETTLING_MOVE = 10e-6
SETTLING_FEED = 1e-3
SETTLING_ACCELERATION = 0.1
SETTLING_DWELL = 2.0
#: the circular test: radius [m], feed [m/s], acceleration [m/s²]
CIRCLE_RADIUS = 5e-3
CIRCLE_FEED = 5e-3
CIRCLE_ACCELERATION = 0.5
#: the positioning test: targets [m] (about the axis' table position), feed [m/s], dwell [s],
#: overshoot [m].  The dwell outlasts the ringing of the set's least-damped servo mode (5.5 Hz,
#: real part −1.15 1/s with the LuGre observer, −1.79 1/s uncompensated, linearised at 5 mm/s):
#: at 0.3 s every row read a moving axis (B of the observer 273 µm, 630 µm of motion within a
#: reading window); B is printed only when each reading window's motion is within the band
POSITIONING_TARGETS = (-1e-3, 1e-3)
POSITIONING_FEED = 5e-3
POSITIONING_DWELL = 4.0
POSITIONING_OVERSHOOT = 0.5e-3
#: how long the reset-cycle check runs at the top of the critical-speed range [s]
RESET_CHECK_DURATION = 6.0


#: the table's columns: (key of a row, heading with its unit)
COLUMNS = (("critical_speed_mm_s", "critical speed [mm/s]"),
           ("largest_spike_um", "largest reversal spike [µm]"),
           ("reversal_value_B_um", "ISO 230-2 B [µm]"),
           ("settling_time_s", "settling time [s]"))


@dataclass(frozen=True)
class Scheme:
    """One compensation scheme of the comparison.

    Parameters
    ----------
    name : str
        One of :data:`SCHEMES`.
    parameters : DriveParameters
        The drive's parameter set with the scheme applied.
    settings : dict
        What the scheme sets, in the table's units, and where each value comes from.
    """

    name: str
    parameters: DriveParameters
    settings: dict[str, Any]


def _with_section(params: DriveParameters, name: str, section: Any) -> DriveParameters:
    kept = tuple((k, v) for k, v in params.sections if k != name)
    return dataclasses.replace(params, sections=kept + ((name, section),))


def check_sampled(params: DriveParameters) -> None:
    """Refuse a set whose velocity loop is continuous: the disturbance observer and the reset
    integrator run at the sampled loop's instants.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Raises
    ------
    ParameterError
        ``controller.velocity_period`` is 0 (continuous).
    """
    if not params.controller.velocity_period > 0.0:
        raise ParameterError("controller.velocity_period", params.controller.velocity_period,
                             "the comparison needs a sampled velocity loop (> 0 s), e.g. "
                             "--preset wang2021-drive")


def motor_inertia_gain(params: DriveParameters) -> float:
    """J_n/K_t of the CDFS screw axis: motor, screw shaft and table (m_t·H²) over K_t
    [A s²/rad] (Wang2021 Tables 1–2; the disturbance observer's nominal model).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    float
        J_n/K_t [A s²/rad].

    References
    ----------
    .. [1] Wang2021 Tables 1–2.
    .. [2] Umeno, T., Hori, Y. (1991). Robust speed control of DC servomotors using modern two
       degrees-of-freedom controller design. IEEE Trans. Ind. Electron. 38(5), 363–368.
    """
    h = params.screw.lead / (2.0 * math.pi)
    inertia = (params.screw_motor.inertia + params.screw.shaft_inertia
               + params.table.mass * h ** 2)
    return float(inertia / params.screw_motor.torque_constant)


def coulomb_current(params: DriveParameters) -> float:
    """I_r = F_c·H/K_t: the screw's and the guide's Coulomb friction as motor current [A]
    (docs/extending.md, the reversal feed-forward).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    float
        I_r [A].

    References
    ----------
    .. [1] Wang2021 Table 1 (F_c of the screw and the guide).
    """
    h = params.screw.lead / (2.0 * math.pi)
    force = (params.friction.screw.positive.coulomb_force
             + params.friction.guide.positive.coulomb_force)
    return float(force * h / params.screw_motor.torque_constant)


def schemes(params: DriveParameters, names: Sequence[str] = SCHEMES, *,
            reversal_current: float | None = None) -> list[Scheme]:
    """The schemes applied to ``params``, with their settings.

    Parameters
    ----------
    params : DriveParameters
        A set with a sampled velocity loop (:func:`check_sampled`).
    names : sequence of str, default SCHEMES
        The schemes wanted, each once.
    reversal_current : float, optional
        I_r of the reversal feed-forward [A]; default :func:`coulomb_current`.

    Returns
    -------
    list of Scheme
        One per name, in the order given.

    Raises
    ------
    ParameterError
        For a set without sampled loops, a name :data:`SCHEMES` does not hold, or one given
        twice.
    """
    from ..model.parts.disturbance_observer import DisturbanceObserver
    from ..model.parts.reset_integrator import ResetIntegrator
    from ..model.parts.reversal_feedforward import ReversalFeedforward

    check_sampled(params)
    check_names(names, SCHEMES, SCHEME_ONCE, "names")  # one scheme made twice (session 30)
    base = params.replace_path("controller.compensation", Compensation())
    c = params.controller
    continuous = base.replace_path("controller", base.controller.with_values(
        current_period=0.0, velocity_period=0.0, position_period=0.0, encoder_counts=0.0,
        grating_resolution=0.0))
    sampled_loops = (f"sampled: current {c.current_period:g} s, velocity "
                     f"{c.velocity_period:g} s, position {c.position_period:g} s")
    continuous_loops = "continuous loops, no quantisation (the feedback exact)"
    out = []
    s: dict[str, Any]
    for name in names:
        if name == "none":
            p, s = base, {"compensation": "none"}
        elif name == "none-continuous":
            p, s = continuous, {"compensation": "none"}
        elif name in ("feedforward", "observer"):
            p = continuous.replace_path("controller.compensation", Compensation(mode=name))
            s = {"compensation": name, "model": "exact (scales 1)", "observer_gain_1_s": 0.0}
            if name == "feedforward":
                del s["observer_gain_1_s"]
        elif name == "disturbance-observer":
            gain = motor_inertia_gain(params)
            p = _with_section(base, "disturbance_observer",
                              DisturbanceObserver(bandwidth=DOB_BANDWIDTH, inertia_gain=gain))
            s = {"bandwidth_rad_s": DOB_BANDWIDTH, "inertia_gain_A_s2_rad": gain,
                 "rule": "J_n/K_t = (J_m + J_s + m_t·H²)/K_t"}
        elif name == "reset-integrator":
            p = _with_section(base, "reset_integrator", ResetIntegrator(fraction=0.0))
            s = {"fraction": 0.0, "rule": "full reset at position-error zero crossings"}
        else:
            current = coulomb_current(params) if reversal_current is None else reversal_current
            period = params.controller.velocity_period
            p = _with_section(base, "reversal_feedforward", ReversalFeedforward(
                current=current, width=REVERSAL_WIDTH, period=period))
            s = {"current_A": current, "width_mm_s": 1e3 * REVERSAL_WIDTH,
                 "period_s": period, "rule": "I_r = F_c·H/K_t (screw + guide)"}
        s["loops"] = continuous_loops if name in CONTINUOUS else sampled_loops
        out.append(Scheme(name, p, s))
    return out


def settling_time(time: np.ndarray, error: np.ndarray, band: float, start: float) -> float:
    """The time from ``start`` after which |error| stays within ``band`` to the end; NaN
    when it is outside at the end.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    error : numpy.ndarray
        Position error [m].
    band : float
        Half-width of the band [m].
    start : float
        When the move ends [s].

    Returns
    -------
    float
        Settling time [s] (0 when inside from ``start`` on).
    """
    after = time >= start
    t, e = time[after], np.abs(error[after])
    outside = np.flatnonzero(e > band)
    if outside.size == 0:
        return 0.0
    if outside[-1] == e.size - 1:
        return math.nan
    return float(t[outside[-1] + 1] - start)


def reset_rate(system: Any, speed: float, *, duration: float = RESET_CHECK_DURATION,
               options: Any = None) -> float:
    """Resets of the velocity-loop integral per second while the table is commanded at a
    constant ``speed``, over the second half of a ``duration`` run from rest.

    The critical creeping speed presumes a loop that runs smoothly once friction lets it; a
    reset integrator (set-point control, Beerens et al. [1]_) that keeps resetting at constant
    speed throws away the friction current its integral holds at every zero crossing of the
    tracking error, and drives a cycle of its own: on ``wang2021-drive`` 12 resets/s, two per
    period of a 6.1-Hz speed oscillation at 3.2 mm/s, where the same loop without resets is
    smooth (tests/unit/test_compensation_compare.py).

    Parameters
    ----------
    system : DriveSystem
        A drive whose parameters carry a ``[reset_integrator]``.
    speed : float
        Commanded table speed [m/s].
    duration : float, default RESET_CHECK_DURATION
        Length of the run [s].
    options : SolverOptions, optional
        Integrator settings.

    Returns
    -------
    float
        Resets per second [1/s] (0: the integral is no longer reset once moving).

    References
    ----------
    .. [1] R. Beerens, A. Bisoffi, L. Zaccarian, W. P. M. H. Heemels, H. Nijmeijer,
       N. van de Wouw, "Reset integral control for improved settling of PID-based motion
       systems with friction", Automatica 107 (2019) 483–492.
    """
    from ..engine.simulate import simulate
    from ..model.reference import ConstantSpeed

    r = simulate(system, ConstantSpeed(speed, 0.0, ramp_time=0.1), duration, options=options)
    t = np.asarray(r.time, dtype=float)
    count = np.asarray(r["reset_integrator_count"], dtype=float)
    half = t >= duration / 2.0
    return float((count[half][-1] - count[half][0]) / (t[half][-1] - t[half][0]))


def check_names(items: Sequence[str], known: Sequence[str], once: str, field: str) -> None:
    """Refuse a name ``known`` does not hold and one given twice, naming ``field`` (the
    argument, or the command line's option: ``--schemes``, ``--metrics``).

    Parameters
    ----------
    items : sequence of str
        The names asked for.
    known : sequence of str
        The names there are (:data:`SCHEMES`, :data:`METRICS`).
    once : str
        What a repeat would do, for the message (:data:`SCHEME_ONCE`, :data:`METRIC_ONCE`).
    field : str
        The name the message gives the list.

    Raises
    ------
    ParameterError
        One line: the unknown names and the known ones, or the repeated name.
    """
    bad = [n for n in items if n not in known]
    if bad:
        raise ParameterError(field, bad, f"expected some of {', '.join(known)}")
    refuse_repeats(field, items, once)


def _check_metrics(metrics: Sequence[str]) -> None:
    """Refuse a quantity :data:`METRICS` does not hold (:func:`measure` left it out without
    a word) and one given twice (counted twice in the progress's total)."""
    check_names(metrics, METRICS, METRIC_ONCE, "metrics")


def measure(scheme: Scheme, drive: str, table_position: float, metrics: Sequence[str], *,
            band: float, options: Any = None,
            progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """One row: the requested :data:`METRICS` of one scheme, each from its own run.

    Parameters
    ----------
    scheme : Scheme
        The scheme.
    drive : str
        The drive (a ball-screw drive with no driven nut, e.g. ``"cdfs"``).
    table_position : float
        Table position of the runs [m].
    metrics : sequence of str
        Some of :data:`METRICS`, each once.
    band : float
        Settling band [m]; also the most the axis may move within a positioning reading
        window (peak to peak) for B to be given (else B is "not at rest").
    options : SolverOptions, optional
        Integrator settings.
    progress : callable, optional
        ``progress(metric)`` before each metric's run.

    Returns
    -------
    dict
        The scheme, its settings and the numbers [mm/s, µm, s].  A critical speed is a
        number, a bound (``> 3.20``), or ``none smooth ≤ 3.20: reset cycle`` when no trial is
        smooth and the reset integrator still resets at the top speed (:func:`reset_rate`);
        B is a number or ``not at rest (… µm moving)``.

    Raises
    ------
    ParameterError
        For a quantity :data:`METRICS` does not hold, or one given twice.
    """
    from ..engine.simulate import DriveSystem, simulate
    from ..model.positioning_profile import stops_profile
    from .critical import critical_speed_from_rest, format_bands, format_critical_speed

    _check_metrics(metrics)
    p = scheme.parameters
    row: dict[str, Any] = {"scheme": scheme.name, "parameter_set": p.name,
                           "settings": scheme.settings}
    if "critical" in metrics:
        if progress:
            progress("critical")
        found = critical_speed_from_rest(
            DriveSystem(p, drive, table_position), speed_range=CRITICAL_RANGE,
            coarse_step=CRITICAL_STEP, resolution=CRITICAL_RESOLUTION, options=options)
        d = found.to_dict()
        row["critical_speed_mm_s"] = format_critical_speed(d)
        row["critical_speed_status"] = d.get("status")
        row["critical_speed_bands"] = format_bands(d)
        if d.get("status") == "above-range" and dict(p.sections).get("reset_integrator"):
            rate = reset_rate(DriveSystem(p, drive, table_position), CRITICAL_RANGE[1],
                              options=options)
            row["resets_per_s_at_top_speed"] = rate
            if rate > 0.0:
                row["critical_speed_mm_s"] = (f"none smooth ≤ {1e3 * CRITICAL_RANGE[1]:.2f}: "
                                              "reset cycle")
    if "spike" in metrics:
        if progress:
            progress("spike")
        from ..machine import Machine, MachineAxis
        from .circular_run import run_circular_test

        machine = Machine(name=f"xy {scheme.name}", axes=(
            MachineAxis("x", p, drive, table_position),
            MachineAxis("y", p, drive, table_position)))
        run = run_circular_test(machine, radius=CIRCLE_RADIUS, feed=CIRCLE_FEED,
                                acceleration=CIRCLE_ACCELERATION, options=options)
        heights = [abs(s.height) for s in run.test.spikes]
        row["largest_spike_um"] = 1e6 * max(heights) if heights else 0.0
        row["spikes_found"] = len(heights)
        assert run.lead_in is not None
        row["spike_lead_arc_deg"] = math.degrees(run.lead_in.arc)  # the settling rule's
    if "reversal" in metrics:
        if progress:
            progress("reversal")
        from .positioning_run import run_positioning_test

        targets = [table_position + t for t in POSITIONING_TARGETS]
        pos = run_positioning_test(p, drive, targets, feed=POSITIONING_FEED,
                                   dwell=POSITIONING_DWELL, overshoot=POSITIONING_OVERSHOOT,
                                   options=options)
        motion = float(pos.reading_motion)
        row["reversal_reading_motion_um"] = 1e6 * motion
        row["reversal_value_B_um"] = (1e6 * float(pos.test.reversal) if motion <= band else
                                      f"not at rest ({1e6 * motion:.3g} µm moving)")
    if "settling" in metrics:
        if progress:
            progress("settling")
        profile, ends = stops_profile([SETTLING_MOVE], feed=SETTLING_FEED,
                                      acceleration=SETTLING_ACCELERATION, dwell=SETTLING_DWELL)
        duration = float(profile.time[-1])
        r = simulate(DriveSystem(p, drive, table_position), profile, duration, options=options)
        t = np.asarray(r.time, dtype=float)
        err = np.asarray(r["table_position"], dtype=float) - SETTLING_MOVE
        move_end = float(ends[0]) - SETTLING_DWELL
        ts = settling_time(t, err, band, move_end)
        row["settling_time_s"] = ts
        row["settling_band_um"] = 1e6 * band
        tail = t >= move_end + (ts if math.isfinite(ts) else 0.0)
        row["error_after_settling_um"] = 1e6 * float(np.max(np.abs(err[tail])))
        row["settling_run_s"] = duration
    return row


def compare_compensations(params: DriveParameters, *, drive: str = "cdfs",
                          table_position: float = 0.4,
                          names: Sequence[str] = SCHEMES,
                          metrics: Sequence[str] = METRICS, band: float = 1e-6,
                          reversal_current: float | None = None, options: Any = None,
                          progress: Callable[[int, int, str], None] | None = None
                          ) -> list[dict[str, Any]]:
    """The comparison table: one row per scheme (:func:`schemes`, :func:`measure`).

    Parameters
    ----------
    params : DriveParameters
        A set with sampled loops.
    drive : str, default "cdfs"
        The drive.
    table_position : float, default 0.4
        Table position [m]; only the default on a drive whose model does not depend on it
        (:func:`~feeddrive.model.mechanisms.base.check_table_position`).
    names : sequence of str, default SCHEMES
        The schemes, each once.
    metrics : sequence of str, default METRICS
        The quantities, each once.
    band : float, default 1e-6
        Settling band [m], and the largest motion within a positioning reading window [m].
    reversal_current : float, optional
        I_r of the reversal feed-forward [A] (default F_c·H/K_t).
    options : SolverOptions, optional
        Integrator settings.
    progress : callable, optional
        ``progress(done, total, label)``.

    Returns
    -------
    list of dict
        The rows.

    Raises
    ------
    ParameterError
        Before any run: a quantity or scheme unknown or given twice, a band ≤ 0, a start
        position the drive's model does not read, a set without sampled loops.
    feeddrive.analysis.compensation.RowsInterrupted
        On Ctrl-C, with the schemes' rows finished before it.
    """
    from ..model.mechanisms.base import check_table_position
    from .compensation import RowsInterrupted

    _check_metrics(metrics)
    if not (math.isfinite(band) and band > 0.0):
        raise ParameterError("band", band, "expected a band > 0 [m]")
    # before any run: the reversal metric's targets would carry it to no model at all
    check_table_position(drive, table_position)
    chosen = schemes(params, names, reversal_current=reversal_current)
    total = len(chosen) * len(metrics)
    done = 0
    rows: list[dict[str, Any]] = []
    try:
        for scheme in chosen:
            def step(metric: str, name: str = scheme.name) -> None:
                nonlocal done
                if progress:
                    progress(done, total, f"{name}: {metric}")
                done += 1

            rows.append(measure(scheme, drive, table_position, metrics, band=band,
                                options=options, progress=step))
    except KeyboardInterrupt:  # the finished schemes' rows are kept (they were dropped)
        raise RowsInterrupted(rows, len(chosen)) from None
    if progress:
        progress(total, total, "done")
    return rows


def comparison_csv(rows: Sequence[dict[str, Any]]) -> str:
    """The table as CSV text: the scheme, every :data:`COLUMNS` value a row has (empty when
    not measured), the settling band [µm] and the scheme's settings.

    Parameters
    ----------
    rows : sequence of dict
        Rows of :func:`compare_compensations`.

    Returns
    -------
    str
        CSV text with a header line.
    """
    head = ["scheme", *(key for key, _ in COLUMNS), "settling_band_um", "parameter_set",
            "settings"]
    lines = [",".join(head)]
    for r in rows:
        cells = [r["scheme"], *(repr(r[k]) if isinstance(r.get(k), float) else
                                str(r.get(k, "")) for k, _ in COLUMNS),
                 str(r.get("settling_band_um", "")), r["parameter_set"],
                 '"' + "; ".join(f"{k}={v}" for k, v in r["settings"].items()) + '"']
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


__all__ = ["COLUMNS", "CONTINUOUS", "METRICS", "SCHEMES", "Scheme", "check_sampled",
           "compare_compensations", "comparison_csv", "coulomb_current", "measure",
           "motor_inertia_gain", "reset_rate", "schemes", "settling_time"]
