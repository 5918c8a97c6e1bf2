"""The paper's studies (Wang2021 Sects. 5–6), each a pure function of a parameter set.

Every function returns plain data (dicts of floats, SI units) so the results can be cached as
JSON, tabulated and plotted; the traces needed for figures are returned as arrays.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis import protocol
from ..analysis.critical import (
    CreepTrial,
    critical_speed_from_rest,
    critical_speed_stepdown,
    decide,
    shadow_possible,
)
from ..analysis.cycle_verdict import VerdictRule
from ..analysis.tracking import reversal_overshoot
from ..engine.result import Result
from ..engine.simulate import DriveSystem, Simulation, simulate
from ..model.mechanisms.ball_screw_stiffness import stiffness_chain
from ..model.reference import ConstantSpeed, SineSpeed
from ..parameters import DriveParameters
from ..units import MM_PER_S
from .paper import PAPER

MM_S = MM_PER_S
MID = 0.4  # [m] mid-screw, Wang2021 Table 3 measurement point 3



# CSV tables: 10 significant digits, so 1e-6 × 220.9e6 is written 220.9 and not
# 220.89999999999998 (issue 12 item 13); as feeddrive.io.results writes signals
CSV_FLOAT = "%.10g"


def _csv_cell(value: Any) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return CSV_FLOAT % value if isinstance(value, float) else str(value)


def write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    """A table of rows as CSV (the standard library's writer: the report's tables need no
    pandas, whose import cost the parent of ``reproduce`` ≈ 0.2 CPU s), floats as
    :data:`CSV_FLOAT`, missing and NaN cells empty.

    Parameters
    ----------
    rows : list of dict
        The rows; the header is every key in order of first appearance.
    path : Path
        The CSV file.
    """
    from ..io.outputs import atomic_path

    header = list(dict.fromkeys(k for row in rows for k in row))
    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        out = csv.writer(fh, lineterminator=os.linesep)
        out.writerow(header)
        out.writerows([_csv_cell(row.get(k)) for k in header] for row in rows)


@dataclass(frozen=True)
class StudySettings:
    """Search settings shared by the studies (speeds in m/s, times in s).

    Every creep trial runs ``trial_initial_duration``, doubling up to ``trial_max_duration``
    until its verdict is decided (:class:`~feeddrive.analysis.cycle_verdict.VerdictRule`).

    Parameters
    ----------
    trial_initial_duration : float, default 12.0
        First duration of a creep trial [s].
    trial_max_duration : float, default 240.0
        Longest duration of a creep trial [s].
    speed_range : tuple of (float, float)
        Speeds the critical-speed search covers [m/s].
    coarse_step : float, default 2e-4
        Step of the coarse scan [m/s].
    resolution : float, default 1e-5
        Bisection resolution, the paper's 0.01 mm/s [m/s].
    fig7_multiples : tuple of float
        Hollow-motor speeds of Fig. 7 as multiples of the CDFS critical speed [-].
    sine_frequency : float, default 0.2
        Frequency of the Figs. 9–10 sine (not stated by the paper) [Hz].
    sine_periods : float, default 2.0
        Periods judged, after one lead-in period that is simulated but not judged
        (:attr:`sine_duration`) [-].
    sine_nut_amplitudes : tuple of float
        Hollow-motor amplitudes of Figs. 9–10 [m/s].

    References
    ----------
    .. [1] Wang2021 Sect. 6 (0.01 mm/s steps), Figs. 7, 9–10.
    """

    trial_initial_duration: float = protocol.TRIAL_DURATION
    trial_max_duration: float = protocol.TRIAL_MAX_DURATION
    speed_range: tuple[float, float] = protocol.SPEED_RANGE
    coarse_step: float = protocol.COARSE_STEP
    resolution: float = protocol.RESOLUTION
    fig7_multiples: tuple[float, ...] = (1.0, 2.0, 5.0, 10.0, 15.0, 20.0)
    sine_frequency: float = 0.2
    sine_periods: float = 2.0
    sine_nut_amplitudes: tuple[float, ...] = (0.0, 2e-3, 10e-3, 16e-3)

    @property
    def sine_duration(self) -> float:
        """Simulated time of each Figs. 9–10 run: the lead-in period and the judged ones [s]."""
        # (the expression of the runs stored so far: the same float, the same samples)
        return self.sine_periods / self.sine_frequency + 1.0 / self.sine_frequency

    def rule(self) -> VerdictRule:
        """The creep-verdict rule of these settings' trial durations.

        Returns
        -------
        VerdictRule
            Trials of ``trial_initial_duration`` doubled up to ``trial_max_duration``.
        """
        return VerdictRule(initial_duration=self.trial_initial_duration,
                           max_duration=self.trial_max_duration)


def critical_speed(params: DriveParameters, drive: str, position: float, nut_speed: float,
                   settings: StudySettings, *, error_estimate: bool = True) -> dict[str, Any]:
    """Critical speed from rest (scan + bisection) at one position.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        ``"cdfs"`` or ``"ddfs"``.
    position : float
        Table position [m].
    nut_speed : float
        Nut speed (DDFS) [m/s].
    settings : StudySettings
        The search settings.
    error_estimate : bool, default True
        Estimate the integration error of the trials that decide the critical speed by their
        shadow (each run again with every tolerance 10× tighter once the search is done;
        False: no ``speed_error_mm_s``; the verdicts, trials and critical speed are the same,
        the runs bit-identical).

    Returns
    -------
    dict
        The search's result in engineering units (``CriticalSpeed.to_dict``: the speed
        [mm/s], or the bound of an out-of-range search, its kind, bands and trials, each
        deciding trials' and the critical speed's table-speed integration error
        ``speed_error_mm_s`` with ``speed_error_method`` "shadow": their difference to a
        run 10× tighter — an estimate, not a bound,
        :data:`feeddrive.engine.error_estimate.SHADOW_RATIO` — 7–9 % more CPU).
    """
    res = critical_speed_from_rest(
        DriveSystem(params, drive=drive, table_position=position), nut_speed=nut_speed,
        speed_range=settings.speed_range, coarse_step=settings.coarse_step,
        resolution=settings.resolution, rule=settings.rule(),
        error_estimate=error_estimate and shadow_possible())  # none at double precision's reach
    return res.to_dict()


def critical_speed_running(params: DriveParameters, drive: str, position: float,
                           nut_speed: float, settings: StudySettings) -> dict[str, Any]:
    """Critical speed by the paper's step-down protocol on a running table (Sect. 6).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    drive : str
        ``"cdfs"`` or ``"ddfs"``.
    position : float
        Table position [m].
    nut_speed : float
        Nut speed (DDFS) [m/s].
    settings : StudySettings
        The search settings.

    Returns
    -------
    dict
        The search's result in engineering units (``CriticalSpeed.to_dict``: the speed
        [mm/s], its kind and the staircase's steps).

    References
    ----------
    .. [1] Wang2021 Sect. 6, Fig. 13.
    """
    res = critical_speed_stepdown(
        DriveSystem(params, drive=drive, table_position=position), nut_speed=nut_speed,
        start_speed=settings.speed_range[1], lowest_speed=settings.speed_range[0],
        step=settings.resolution, coarse_step=protocol.STAIRCASE_COARSE_STEP,
        rule=settings.rule())
    return res.to_dict()


def speed_trace(result: Any, stride: int = 5) -> dict[str, list[float]]:
    """A run's table speed and its command, decimated for the stored study and the figures.

    Parameters
    ----------
    result : Result
        The run.
    stride : int, default 5
        Keep every ``stride``-th sample.

    Returns
    -------
    dict of str to list of float
        ``time`` [s], ``table_speed`` and ``table_speed_reference`` [m/s].
    """
    return {"time": result.time[::stride].tolist(),
            "table_speed": result["table_speed"][::stride].tolist(),
            "table_speed_reference": result["table_speed_reference"][::stride].tolist()}


def decided_run(system: DriveSystem, profile: ConstantSpeed, rule: VerdictRule
                ) -> tuple[Result, CreepTrial]:
    """Simulate ``profile`` from rest until the creep verdict is decided; the last (deciding)
    run and its verdict.

    Parameters
    ----------
    system : DriveSystem
        The drive.
    profile : ConstantSpeed
        The commanded speed.
    rule : VerdictRule
        The verdict rule (trial durations).

    Returns
    -------
    result : Result
        The deciding run.
    trial : CreepTrial
        Its verdict.
    """
    runs: list[Result] = []
    sim = Simulation(system, profile)

    def run(duration: float) -> tuple[np.ndarray, np.ndarray]:
        runs.append(sim.run(duration))
        return runs[-1].time, runs[-1]["table_speed"]

    verdict, duration = decide(run, profile.table_speed, rule)
    return runs[-1], CreepTrial.from_verdict(profile.table_speed, verdict, duration)


def verdict_word(trial: CreepTrial) -> str:
    """"creeping" (stick-slip or sustained oscillation), "smooth" or "undecided".

    Parameters
    ----------
    trial : CreepTrial
        A creep trial's verdict.

    Returns
    -------
    str
        The word.
    """
    return "creeping" if trial.creeping else trial.kind


def fig6(params: DriveParameters, settings: StudySettings) -> dict[str, Any]:
    """CDFS at 1.55 and 1.56 mm/s, mid-screw (Wang2021 Fig. 6), each run until decided.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    settings : StudySettings
        The search settings.

    Returns
    -------
    dict
        Per commanded speed (``"1.55"``, ``"1.56"`` mm/s): verdict, kind, ripple ratio,
        stick fraction, stick-slip frequency [Hz], duration and settling time [s], and the
        decimated trace.

    References
    ----------
    .. [1] Wang2021 Fig. 6, Sect. 5.2.
    """
    out: dict[str, Any] = {}
    for v in (1.55e-3, 1.56e-3):
        r, m = decided_run(DriveSystem(params, "cdfs", MID), ConstantSpeed(v), settings.rule())
        out[f"{v / MM_S:.2f}"] = {"verdict": verdict_word(m), "kind": m.kind,
                                  "ripple_ratio": m.ripple_ratio,
                                  "stick_fraction": m.stick_fraction,
                                  "frequency": m.stick_slip_frequency,
                                  "duration": m.duration,
                                  "settling_time": settling_time(r.time, r["table_speed"], v),
                                  "trace": speed_trace(r)}
    return out


def settling_time(time: np.ndarray, speed: np.ndarray, command: float,
                  band: float = 0.05) -> float | None:
    """Time [s] after which |speed − command| stays within ``band``·|command|; None if never.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    speed : numpy.ndarray
        The speed trace [m/s].
    command : float
        The commanded speed [m/s].
    band : float, default 0.05
        The band, relative to the command [-].

    Returns
    -------
    float or None
        The settling time [s].
    """
    outside = np.abs(speed - command) > band * abs(command)
    if not outside.any():
        return 0.0
    last = int(np.nonzero(outside)[0][-1])
    if last >= len(time) - 1:
        return None
    return float(time[last + 1])


def overshoot(speed: np.ndarray, command: float) -> float:
    """Peak overshoot (max − command)/command, ≥ 0.

    Parameters
    ----------
    speed : numpy.ndarray
        The speed trace [m/s].
    command : float
        The commanded speed [m/s].

    Returns
    -------
    float
        The overshoot [-].
    """
    return max(0.0, float(np.max(speed) - command) / abs(command))


def fig7(params: DriveParameters, cdfs_critical: float, settings: StudySettings
         ) -> dict[str, Any]:
    """DDFS at 1.55 mm/s for hollow-motor speeds v_n = k × the CDFS critical speed (Fig. 7).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    cdfs_critical : float
        The CDFS critical speed the multiples refer to [m/s].
    settings : StudySettings
        The search settings.

    Returns
    -------
    dict
        The decimated traces by multiple and a row per multiple (nut speed [m/s], overshoot
        [-], settling time [s], verdict).

    References
    ----------
    .. [1] Wang2021 Fig. 7.
    """
    v = 1.55e-3
    rows = []
    traces = {}
    for k in (0.0, *settings.fig7_multiples):
        vn = k * cdfs_critical
        drive = "ddfs" if vn > 0 else "cdfs"
        r, m = decided_run(DriveSystem(params, drive, MID), ConstantSpeed(v, vn),
                           settings.rule())
        s = r["table_speed"]
        rows.append({"multiple": k, "nut_speed": vn, "overshoot": overshoot(s, v),
                     "settling_time": settling_time(r.time, s, v),
                     "verdict": verdict_word(m), "kind": m.kind,
                     "ripple_ratio": m.ripple_ratio})
        traces[f"{k:g}"] = speed_trace(r)
    return {"rows": rows, "traces": traces, "table_speed": v}


def figs9_10(params: DriveParameters, settings: StudySettings) -> dict[str, Any]:
    """Sinusoidal table speed, amplitudes 1.56 and 2 mm/s, several nut amplitudes.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.
    settings : StudySettings
        The search settings (frequency, periods, nut amplitudes).

    Returns
    -------
    dict
        ``rows`` (table, nut and screw amplitudes [m/s] and the reversal overshoot of each
        run), the decimated ``traces`` by ``"amplitude/nut amplitude"`` [mm/s] and the
        ``frequency`` [Hz].

    References
    ----------
    .. [1] Wang2021 Sect. 5.3, Figs. 9–10.
    """
    rows = []
    traces = {}
    duration = settings.sine_duration
    for amp in (1.56e-3, 2e-3):
        for vn in settings.sine_nut_amplitudes:
            drive = "ddfs" if vn > 0 else "cdfs"
            r = simulate(DriveSystem(params, drive, MID),
                         SineSpeed(amp, vn, settings.sine_frequency), duration)
            ro = reversal_overshoot(r.time, r["table_speed"], r["table_speed_reference"], amp,
                                    settings.sine_frequency)
            rows.append({"table_amplitude": amp, "nut_amplitude": vn,
                         "screw_amplitude": amp + vn, "reversal_overshoot": ro})
            traces[f"{amp / MM_S:g}/{vn / MM_S:g}"] = speed_trace(r)
    return {"rows": rows, "traces": traces, "frequency": settings.sine_frequency}


def stiffness_rows(params: DriveParameters) -> list[dict[str, float]]:
    """k_sa and K_eq at the positions of Wang2021 Table 3, beside the paper's k_sa row.

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    list of dict of str to float
        Per position: ``position`` [m], ``k_sa``, ``k_sa_paper`` and ``k_eq`` [N/m].

    References
    ----------
    .. [1] Wang2021 Table 3, Eqs. (2)–(5).
    """
    chain = stiffness_chain(params, np.array(PAPER["positions"]))
    return [{"position": float(a), "k_sa": float(k), "k_sa_paper": float(kp),
             "k_eq": float(ke)}
            for a, k, kp, ke in zip(chain.position, chain.screw_axial, PAPER["k_sa"],
                                    chain.equivalent, strict=True)]
