"""The report's answer box (issue 41 item 1): the critical speeds the study found, fitted or
predicted, and the mechanism behind them in one sentence — every number from this run, so a
changed parameter set (``--preset wang2021-literal``, a changed gain) gets its own answer."""

from __future__ import annotations

from typing import Any

from ..analysis.critical import format_critical_speed
from ..parameters import DriveParameters
from .beyond_section import _find, _v
from .linear_section import CdfsLinear
from .paper import PAPER

MID = 0.4  # [m] mid-screw, Wang2021 Table 3
#: the parameter set whose one unstated gain was fitted to the CDFS's 1.56 mm/s
FITTED_SET = "wang2021"
FITTED_PATH = "controller.velocity_integral_gain"
#: what "reproduced" allows around the paper's DDFS 0.50 mm/s (the targets' range)
DDFS_TARGET = (0.40, 0.60)


def _speed(search: dict[str, Any]) -> str:
    return f"{format_critical_speed(search)} mm/s"


def answer_markdown(params: DriveParameters, results: dict[str, Any],
                    cdfs: CdfsLinear) -> str:
    """The answer box: three bold-led lines in Markdown.

    Parameters
    ----------
    params : DriveParameters
        The parameter set of the run.
    results : dict
        Every study's stored results.
    cdfs : CdfsLinear
        The CDFS linearised (:func:`feeddrive.reproduce.linear_section.cdfs_linear`).

    Returns
    -------
    str
        The box's Markdown: the CDFS, the DDFS and the mechanism.

    References
    ----------
    .. [1] Wang2021 Sect. 5.2 (1.56 mm/s CDFS, 0.5 mm/s DDFS), Sect. 6 (step-down protocol).
    """
    crit = results["critical"]
    rest, running = crit[f"crit-cdfs-{MID}"], crit["crit-cdfs-running"]
    ddfs = crit["crit-ddfs-fig8"]
    paper_cdfs = 1e3 * PAPER["cdfs_critical_sim"]
    paper_ddfs = 1e3 * PAPER["ddfs_critical_sim"]
    how = (f"*fitted* (one gain, `{FITTED_PATH}`)" if params.name == FITTED_SET
           else "*predicted*")
    cdfs_line = (f"**CDFS (mid-screw): {_speed(rest)}** from rest, {how}, and "
                 f"**{_speed(running)}** *predicted* by the paper's step-down protocol; "
                 f"Wang2021: {paper_cdfs:.2f} mm/s.")
    v = ddfs["critical_speed_mm_s"]
    lo, hi = DDFS_TARGET
    reproduced = v is not None and lo <= v <= hi
    forced = results.get("forced_study") or []
    ripple = _v(_find(forced, "ddfs", PAPER["ddfs_sim_nut_speed"] * 1e3, 0.5))
    ddfs_line = (f"**DDFS (v_n = {1e3 * PAPER['ddfs_sim_nut_speed']:g} mm/s): {_speed(ddfs)}** "
                 + (f"*predicted*, as Wang2021's {paper_ddfs:.2f} mm/s." if reproduced else
                    f"— the published model does not reproduce Wang2021's {paper_ddfs:.2f} mm/s")
                 + ("" if reproduced or ripple is None else
                    f"; {ripple:.2f} mm/s only with motor torque ripple added "
                    "(`wang2021-ripple`, 50 % ripple threshold)")
                 + ("" if reproduced else "."))
    return "\n\n".join([cdfs_line, ddfs_line, "**Mechanism:** " + mechanism_sentence(cdfs)])


def mechanism_sentence(cdfs: CdfsLinear) -> str:
    """The mechanism in one sentence, from the linearised CDFS: which mode the Stribeck slope
    destabilises and where steady sliding is linearly unstable.

    Parameters
    ----------
    cdfs : CdfsLinear
        The CDFS's loops, frictionless, at 1.5 mm/s, and its unstable band of steady sliding.

    Returns
    -------
    str
        E.g. "the Stribeck slope of the friction destabilises the 5.47-Hz, ζ 0.034 screw
        velocity loop mode (crossover 5.44 Hz), the least damped without friction: steady
        sliding is linearly unstable at 0.17–1.40 mm/s."
    """
    loops, band = cdfs.loops, cdfs.band
    where = band.text(2, "mm/s")
    if loops is None:
        return ((f"steady sliding of the CDFS is linearly unstable at {where}; " if where
                 else "steady sliding of the CDFS is linearly stable at every speed scanned; ")
                + f"its loops have no steady state without friction at 1.5 mm/s ({cdfs.note}).")
    d = loops.dominant()
    # the loop whose gain crossover lies nearest the mode names it (the screw velocity loop,
    # 5.44 Hz, for the 5.47-Hz mode of wang2021)
    crossed = [(lp.name, lp.crossover_hz) for lp in loops.loops if lp.crossover_hz is not None]
    near = min(crossed, key=lambda c: abs(c[1] - d.frequency_hz), default=None)
    owner = (f"{near[0]} mode (crossover {near[1]:.2f} Hz)" if near is not None
             and abs(near[1] / d.frequency_hz - 1.0) < 0.25 else "servo mode")
    mode = (f"the {d.frequency_hz:.2f}-Hz, ζ {d.damping_ratio:.3f} {owner}, the least damped "
            "without friction")
    if not band.intervals:
        return (f"steady sliding of the CDFS is linearly stable at every speed scanned; its "
                f"least-damped mode is {mode[4:]}.")
    return (f"the Stribeck slope of the friction destabilises {mode}: steady sliding is "
            f"linearly unstable at {where}.")
