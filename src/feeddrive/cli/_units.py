"""CLI values in mm, mm/s and s, checked and converted to SI at the edge.

Messages name the option and speak the CLI's units (issue 12 item 3); a value that looks as
if it was given in SI to an mm option draws a warning (item 2), as ``params check`` does for a
lead of 5.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

from .. import units
from ..analysis import protocol
from ..parameters import DriveParameters, ParameterError
from ._common import MM, MM_PER_S, err_console

if TYPE_CHECKING:
    from ..analysis.cycle_verdict import VerdictRule

# A table speed below 0.01 mm/s (the CLI's resolution for critical speeds) or a table
# position below 1 mm (the nut itself is longer) is what an SI value typed into an mm
# option looks like: 0.0005 meant 0.5 mm/s, 0.4 meant 400 mm.
SMALLEST_PLAUSIBLE_SPEED_MM_S = 0.01
SMALLEST_PLAUSIBLE_POSITION_MM = 1.0
# No table travels 100 m: the bound of a position no screw bounds (a linear motor's start;
# `--position 1e300` was simulated and exported: an outside check, 2026-12-07)
LARGEST_POSITION_MM = 1e5
# A speed above 100 m/s is no feed drive's (the measured-data limit, io.measured): refused,
# not exported or simulated (`export fmu --table-speed 1e300` was exported; issue 39 item 4)
LARGEST_SPEED_MM_S = units.LARGEST_SPEED / MM_PER_S


#: the lists of the warnings recording now (:func:`recorded_warnings`)
_RECORDS: list[list[str]] = []


def warn(text: str) -> None:
    """Print ``warning: text`` on stderr, and record it where a command records its warnings
    (:func:`recorded_warnings`)."""
    err_console.print(f"warning: {text}", markup=False, highlight=False, soft_wrap=True)
    for record in _RECORDS:
        record.append(text)


@contextmanager
def recorded_warnings() -> Iterator[list[str]]:
    """The warnings :func:`warn` prints meanwhile, in order: what a command's ``--json``
    reports beside what it printed.

    Yields
    ------
    list of str
        The warnings' texts (without ``warning:``), filled as they are printed.
    """
    record: list[str] = []
    _RECORDS.append(record)
    try:
        yield record
    finally:
        _RECORDS[:] = [r for r in _RECORDS if r is not record]  # this one, not an equal one


def _finite(option: str, value: float, unit: str) -> float:
    if not math.isfinite(value):
        raise ParameterError(option, value, f"expected a finite value [{unit}]")
    return value


def speed(option: str, value: float, *, positive: bool = False, nonzero: bool = False,
          warn_small: bool = True) -> float:
    """``value`` [mm/s] → [m/s]; a non-zero magnitude below 0.01 mm/s draws a warning (unless
    ``warn_small`` is False: a resolution is small by nature), one above
    :data:`LARGEST_SPEED_MM_S` is refused, and with ``positive`` (``nonzero``) one ≤ 0 (= 0)."""
    _finite(option, value, "mm/s")
    if positive and value <= 0.0:
        raise ParameterError(option, value, "expected a speed > 0 [mm/s]")
    if nonzero and value == 0.0:
        raise ParameterError(option, value, "expected a non-zero speed [mm/s]")
    if abs(value) > LARGEST_SPEED_MM_S:
        raise ParameterError(option, value, f"expected |speed| ≤ {LARGEST_SPEED_MM_S:g} [mm/s] "
                                            "(no feed drive is faster)")
    if warn_small and 0.0 < abs(value) < SMALLEST_PLAUSIBLE_SPEED_MM_S:
        warn(f"{option} = {value:g} mm/s looks like a value in m/s "
             f"({value * 1e3:g} mm/s?); the CLI takes mm/s")
    return value * MM_PER_S


def speed_range(low_option: str, low: float, high_option: str, high: float, *,
                search: bool = False) -> tuple[float, float]:
    """(low, high) [mm/s] → [m/s], both > 0 and low < high; for a critical-speed search
    (``search``) also at most the protocol's coarse steps apart (``protocol.
    MAX_SEARCH_STEPS`` of the finer of its two coarse steps, the scan's and the
    staircase's): the API refuses a wider range in m/s, which told a CLI user "the API
    takes m/s" of a --high in mm/s (session 25)."""
    lo = speed(low_option, low, positive=True)
    hi = speed(high_option, high, positive=True)
    if not low < high:
        raise ParameterError(high_option, high, f"expected > {low_option} = {low:g} [mm/s]")
    step = min(protocol.COARSE_STEP, protocol.STAIRCASE_COARSE_STEP) / MM_PER_S
    widest = protocol.MAX_SEARCH_STEPS * step
    if search and high - low > widest * (1 + 1e-12):
        raise ParameterError(high_option, high, f"expected ≤ {low_option} + {widest:g} = "
                             f"{low + widest:g} [mm/s] (at most {protocol.MAX_SEARCH_STEPS} "
                             f"coarse steps of {step:g} mm/s on a search's scan)")
    return lo, hi


def position(option: str, value: float, params: DriveParameters,
             drive: str = "cdfs") -> float:
    """Table position ``value`` [mm] → [m]; strictly within the travel the drive's mechanism
    declares (``Mechanism.travel_length``: a ball screw's supports; a linear motor has no
    screw to bound it), and only the default 400 mm on a drive whose model does not depend on
    the table's position (``Mechanism.uses_table_position``)."""
    from ..model.mechanisms import mechanism

    _finite(option, value, "mm")
    try:
        topology = mechanism(drive)
    except ParameterError:  # an unknown drive: refused where the drive is read
        topology = None
    if topology is not None and topology.travel_length:
        length: object = params
        for key in topology.travel_length.split("."):
            length = getattr(length, key)
        assert isinstance(length, (int, float))
        length_mm = float(length) / MM
        if not 0.0 < value < length_mm:
            raise ParameterError(option, value, f"expected 0 < position < {length_mm:g} [mm] "
                                                f"(strictly between {topology.travel_ends})")
    elif abs(value) > LARGEST_POSITION_MM:  # no screw bounds it: no table travels further
        raise ParameterError(option, value, f"expected |position| ≤ {LARGEST_POSITION_MM:g} "
                                            "[mm]")
    if topology is not None:
        # a position other than the option's default (400 mm, DriveSystem's 0.4 m) on a drive
        # whose model does not read it was dropped without a word (session 30)
        from ..model.mechanisms.base import check_table_position

        try:
            check_table_position(drive, value * MM)
        except ParameterError as err:
            raise ParameterError(option, value, err.message) from None
    if 0.0 < value < SMALLEST_PLAUSIBLE_POSITION_MM:
        warn(f"{option} = {value:g} mm looks like a value in metres "
             f"({value * 1e3:g} mm?); the CLI takes mm")
    return value * MM


def contour_limit(name: str) -> float:
    """A machine contour's largest value (:data:`feeddrive.machine.contour.LIMITS`) in the
    command line's unit: ``radius`` and ``distance`` [mm], ``feed`` [mm/min],
    ``acceleration`` [mm/s²], ``turns`` [-].

    Parameters
    ----------
    name : str
        A key of ``LIMITS``.

    Returns
    -------
    float
        The limit.
    """
    from ..machine.contour import LIMITS

    per = {"radius": 1e3, "distance": 1e3, "feed": 6e4, "acceleration": 1e3, "turns": 1.0}
    return LIMITS[name] * per[name]


def trial_rule(max_duration: float, initial_duration: float | None = None) -> VerdictRule:
    """The creep-verdict rule with the trial lengths of ``--max-duration`` and
    ``--initial-duration`` [s] (the protocol's first length when the command has no
    ``--initial-duration``): each finite and at least the rule's ``settle_time`` (a shorter
    trial can never be judged), the longest not below the first."""
    from ..analysis.cycle_verdict import VerdictRule

    shortest = VerdictRule().settle_time
    given = {"--max-duration": max_duration}
    if initial_duration is not None:
        given["--initial-duration"] = initial_duration
    for option, value in given.items():
        _finite(option, value, "s")
        if value < shortest:
            raise ParameterError(option, value, f"expected ≥ {shortest:g} [s] (the verdict "
                                                "rule's settle time: a shorter trial cannot be "
                                                "judged)")
    first = protocol.TRIAL_DURATION if initial_duration is None else initial_duration
    if max_duration < first:
        raise ParameterError("--max-duration", max_duration,
                             f"expected ≥ {first:g} [s], the first trial's length"
                             + (" (--initial-duration)" if initial_duration is not None
                                else ""))
    return VerdictRule(initial_duration=first, max_duration=max_duration)


def number(value: object, digits: int = 4) -> str:
    """A value as printed by the CLI: ``digits`` significant digits, "none" for None
    (a summary used to print 17 digits, issue 12 item 13)."""
    if value is None:
        return "none"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


def reversal_angle(degrees: float) -> float:
    """``--reversal-angle`` [°] as the circular test's ``reversal`` [rad], refused outside
    (0, 360)°.

    Parameters
    ----------
    degrees : float
        The option's value [°].

    Returns
    -------
    float
        The angle [rad].
    """
    if not (math.isfinite(degrees) and 0.0 < degrees < 360.0):
        raise ParameterError("--reversal-angle", degrees,
                             "expected an angle > 0 and < 360 [°]")
    return math.radians(degrees)
