"""`feeddrive creep`: critical creeping speed and creeping bands."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import typer

from ..analysis import protocol
from . import _units
from ._common import (
    MM_PER_S,
    app,
    console,
    err_console,
    print_json,
    resolve_parameters,
    user_errors,
)
from ._creep_estimate import (
    ESTIMATE_HELP,
    RIPPLE_REASON,
    estimate_asked,
    integration_error,
    no_estimate_reason,
    not_estimated,
)
from ._creep_progress import SearchProgress, search_progress, stage
from ._solver import accuracy_options
from .simulate_cmd import ALL_DRIVES, ALL_DRIVES_TEXT, CLI_METHODS

if TYPE_CHECKING:
    from ..analysis.critical import CriticalSpeed
    from ..analysis.cycle_verdict import VerdictRule
    from ..engine.simulate import DriveSystem

_LOW, _HIGH = (round(v / MM_PER_S, 9) for v in protocol.SPEED_RANGE)
#: the unit of every field of ``creep --json`` whose name carries none (``units`` in the
#: JSON): a trial's (``feeddrive.analysis.critical.CreepTrial.to_dict``: its speed in mm/s,
#: the rest as stored) and the verdict rule's (``feeddrive.analysis.cycle_verdict.VerdictRule``)
UNITS = {
    "speed": "mm/s", "duration": "s", "decided_at": "s", "stick_slip_frequency": "Hz",
    "ripple_ratio": "-", "stick_fraction": "-", "min_ratio": "-",
    "smooth_band": "-", "settle_time": "s", "growth_blocks": "-", "growth_run": "-",
    "cycle_tolerance": "-", "min_cycles": "-", "min_compare_time": "s",
    "max_multiplicity": "-", "envelope_tolerance": "-", "envelope_blocks": "-",
    "stick_level": "-", "initial_duration": "s", "max_duration": "s",
}
#: the same for the ``--ripple-threshold`` search's JSON
# (``feeddrive.analysis.forced.threshold_critical_speed``)
RIPPLE_UNITS = {"threshold": "-", "ripple_ratio": "-", "min_ratio": "-", "mean_ratio": "-"}


def protocol_text(start: str, speed_range: tuple[float, float], coarse_step: float,
                  rule: VerdictRule) -> str:
    """The protocol a search ran, in words with its settings
    (:func:`feeddrive.analysis.protocol.describe`, which writes the default one for the
    report): the speed range, the coarse step and the trial lengths given.

    Parameters
    ----------
    start : str
        ``"rest"`` or ``"running"`` (the step-down).
    speed_range : tuple of float
        Lowest and highest speed tested [m/s].
    coarse_step : float
        The scan step from rest [m/s] (the step-down's is the protocol's).
    rule : VerdictRule
        The trial lengths [s].

    Returns
    -------
    str
        One sentence.
    """
    return protocol.describe(start, speed_range=speed_range,
                             coarse_step=coarse_step if start == "rest" else None,
                             durations=(rule.initial_duration, rule.max_duration),
                             holds=start != "rest")


@app.command("creep")
@user_errors
@accuracy_options
def creep_command(
    drive: str = typer.Option("cdfs", "--drive", metavar=ALL_DRIVES, help=ALL_DRIVES_TEXT),
    position: float = typer.Option(400.0, "--position", help="Table position [mm]."),
    nut_speed: float = typer.Option(0.0, "--nut-speed", help="Hollow-motor speed [mm/s] (DDFS)."),
    method: str = typer.Option("both", "--method", help="bisect (from rest), stepdown (the "
                               "paper's protocol on a running table) or both"),
    low: float = typer.Option(_LOW, "--low", help="Lowest speed tested [mm/s] (as "
                              "`reproduce`)."),
    high: float = typer.Option(_HIGH, "--high", help="Highest speed tested, where the "
                               "step-down starts [mm/s] (as `reproduce`)."),
    initial_duration: float = typer.Option(protocol.TRIAL_DURATION, "--initial-duration",
                                           help="First trial length [s], at least 2 (the "
                                           "rule's settle time); doubled until the verdict "
                                           "is decided."),
    max_duration: float = typer.Option(protocol.TRIAL_MAX_DURATION, "--max-duration",
                                       help="Longest trial [s], at least the first "
                                       "(--initial-duration); still undecided then: "
                                       "'undecided'."),
    ripple_threshold: float | None = typer.Option(
        None, "--ripple-threshold", help="Define the critical speed by a ripple threshold "
        "instead, for a forced oscillation (motor torque ripple, e.g. --preset "
        "wang2021-ripple): the lowest command above which the steady peak-to-peak table-speed "
        "ripple stays below this fraction of the command [fraction]; each speed runs from "
        "rest until its ripple is steady (not with --method, --initial-duration, "
        "--max-duration)."),
    integrator: str | None = typer.Option(
        None, "--integrator", metavar="|".join(CLI_METHODS),
        help="The trials' integrator (as simulate's --method; default: the parameter file's "
        "[solver] method, else modal)."),
    error_estimate: str = typer.Option(
        "shadow", "--error-estimate", metavar="shadow|embedded|none",
        help=ESTIMATE_HELP),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON (speeds in mm/s; `units` "
                                 "names the unit of each field whose name has none; "
                                 "`integration_error` states the estimate or why there is "
                                 "none)."),
    solver: Any = None,
) -> None:
    """Critical creeping speed [mm/s]: the upper edge of the highest creeping band (the lowest
    tested speed above every stick-slip or sustained oscillation), resolution 0.01 mm/s, with
    every creeping band found and its kind.  Each trial runs until decided (smooth, stick-slip,
    oscillation) or answers 'undecided'.  With --method both, the answers from rest and from a
    running table are shown.  Each search states the protocol it ran (speed range, steps,
    trial lengths); at the defaults it is the one `reproduce` uses, so both give one number.
    The search from rest states the table-speed integration error of the trials that decide
    it: their difference to the same trials run with every tolerance 10× tighter (7–9 % more
    CPU), an estimate, not a bound, written with the measured range of its ratio to the true
    error (docs/model.md; --error-estimate chooses it); where none is made (the step-down,
    --ripple-threshold, --error-estimate none, settings at double precision's reach) it says
    why.  On a terminal, the search's progress shows on
    stderr."""
    from ..engine.simulate import DriveSystem

    if method not in ("bisect", "stepdown", "both"):
        raise ValueError(f"--method = {method!r}: expected bisect, stepdown or both")
    if ripple_threshold is not None:
        _ripple_takes_no_trials(method, initial_duration, max_duration)
    rule = _units.trial_rule(max_duration, initial_duration)
    params = resolve_parameters(preset_name, params_file, drive)
    system = DriveSystem(params, drive=drive,
                         table_position=_units.position("--position", position, params, drive))
    v_n = _units.speed("--nut-speed", nut_speed)
    speed_range = _units.speed_range("--low", low, "--high", high, search=True)
    # the drive, and where its table is when that matters (not for a linear motor)
    where = drive.upper() + (f" at {position:g} mm" if system.topology().uses_table_position
                             else "")
    solver = _with_integrator(solver, integrator)
    context = {"parameter_set": params.name, "table_position_mm": position,
               "integrator": solver.describe()}
    from ..engine.options import using

    with using(solver):  # every trial runs with it
        if ripple_threshold is not None:
            _ripple(system, v_n, ripple_threshold, speed_range, context, as_json=as_json,
                    heading=f"{where}, v_n = {nut_speed:g} mm/s")
            return
        from ..analysis.critical import shadow_possible

        estimate = estimate_asked(error_estimate, shadow_possible())
        with search_progress(not as_json) as shown:
            results = _searches(system, v_n, method, speed_range, rule, estimate, shown)
    searches = [r.to_dict() for r in results]
    error = integration_error(searches, no_estimate_reason(method, estimate, error_estimate))
    if as_json:
        print_json(_json(searches, error, context, drive=drive, nut_speed=nut_speed,
                         rule=rule))
        return
    _print_text(results, searches, error, where, rule, solver.describe())


def _with_integrator(solver: Any, integrator: str | None) -> Any:
    """The command's solver options with ``--integrator`` over them (as ``simulate``'s
    ``--method``; ``creep --method`` is the search's): ``creep`` could choose its trials'
    integrator only through a ``[solver]`` file (an outside check, 2026-12-06)."""
    from ..engine.options import layered
    from ..parameters import ParameterError

    if integrator is None:
        return solver
    if integrator not in CLI_METHODS:
        raise ParameterError("--integrator", integrator,
                             f"expected one of {', '.join(CLI_METHODS)}")
    return layered([("command line", {"method": (integrator, "--integrator")})], base=solver)


def _ripple_takes_no_trials(method: str, initial_duration: float,
                            max_duration: float) -> None:
    """Refuse the trial settings of the creep searches with ``--ripple-threshold``, whose
    search runs every speed for its own fixed time (``feeddrive.analysis.forced.TRIAL``,
    until the forced ripple is steady) from rest: they were taken and ignored (an outside
    check, 2026-12-06)."""
    from ..analysis.forced import TRIAL
    from ..parameters import ParameterError

    for flag, value, default in (("--method", method, "both"),
                                 ("--initial-duration", initial_duration,
                                  protocol.TRIAL_DURATION),
                                 ("--max-duration", max_duration, protocol.TRIAL_MAX_DURATION)):
        if value != default:
            raise ParameterError(flag, value, "not used with --ripple-threshold (its search "
                                              f"runs each speed {TRIAL:g} s from rest, until "
                                              "the forced ripple is steady)")


def _coarse_step(speed_range: tuple[float, float]) -> float:
    """The scan step from rest [m/s]: the protocol's, or half the range if that is less."""
    lo, hi = speed_range
    return min(protocol.COARSE_STEP, (hi - lo) / 2)


def _searches(system: DriveSystem, v_n: float, method: str,
              speed_range: tuple[float, float], rule: VerdictRule, estimate: str | bool,
              shown: SearchProgress | None) -> list[CriticalSpeed]:
    """The searches ``--method`` asks for, from rest first (the protocol's settings)."""
    from ..analysis.critical import (
        check_stepdown,
        critical_speed_from_rest,
        critical_speed_stepdown,
    )

    lo, hi = speed_range
    stepdown: dict[str, Any] = {
        "nut_speed": v_n, "start_speed": hi, "lowest_speed": lo, "step": protocol.RESOLUTION,
        "coarse_step": protocol.STAIRCASE_COARSE_STEP, "rule": rule}
    if method in ("stepdown", "both"):  # refused before the search from rest runs
        check_stepdown(system, options=None, **stepdown)
    results = []
    if method in ("bisect", "both"):
        results.append(critical_speed_from_rest(
            system, nut_speed=v_n, speed_range=(lo, hi), coarse_step=_coarse_step(speed_range),
            resolution=protocol.RESOLUTION, rule=rule, error_estimate=estimate,
            **stage(shown, "search from rest")))
    if method in ("stepdown", "both"):
        if shown is not None:  # the step-down reports no trials as it goes
            shown.stage("step-down on a running table")
        try:
            results.append(critical_speed_stepdown(system, **stepdown))
        except KeyboardInterrupt:
            if results:  # the search from rest had finished: its answer said, not dropped
                # (an outside check, 2026-12-07)
                r = results[0]
                err_console.print(f"interrupted in the step-down; the search from rest had "
                                  f"finished: critical creeping speed {r.display()} "
                                  f"({len(r.trials)} trials)", markup=False, highlight=False,
                                  soft_wrap=True)
            raise
    return results


def _json(searches: list[dict[str, Any]], error: dict[str, Any], context: dict[str, Any], *,
          drive: str, nut_speed: float, rule: VerdictRule) -> dict[str, Any]:
    """``creep --json`` of the searches, the first one's answer at the top."""
    first = searches[0]
    out = {"drive": drive, "table_position_mm": context["table_position_mm"],
           "nut_speed_mm_s": nut_speed, "integration_error": error,
           "parameter_set": context["parameter_set"],
           "critical_speed_mm_s": first["critical_speed_mm_s"], "status": first["status"],
           "kind": first["kind"], "bands": first["bands"], "verdict_rule": rule.to_dict(),
           "integrator": context["integrator"], "units": UNITS, "searches": searches}
    if len(searches) == 2:
        a, b = (s["critical_speed_mm_s"] for s in searches)
        out["start_condition_matters"] = a != b
    return out


def _print_text(results: list[CriticalSpeed], searches: list[dict[str, Any]],
                error: dict[str, Any], where: str, rule: VerdictRule, integrator: str) -> None:
    """The searches as ``creep`` prints them: each with its protocol, then the rule."""
    from ..analysis.critical import format_bands, format_integration_error

    for r, d in zip(results, searches, strict=True):
        console.print(f"{where}, start from {r.start}: critical "
                      f"creeping speed {r.display()}{format_integration_error(d)} "
                      f"({len(r.trials)} trials); creeping bands [mm/s]: {format_bands(d)}",
                      markup=False, highlight=False)
        text = protocol_text(r.start, r.speed_range, _coarse_step(r.speed_range), rule)
        console.print(f"  protocol {text}", markup=False, highlight=False)
    console.print(f"Verdict rule: {rule.describe()}", markup=False, highlight=False)
    console.print(f"Integrator: {integrator}", markup=False, highlight=False)
    if not error["estimated"]:
        console.print(error["text"], markup=False, highlight=False)


def _ripple(system: DriveSystem, v_n: float, threshold: float,
            speed_range: tuple[float, float], context: dict[str, Any], *, as_json: bool,
            heading: str) -> None:
    """``creep --ripple-threshold``: the critical speed by the forced ripple's threshold
    (:func:`feeddrive.analysis.forced.threshold_critical_speed`); no integration-error
    estimate, and it says so."""
    from ..analysis.forced import threshold_critical_speed
    from ..parameters import ParameterError

    if not 0 < threshold <= 10:
        raise ParameterError("--ripple-threshold", threshold,
                             "expected a fraction of the command in (0, 10]")
    with search_progress(not as_json) as shown:
        if shown is not None:  # the ripple search reports no runs as it goes
            shown.stage("ripple-threshold search")
        res = threshold_critical_speed(system, v_n, threshold=threshold, speed_range=speed_range,
                                       coarse_step=_coarse_step(speed_range),
                                       resolution=protocol.RESOLUTION)
    error = not_estimated(RIPPLE_REASON)
    res.update(parameter_set=context["parameter_set"],
               table_position_mm=context["table_position_mm"],
               integrator=context["integrator"], integration_error=error, units=RIPPLE_UNITS)
    if as_json:
        print_json(res)
        return
    shown_speed = (f"{res['critical_speed_mm_s']:.2f} mm/s ({res['kind']} below it)"
                   if res["critical_speed_mm_s"] is not None else res["status"])
    for line in (f"{heading}: critical speed {shown_speed}", f"Rule: {res['rule']}",
                 f"Integrator: {context['integrator']}", error["text"]):
        console.print(line, markup=False, highlight=False)
