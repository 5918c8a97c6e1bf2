"""The text `loops` prints for one drive, shared by `loops` and `loops --machine`."""

from __future__ import annotations

from typing import Any

from ._common import console


def print_loops(title: str, set_name: str, table_speed: float, with_friction: bool,
                data: dict[str, Any]) -> None:
    """Print one drive's loop analysis (``LoopAnalysis.as_dict``) as `loops` does.

    Parameters
    ----------
    title : str
        The drive (or axis) shown first.
    set_name : str
        Its parameter set's name.
    table_speed : float
        The operating point [mm/s].
    with_friction : bool
        Whether it was linearised with friction.
    data : dict
        The analysis.
    """
    from ..analysis.linear import margin_text

    d = data["least_damped_mode"]
    console.print(f"[bold]{title}[/] ({set_name}), {table_speed:g} mm/s, "
                  f"{data['friction']}"
                  f"{'' if with_friction else ' (--with-friction: the explorer’s margins)'}"
                  f": least-damped mode {d['frequency_hz']:.3f} Hz, "
                  f"ζ = {d['damping_ratio']:.4f}")
    for note in data["notes"]:
        console.print(f"  {note}", markup=False)
    rigid = sum(p["kind"] == "rigid-body" for p in data["poles"])
    if rigid:
        console.print(f"  {rigid} rigid-body pole{'s' if rigid > 1 else ''} (a free motion no "
                      "loop holds; no damping ratio)")
    # the poles the help promises, each pair once, least damped first
    poles = sorted(data["poles"], key=lambda p: (p["kind"] == "rigid-body",
                                                 p.get("damping_ratio", 0.0)))
    console.print(f"  poles ({len(poles)}, each complex pair once, least damped first):",
                  markup=False)
    for p in poles:
        if p["kind"] == "rigid-body":
            console.print(f"    rigid-body   real {p['real_1_per_s']:.3g} 1/s", markup=False)
        else:
            console.print(f"    {p['kind']:12s} {p['frequency_hz']:10.4g} Hz  ζ = "
                          f"{p['damping_ratio']:.4g}  (real {p['real_1_per_s']:.4g} 1/s)",
                          markup=False)
    for lp in data["loops"]:
        # ∞ for a gain margin without phase crossover, — for a value the loop has not
        shown = {name: margin_text(name, lp[name], ".2f", unit) for name, unit in
                 (("crossover_hz", "Hz"), ("phase_margin_deg", "°"), ("gain_margin_db", "dB"),
                  ("closed_loop_bandwidth_hz", "Hz"))}
        console.print(f"  {lp['loop']:22s} crossover {shown['crossover_hz']:>10s}  "
                      f"phase margin {shown['phase_margin_deg']:>9s}  gain margin "
                      f"{shown['gain_margin_db']:>9s}  bandwidth "
                      f"{shown['closed_loop_bandwidth_hz']}")
