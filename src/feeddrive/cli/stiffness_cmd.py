"""`feeddrive stiffness`: the stiffness chain of Wang2021 Eqs. (2)–(5) at table positions."""

from __future__ import annotations

import math
from typing import Any

import typer
from rich.markup import escape
from rich.table import Table

from ..parameters import ParameterError
from ..parameters.validation import refuse_repeats
from . import _units
from ._common import MM, N_PER_UM, app, console, print_json, resolve_parameters, user_errors

_READINGS_SHOWN = 5


def parse_positions_mm(text: str, screw_length: float) -> list[float]:
    """Parse ``--positions``: comma-separated table positions in mm, converted to metres.

    A value that looks like metres (below the smallest plausible position) is warned about.

    Parameters
    ----------
    text : str
        E.g. ``"200,400,600"`` [mm].
    screw_length : float
        The screw's length l [m]; each position must be strictly inside (0, l).

    Returns
    -------
    list of float
        The positions [m].

    Raises
    ------
    ParameterError
        For a token that is not a number, lies outside the supports or repeats a position.
    """
    length_mm = screw_length / MM
    tokens = [token.strip() for token in text.split(",")]
    values = []
    for token in tokens:
        try:
            value = float(token)
        except ValueError:
            raise ParameterError(
                "--positions", token, "expected numbers [mm], e.g. 200,400"
            ) from None
        if not math.isfinite(value) or value <= 0.0 or value >= length_mm:
            raise ParameterError(
                "--positions", token,
                f"expected 0 < position < {length_mm:g} [mm] (strictly between the screw supports)",
            )
        values.append(value)
    # its row was printed twice (an earlier sweep, session 30)
    refuse_repeats("--positions", values, "each position once [mm], e.g. 200,400",
                   shown=tokens)
    for token, value in zip(tokens, values, strict=True):
        if value < _units.SMALLEST_PLAUSIBLE_POSITION_MM:
            _units.warn(f"--positions: {token} mm looks like a value in metres "
                        f"({value * 1e3:g} mm?); the CLI takes mm")
    return [value * MM for value in values]


def _table3_value(position: float) -> float | None:
    # imported here: the model package compiles numba kernels, `feeddrive --help` must not
    from ..model.mechanisms import ball_screw_stiffness as stiffness

    for a, k in zip(stiffness.TABLE3_POSITIONS, stiffness.TABLE3_SCREW_AXIAL_STIFFNESS,
                    strict=True):
        if math.isclose(a, position, rel_tol=0.0, abs_tol=1e-9):
            return k
    return None


@app.command("stiffness")
@user_errors
def stiffness_command(
    positions: str = typer.Option(
        "200,300,400,500,600", "--positions",
        help="Table positions a from the motor-side support [mm], comma-separated "
             "(default: the five measurement points of Wang2021 Table 3).",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
) -> None:
    """k_sa, K_a and K_eq at table positions, in N/µm: equations (2)–(5) of Wang2021.

    Also compares K_eq at mid-screw with the 2.16e7 N/m (21.6 N/µm) of Wang2021 Sect. 5.2 and
    lists the readings of Eqs. (2)–(5) that come closest to it.
    """
    import numpy as np

    from ..model.mechanisms import ball_screw_stiffness as stiffness

    params = resolve_parameters(preset_name, params_file)
    a = parse_positions_mm(positions, params.screw.length)
    with np.errstate(over="ignore", divide="ignore"):
        chain = stiffness.stiffness_chain(params, a)
    for i, x in enumerate(a):  # a nut (all but) at a support: k_sa overflows (an outside check,
        # 2026-12-07: 1e-300 mm printed inf, and --json failed on it)
        if not np.isfinite(chain.screw_axial[i]):
            raise ParameterError("--positions", x / MM, "k_sa is not finite there (the nut "
                                 "at a support); expected a position inside the screw [mm]")
    mid = stiffness.stiffness_chain(params, stiffness.mid_screw_position(params.screw))
    k_mid = float(mid.equivalent[()])
    k_mid_chain = float(mid.equivalent_chain[()])
    readings = stiffness.mid_screw_readings(params)[:_READINGS_SHOWN]
    paper = stiffness.PAPER_MID_SCREW_K_EQ

    rows = []
    for i, x in enumerate(a):
        t3 = _table3_value(x)
        rows.append({
            "position_mm": x / MM,
            "screw_axial_stiffness_N_per_um": float(chain.screw_axial[i]) / N_PER_UM,
            "table3_screw_axial_stiffness_N_per_um": None if t3 is None else t3 / N_PER_UM,
            "axial_stiffness_N_per_um": float(chain.axial[i]) / N_PER_UM,
            "equivalent_stiffness_chain_N_per_um": float(chain.equivalent_chain[i]) / N_PER_UM,
            "equivalent_stiffness_N_per_um": float(chain.equivalent[i]) / N_PER_UM,
        })
    override = params.stiffness.equivalent_stiffness > 0
    summary: dict[str, Any] = {
        "parameters": params.name,
        "screw_support": params.stiffness.screw_support,
        "support_bearing_count": params.stiffness.support_bearing_count,
        "include_torsion": params.stiffness.include_torsion,
        "equivalent_stiffness_override": override,
        "torsional_stiffness_N_m_per_rad": chain.torsional,
        "positions": rows,
        "mid_screw": {
            "position_mm": stiffness.mid_screw_position(params.screw) / MM,
            "equivalent_stiffness_N_per_um": k_mid / N_PER_UM,
            "equivalent_stiffness_chain_N_per_um": k_mid_chain / N_PER_UM,
            "paper_equivalent_stiffness_N_per_um": paper / N_PER_UM,
            "paper_source": "Wang2021 Sect. 5.2",
            "deviation": k_mid / paper - 1.0,
        },
        "closest_readings": [
            {"description": r.description,
             "equivalent_stiffness_N_per_um": r.equivalent_stiffness / N_PER_UM,
             "deviation": r.deviation}
            for r in readings
        ],
    }
    if as_json:
        print_json(summary)
        return

    table = Table(title=f"Stiffness chain, Wang2021 Eqs. (2)–(5) — {params.name}")
    headers = ["x_t [mm]", "k_sa [N/µm]", "Table 3 k_sa", "K_a [N/µm]", "K_eq [N/µm]"]
    if override:
        headers.append("K_eq chain [N/µm]")
    for header in headers:
        table.add_column(escape(header), justify="right")
    for row in rows:
        t3 = row["table3_screw_axial_stiffness_N_per_um"]
        cells = [
            f"{row['position_mm']:g}",
            f"{row['screw_axial_stiffness_N_per_um']:.2f}",
            "" if t3 is None else f"{t3:.2f}",
            f"{row['axial_stiffness_N_per_um']:.2f}",
            f"{row['equivalent_stiffness_N_per_um']:.2f}",
        ]
        if override:
            cells.append(f"{row['equivalent_stiffness_chain_N_per_um']:.2f}")
        table.add_row(*cells)
    console.print(table)
    console.print(f"K_t1 = {chain.torsional:.5g} N m/rad (Eq. 2)")
    source = "set directly (stiffness.equivalent_stiffness)" if override else "from the chain"
    console.print(
        f"K_eq at mid-screw ({summary['mid_screw']['position_mm']:g} mm): "
        f"{k_mid / N_PER_UM:.2f} N/µm {source}; Wang2021 Sect. 5.2 states "
        f"{paper / N_PER_UM:.1f} N/µm: deviation {k_mid / paper - 1.0:+.1%}"
    )
    closest = Table(title="Readings of Eqs. (2)–(5) closest to 21.6 N/µm at mid-screw")
    closest.add_column(escape("K_eq [N/µm]"), justify="right")
    closest.add_column("vs 21.6", justify="right")
    closest.add_column("reading")
    for r in readings:
        closest.add_row(f"{r.equivalent_stiffness / N_PER_UM:.2f}", f"{r.deviation:+.1%}",
                        r.description)
    console.print(closest)
