"""The report's sensitivity section (issue 22 item 5): the elasticity of the linear band's
upper edge to every numeric parameter of the set (cheap: linearisations only, no
simulation), its tornado chart, and the paper's claim "the greater the axial rigidity, the
lower the critical speed" read from the chart's stiffness rows.  The full chart of the
simulated critical speed is `feeddrive sensitivity --quantity critical-speed`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..parameters import DriveParameters

FIGURE = "sensitivity_linear_band.png"
#: the linear band's scan grid for the report (the bisection to 10⁻³ mm/s is unchanged)
LINEAR_POINTS = 20
#: the stiffness rows that make up the axial rigidity (Wang2021 Eqs. (2)–(5))
AXIAL = ("screw.nut_axial_stiffness", "screw.nut_bearing_axial_stiffness",
         "screw.support_bearing_axial_stiffness", "screw.youngs_modulus", "screw.diameter")


def compute(params: DriveParameters) -> dict[str, Any]:
    """The CDFS linear-band sensitivity of ``params`` at mid-screw, as a dict (stored).

    Parameters
    ----------
    params : DriveParameters
        The parameter set.

    Returns
    -------
    dict
        :meth:`~feeddrive.analysis.sensitivity.SensitivityResult.to_dict`: the linear band's upper
        edge at the base point [mm/s] and, per parameter, the band with it moved down and up
        and its elasticity.
    """
    from ..analysis.sensitivity import sensitivity

    return sensitivity(params, drive="cdfs", table_position=0.4, quantity="linear-band",
                       in_process=True, linear_points=LINEAR_POINTS).to_dict()


def figure(data: dict[str, Any] | None, out: Path) -> Path | None:
    """The tornado chart ``out/FIGURE`` from the stored dict.

    Parameters
    ----------
    data : dict or None
        The stored sensitivity study; None when it was not run.
    out : Path
        The report folder.

    Returns
    -------
    Path or None
        The chart written; None without data.
    """
    if not data:
        return None
    from ..analysis.sensitivity import Entry, SensitivityResult, plot_tornado

    entries = tuple(Entry(path=e["path"], value=e["value"], absolute=e["kind"] == "derivative",
                          step=e["step"], q_minus=1e-3 * _num(e["q_minus_mm_s"]),
                          q_plus=1e-3 * _num(e["q_plus_mm_s"]),
                          elasticity=_num(e["elasticity"]), bound=_num(e["bound"]),
                          resolved=e["resolved"], halved=_num(e["elasticity_half_step"]),
                          consistent=e["halving_consistent"], note=e["note"])
                    for e in data["entries"])
    result = SensitivityResult(parameter_set=data["parameter_set"], drive=data["drive"],
                               quantity=data["quantity"], base=data["base_mm_s"] * 1e-3,
                               resolution=data["resolution_mm_s"] * 1e-3, entries=entries,
                               skipped=data["skipped"], evaluations=data["evaluations"],
                               executor=data["executor"])
    return plot_tornado(result, out / FIGURE)


def _num(x: float | None) -> float:
    return math.nan if x is None else float(x)


def axial_rigidity_answer(data: dict[str, Any]) -> str:
    """The claim "the greater the axial rigidity, the lower the critical speed" against the
    chart's stiffness rows.

    The claim is Wang2021's conclusion on axial rigidity.

    Parameters
    ----------
    data : dict
        The stored sensitivity study (:func:`compute`).

    Returns
    -------
    str
        A sentence saying whether the chart bears the claim out.

    References
    ----------
    .. [1] Wang2021 Sect. 6, Sect. 7 (conclusion 3), Table 3.
    """
    rows = {e["path"]: e for e in data["entries"] if e["path"] in AXIAL}
    if not rows:
        return "No stiffness row was varied."
    resolved = {p: e for p, e in rows.items() if e["resolved"]}
    if resolved:
        signs = {p: e["elasticity"] for p, e in resolved.items()}
        lower = all(v < 0 for v in signs.values())
        listed = ", ".join(f"{p} E = {v:+.3g}" for p, v in signs.items())
        return (f"Stiffness rows: {listed}. " + (
            "Greater axial rigidity lowers the linear band's upper edge, as the paper says."
            if lower else "Greater axial rigidity does not lower the linear band's upper edge "
            "for every part of the chain: the linear analysis does not support the claim."))
    largest = max(abs(_num(e["q_plus_mm_s"]) - _num(e["q_minus_mm_s"])) for e in rows.values())
    bound = max(_num(e["bound"]) for e in rows.values())
    return (f"Stiffness rows ({', '.join(rows)}): ±40 % moves the linear band's upper edge by "
            f"at most {largest:.3g} mm/s (|E| < {bound:.2g}, below 10× the "
            f"{data['resolution_mm_s']:g}-mm/s resolution): the linear analysis neither supports "
            "nor refutes \"the greater the axial rigidity, the lower the critical speed\"; at "
            "this set the axial chain hardly enters the unstable servo mode.  The simulated "
            "critical speed's chart (`feeddrive sensitivity --quantity critical-speed "
            "--parameters 'screw.*stiffness'`) answers it at 0.01 mm/s.")


def sensitivity_rows(data: dict[str, Any] | None) -> tuple[str, list[dict[str, str]]]:
    """(section text, rows) from the stored dict (None: the study was not run).

    Parameters
    ----------
    data : dict or None
        The stored sensitivity study.

    Returns
    -------
    text : str
        The section's Markdown text.
    rows : list of dict of str to str
        One row per parameter: column heading → formatted cell [mm/s].
    """
    if not data:
        return "Not computed (run without --no-study).", []
    rows = []
    for e in data["entries"]:
        if e["resolved"]:
            value = f"{e['elasticity']:+.3g}"
            check = "halving agrees" if e["halving_consistent"] else "nonlinear"
        else:
            value = f"|E| < {e['bound']:.2g}" if e["bound"] is not None else "—"
            check = e["note"]
        step = e["step"]
        rows.append({"parameter": e["path"], "elasticity": value,
                     # a step the set refused has none (it printed "±nan %", issue 41 item 5)
                     "step": f"±{100 * step:g} %" if step is not None and math.isfinite(step)
                     else "—", "check": check})
    text = (f"Elasticity E of the CDFS linear band's upper edge (mid-screw, base "
            f"{data['base_mm_s']:.3f} mm/s) to each numeric parameter of the set: central "
            f"differences, the step doubled from ±10 % until its effect is at least 10× the "
            f"{data['resolution_mm_s']:g}-mm/s resolution, checked by halving "
            f"(`feeddrive sensitivity --quantity linear-band`; scan grid of {LINEAR_POINTS} "
            f"speeds; {data['evaluations']} linearised points; {len(data['skipped'])} "
            "parameters left out: no effect on the CDFS, structural switches, limits not in "
            "effect).  The simulated critical speed can sit on a knife edge where the linear "
            "edge moves little (table.mass 20 → 40 kg makes the CDFS creep at 1.56 mm/s in a "
            "creep trial from rest, while this edge moves by 0.01 mm/s); its chart is "
            "`feeddrive sensitivity --quantity critical-speed`.  " + axial_rigidity_answer(data))
    return text, rows
