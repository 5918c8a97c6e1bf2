"""Is the second motor worth it?  CDFS, CDFS + friction compensation (exact and mismatched),
and the DDFS, side by side (issue 14): critical speed from rest, the linear creep band, and
tracking at a constant speed inside the CDFS's creep range.

Compensation laws: :class:`feeddrive.model.loops.Compensation` (static feed-forward,
Armstrong-Hélouvry et al. 1994; LuGre observer, Canudas de Wit et al. 1995).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..engine.simulate import DriveSystem, simulate
from ..model.loops import Compensation
from ..model.mechanisms import Mechanism, drive_names, mechanism
from ..model.reference import ConstantSpeed
from ..parameters import DriveParameters
from ..parameters.validation import check_flag, check_speed
from .cycle_verdict import VerdictRule


@dataclass(frozen=True)
class Case:
    """One case of the friction-compensation study.

    Parameters
    ----------
    label : str
        The case's name in the report.
    drive : str
        The drive (``"cdfs"``, or the alternative ``"ddfs"``).
    compensation : Compensation
        The compensator and its model mismatch.
    nut_speed : float, default 0.0
        Nut speed (DDFS) [m/s].
    """
    label: str
    drive: str
    compensation: Compensation
    nut_speed: float = 0.0  # [m/s]


def default_cases(mismatch: float = 0.2, nut_speed: float = 16e-3, *, drive: str = "cdfs",
                  alternative: str | None = "ddfs") -> list[Case]:
    """None, exact, ±``mismatch`` on F_c, F_s and v_s, for both compensators; and the
    alternative with its nut driven (the DDFS).

    Parameters
    ----------
    mismatch : float, default 0.2
        Relative error of the compensator's F_c, F_s and v_s [-].
    nut_speed : float, default 0.016
        Nut speed of the alternative's case [m/s].
    drive : str, default "cdfs"
        The drive compensated (one of :func:`study_drives`).
    alternative : str or None, default "ddfs"
        The drive of the same topology with its nut driven (:func:`study_drives`); None: no
        such case.

    Returns
    -------
    list of Case
        The cases.

    Raises
    ------
    ParameterError
        For a nut speed that is not a finite number within ``units.LARGEST_SPEED``
        (:func:`~feeddrive.parameters.validation.check_speed`).
    """
    # a NaN nut speed made a case that failed only when run, a str one "Unknown format
    # code 'g'" (session 27)
    nut_speed = check_speed("nut_speed", nut_speed, sign="any")
    up, down = 1.0 + mismatch, 1.0 - mismatch
    pct = f"{100 * mismatch:g} %"
    name = drive.upper()
    cases = [Case(f"{name}, no compensation", drive, Compensation())]
    for mode in ("feedforward", "observer"):
        cases.append(Case(f"{name} + {mode}, exact model", drive, Compensation(mode=mode)))
        cases.append(Case(f"{name} + {mode}, model +{pct}", drive, Compensation(
            mode=mode, coulomb_scale=up, static_scale=up, stribeck_velocity_scale=up)))
        cases.append(Case(f"{name} + {mode}, model −{pct}", drive, Compensation(
            mode=mode, coulomb_scale=down, static_scale=down, stribeck_velocity_scale=down)))
    if alternative is not None:
        cases.append(Case(f"{alternative.upper()}, v_n = {1e3 * nut_speed:g} mm/s",
                          alternative, Compensation(), nut_speed))
    return cases


def study_drives(params: DriveParameters) -> dict[str, str | None]:
    """The drives the study compensates, each with its alternative, as the topologies declare
    them: a drive whose topology has a friction compensator (``Mechanism.compensation``) and
    which drives no nut, and the drive of the same topology that drives its nut.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    dict of str to (str or None)
        Drive → its alternative (None: its topology has no drive with a driven nut).
    """
    out: dict[str, str | None] = {}
    for name in drive_names():
        topology = mechanism(name)
        if topology.compensation is Mechanism.compensation:
            continue  # no compensator declared
        if topology(params, name, 0.4, "locked").follows("nut"):
            continue
        out[name] = next((d for d in topology.drives
                          if topology(params, d, 0.4, "locked").follows("nut")), None)
    return out


def case_parameters(params: DriveParameters, case: Case) -> DriveParameters:
    """The parameter set of one case: ``params`` with the case's compensator.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    case : Case
        The case.

    Returns
    -------
    DriveParameters
        ``params`` with ``controller.compensation`` set to the case's.
    """
    return params.replace_path("controller.compensation", case.compensation)


def evaluate(params: DriveParameters, case: Case, *, table_position: float = 0.4,
             tracking_speed: float = 1.0e-3, duration: float = 12.0,
             search: bool = True, rule: VerdictRule | None = None,
             found: dict[str, Any] | None = None) -> dict[str, Any]:
    """One row of the study (SI inside, mm and µm in the keys' units).  The tracking run
    lasts ``duration`` [s]; its verdict and every critical-speed trial follow ``rule``.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    case : Case
        The case.
    table_position : float, default 0.4
        Table position [m].
    tracking_speed : float, default 0.001
        Speed of the tracking run [m/s].
    duration : float, default 12.0
        Length of the tracking run [s].
    search : bool, default True
        Also search the critical speed.
    rule : VerdictRule, optional
        The creep-verdict rule.
    found : dict, optional
        The case's critical-speed search already made elsewhere (``CriticalSpeed.to_dict``
        of :func:`~feeddrive.analysis.critical.critical_speed_from_rest` on this case's system
        and nut speed with the protocol's grid and ``rule``): used instead of searching again.

    Returns
    -------
    dict
        The case, its critical speed [mm/s], linear creep bands [mm/s], verdict at the
        tracking speed and rms following error [µm].
    """
    search = check_flag("search", search)
    system = DriveSystem(case_parameters(params, case), case.drive, table_position)
    # imported here: `simulate` imports this module for observer_gain_warning alone
    from .critical import creep_trial, critical_speed_from_rest, format_critical_speed
    from .linear import stability_band

    band = stability_band(system, case.nut_speed, points=25)
    trial = creep_trial(system, tracking_speed, nut_speed=case.nut_speed, rule=rule)
    run = simulate(system, ConstantSpeed(tracking_speed, case.nut_speed), duration)
    m = run.creep_metrics()
    sel = (run.time >= m.window_start) & (run.time <= m.window_end)
    err = run["following_error"][sel]
    row: dict[str, Any] = {
        "case": case.label, "drive": case.drive, "compensation": case.compensation.mode,
        "linear_unstable_bands_mm_s": [[1e3 * lo, 1e3 * hi] for lo, hi in band.intervals],
        "tracking_speed_mm_s": 1e3 * tracking_speed,
        "verdict_at_tracking_speed": trial.kind,
        "speed_ripple_ratio": m.ripple_ratio,
        "following_error_rms_um": 1e6 * float(np.sqrt(np.mean(err**2))),
        "following_error_peak_um": 1e6 * float(np.max(np.abs(err))),
    }
    if search:
        if found is None:
            found = critical_speed_from_rest(system, nut_speed=case.nut_speed,
                                             rule=rule).to_dict()
        row["critical_speed_mm_s"] = format_critical_speed(found)
    return row


class RowsInterrupted(KeyboardInterrupt):
    """Ctrl-C during a table of runs (:func:`compensation_study`,
    :func:`~feeddrive.analysis.compensation_compare.compare_compensations`): ``rows`` holds
    the rows finished before it, which the caller keeps (prints, writes).

    Parameters
    ----------
    rows : list of dict
        The finished rows.
    total : int
        How many rows were asked for.
    """

    def __init__(self, rows: list[dict[str, Any]], total: int) -> None:
        super().__init__(f"stopped after {len(rows)} of {total} rows")
        self.rows, self.total = rows, total


def compensation_study(params: DriveParameters, cases: list[Case] | None = None, *,
                       search: bool = True,
                       progress: Callable[[int, int], None] | None = None,
                       found: dict[int, dict[str, Any]] | None = None,
                       **kwargs: Any) -> list[dict[str, Any]]:
    """Evaluate every case of the friction-compensation study (:func:`evaluate`).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    cases : list of Case, optional
        The cases; :func:`default_cases` by default.
    search : bool, default True
        Also search each case's critical speed.
    progress : callable, optional
        ``progress(done, total)`` after each case.
    found : dict of int to dict, optional
        Critical-speed searches already made, by case index (see :func:`evaluate`).
    **kwargs
        Passed to :func:`evaluate` (table position, tracking speed, duration, rule).

    Returns
    -------
    list of dict
        One row per case.

    Raises
    ------
    RowsInterrupted
        On Ctrl-C, with the rows finished before it.
    """
    search = check_flag("search", search)  # refused before the first case is run
    cases = cases if cases is not None else default_cases()
    rows: list[dict[str, Any]] = []
    try:
        for k, case in enumerate(cases):
            rows.append(evaluate(params, case, search=search, found=(found or {}).get(k),
                                 **kwargs))
            if progress:
                progress(k + 1, len(cases))
    except KeyboardInterrupt:  # the finished rows are kept (they were dropped)
        raise RowsInterrupted(rows, len(cases)) from None
    return rows


__all__ = ["Case", "RowsInterrupted", "case_parameters", "compensation_study", "default_cases",
           "evaluate", "study_drives"]


def observer_gain_warning(system: DriveSystem, table_speed: float, nut_speed: float = 0.0
                          ) -> str | None:
    """A warning when the observer's correction gain k (``observer_gain``) makes the closed
    loop, linearised at steady sliding at ``table_speed`` [m/s], unstable where it is stable
    with k = 0; None otherwise (no observer, k = 0, or unstable without k too: the
    friction's own creep band).  At k = 100 1/s the observer destabilised the CDFS at
    0.5 mm/s (speed error 7.35× the command, issue 24 item 9); docs/linear.md gives the usable
    range of k.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    table_speed : float
        Steady table speed [m/s].
    nut_speed : float, default 0.0
        Steady nut speed [m/s].

    Returns
    -------
    str or None
        The warning, or None.
    """
    from dataclasses import replace

    from .linear import rightmost_pole

    comp = system.parameters.controller.compensation
    if comp.mode != "observer" or comp.observer_gain == 0.0 or table_speed == 0.0:
        return None
    growth, freq = rightmost_pole(system, table_speed, nut_speed)
    if growth <= 0.0:
        return None
    plain = DriveSystem(system.parameters.replace_path(
        "controller.compensation", replace(comp, observer_gain=0.0)), system.drive,
        system.table_position)
    if rightmost_pole(plain, table_speed, nut_speed)[0] > 0.0:
        return None
    return (f"controller.compensation.observer_gain = {comp.observer_gain:g} 1/s makes the "
            f"loop linearised at {1e3 * table_speed:g} mm/s unstable (a {freq:.3g}-Hz mode "
            f"growing at {growth:.3g} 1/s; with k = 0 it is stable): lower k "
            "(docs/linear.md gives the usable range)")
