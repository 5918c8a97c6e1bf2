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
        def fmt(v: float | None, unit: str) -> str:
            return "—" if v is None else f"{v:.2f} {unit}"
        console.print(f"  {lp['loop']:22s} crossover {fmt(lp['crossover_hz'], 'Hz'):>10s}  "
                      f"phase margin {fmt(lp['phase_margin_deg'], '°'):>9s}  gain margin "
                      f"{fmt(lp['gain_margin_db'], 'dB'):>9s}  bandwidth "
                      f"{fmt(lp['closed_loop_bandwidth_hz'], 'Hz')}")
