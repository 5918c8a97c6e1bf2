"""`feeddrive identify static|dynamic|merge`: LuGre friction from measurements.

File formats: docs/measured-data.md.  The logic lives in feeddrive.analysis.static_fit,
feeddrive.analysis.presliding, feeddrive.analysis.fragments and feeddrive.io.measured.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from ..io.outputs import PLOT_FORMATS, atomic_path, shown
from ..parameters import DriveParameters, ParameterError, save

if TYPE_CHECKING:
    from ..analysis.fit_statistics import Estimate
    from ..analysis.presliding import DynamicFit
    from ..analysis.static_fit import StaticFit

from ._common import (
    MM_PER_S,
    N_PER_UM,
    DecimalOption,
    SepOption,
    TimeUnitOption,
    app,
    console,
    err_console,
    outputs,
    print_json,
    resolve_parameters,
    user_errors,
)


def _say(text: str) -> None:
    console.print(text, highlight=False, markup=False, soft_wrap=True)


identify_app = typer.Typer(no_args_is_help=True,
                           help="Identify LuGre friction parameters from measured tests.")
app.add_typer(identify_app, name="identify")

SITES = ("screw", "nut", "guide")  # the CDFS/DDFS sites (feeddrive.units.SITES)
_SITE_HELP = "Friction site: screw, nut or guide (Wang2021 Sect. 4)."
def _site(site: str) -> str:
    if site not in SITES:
        raise ParameterError("--site", site, f"expected one of {', '.join(SITES)}")
    return site


def _base(preset_name: str | None, params_file: str | None,
          fragments: list[str] | None = None) -> DriveParameters:
    from ..analysis.fragments import merge_fragment

    params = resolve_parameters(preset_name, params_file)
    for frag in fragments or []:
        params = merge_fragment(params, Path(frag))
    return params


def _fmt(est: Estimate, scale: float = 1.0, digits: int = 4) -> str:
    v = est.value * scale
    if not (math.isfinite(est.low) and math.isfinite(est.high)):
        return f"{v:.{digits}g} (interval not determined)"
    return (f"{v:.{digits}g}  [{est.low * scale:.{digits}g} … {est.high * scale:.{digits}g}]")


def _print_static(fit: StaticFit, confidence: float) -> None:
    _say(f"static friction fit of {fit.source} ({100 * confidence:.0f} % intervals)")
    rows = (("F_c", "coulomb_force", 1.0, "N"), ("F_s", "static_force", 1.0, "N"),
            ("v_s", "stribeck_velocity", 1.0 / MM_PER_S, "mm/s"),
            ("σ2", "viscous_coefficient", 1.0, "N s/m"))
    if fit.one_direction:
        other = "negative" if fit.one_direction == "positive" else "positive"
        _say(f"  tests in the {fit.one_direction} direction only: that branch only is fitted; "
             f"the {other} branch is not (a fragment leaves it to the base set)")
    for name, b in fit.branches().items():
        _say(f"  {name} direction: {b.speed.size} tests, rms residual {b.rmse:.3g} N")
        for label, attr, scale, unit in rows:
            est = getattr(b, attr)
            flag = "" if est.identifiable else "  (not identifiable)"
            _say(f"    {label:4s} = {_fmt(est, scale)} {unit}{flag}")
    _warn_unidentifiable(fit)


def _warnings(fit: StaticFit | DynamicFit) -> list[str]:
    """One line per fitted value the data do not determine."""
    from ..analysis.static_fit import StaticFit

    if isinstance(fit, StaticFit):
        labels = {"coulomb_force": "F_c", "static_force": "F_s", "stribeck_velocity": "v_s",
                  "viscous_coefficient": "σ2"}
        return [f"{labels[name]} ({direction}) is not identifiable from these data: {why}"
                for direction, b in fit.branches().items()
                for name, why in b.unidentifiable().items()]
    out = []
    if not fit.residual_ok:
        return [f"poor fit: rms residual {fit.rmse * 1e9:.3g} nm is "
                f"{fit.rmse / fit.noise:.3g}× the record's own noise {fit.noise * 1e9:.3g} nm; "
                "σ0 and σ1 are not determined"]
    for label, est in (("σ0", fit.bristle_stiffness), ("σ1", fit.bristle_damping)):
        if not est.identifiable:
            out.append(f"{label} is not identifiable from these data: "
                       f"{est.identifiability_issue}")
    return out


def _warn_unidentifiable(fit: StaticFit | DynamicFit) -> None:
    for text in _warnings(fit):
        err_console.print(f"warning: {text}", markup=False, highlight=False, soft_wrap=True)


def _print_dynamic(fit: DynamicFit) -> None:
    s0, s1 = fit.bristle_stiffness, fit.bristle_damping
    level = f"{100 * s0.confidence:.0f} %"
    _say(f"pre-sliding fit of {fit.source}: model {fit.model}, mass {fit.mass:.4g} kg, "
                  f"rms residual {fit.rmse * 1e9:.3g} nm")
    _say(f"  σ0 = {_fmt(s0, 1.0 / N_PER_UM)} N/µm ({level})"
         + ("" if s0.identifiable and fit.residual_ok else "  (not identifiable)"))
    if not fit.residual_ok:
        _say("  σ1 not determined: poor fit (the residual exceeds the record's noise)")
    elif fit.sigma1_determined:
        _say(f"  σ1 = {_fmt(s1)} N s/m ({level})")
    else:
        low, high = fit.sigma1_interval
        upper = f"{high:.3g}" if math.isfinite(high) else "unbounded"
        _say(f"  σ1 poorly determined: consistent with {low:.3g} … {upper} N s/m "
                      f"({level} profile)")
    _say(f"  σ2 = {fit.viscous_coefficient:.4g} N s/m held fixed")
    if fit.force_ratio is not None:
        _say(f"  max|F| = {100 * fit.force_ratio:.0f} % of F_s")
    _say(f"  {fit.note}")
    _warn_unidentifiable(fit)


@identify_app.command("static")
@user_errors
@outputs(out=(".toml",), plot=PLOT_FORMATS)
def static_command(
    file: str = typer.Argument(..., help="CSV of constant-speed tests (speed, force)."),
    site: str = typer.Option("screw", "--site", help=_SITE_HELP),
    out: str | None = typer.Option(None, "--out", help="Write a TOML fragment here."),
    plot: str | None = typer.Option(None, "--plot", help="Write the fit/residual plot here."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    speed_column: str = typer.Option("speed", "--speed-column"),
    force_column: str = typer.Option("force", "--force-column"),
    current_column: str = typer.Option("current", "--current-column",
                                       help="Used when there is no force column."),
    speed_unit: str | None = typer.Option(None, "--speed-unit",
                                          help="mm/s (default), m/s, um/s, mm/min."),
    force_unit: str | None = typer.Option(None, "--force-unit", help="N (default) or kN."),
    current_unit: str | None = typer.Option(None, "--current-unit", help="A (default) or mA."),
    torque_constant: float | None = typer.Option(
        None, "--torque-constant", help="K_t [N m/A] for a current column (default: the "
        "parameter set's motor of the site)."),
    lead: float | None = typer.Option(None, "--lead", help="Screw lead [mm] for a current "
                                      "column (default: the parameter set's)."),
    weighting: str = typer.Option("relative", "--weighting",
                                  help="relative (noise ∝ force) or absolute."),
    confidence: float = typer.Option(0.95, "--confidence", help="Confidence level [-]."),
    sep: SepOption = None,
    decimal: DecimalOption = ".",
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    force: bool = typer.Option(False, "--force", help="Replace existing --out/--plot files."),
) -> None:
    """Fit F_c, F_s, v_s and σ2 per direction to constant-speed friction tests."""
    from ..analysis.fragments import friction_fragment
    from ..analysis.static_fit import fit_static
    from ..io.measured import read_static_test

    # in the options' units, before the file is read (--lead 0 was refused as "lead = 0.0
    # ... [m]" together with the torque constant: an outside check, 2026-12-07)
    for option, given, unit in (("--torque-constant", torque_constant, "N m/A"),
                                ("--lead", lead, "mm")):
        if given is not None and not (math.isfinite(given) and given > 0):
            raise ParameterError(option, given, f"expected a finite value > 0 [{unit}]")
    site = _site(site)
    params = _base(preset_name, params_file)
    motor = params.hollow_motor if site == "nut" else params.screw_motor
    kt = torque_constant if torque_constant is not None else motor.torque_constant
    lead_m = lead * 1e-3 if lead is not None else params.screw.lead
    if weighting not in ("relative", "absolute"):
        raise ValueError(f"--weighting = {weighting!r}: expected relative or absolute")
    data = read_static_test(file, speed_column=speed_column, force_column=force_column,
                            current_column=current_column, speed_unit=speed_unit,
                            force_unit=force_unit, current_unit=current_unit,
                            torque_constant=kt, lead=lead_m, sep=sep, decimal=decimal)
    fit = fit_static(data.speed, data.force, confidence=confidence,
                     weighting=weighting,  # type: ignore[arg-type]
                     lines=data.lines, source=data.source)
    if out:
        with atomic_path(out) as tmp:
            tmp.write_text(friction_fragment(site, static=fit, source=data.source),
                           encoding="utf-8")
    if plot:
        from ..plots.analysis import plot_static_fit

        plot_static_fit(fit, plot)
    if as_json:
        print_json({"site": site, "force_from": data.force_from, **fit.to_dict("mm"),
                    "warnings": _warnings(fit), "fragment": out, "plot": plot})
        return
    _print_static(fit, confidence)
    if data.force_from != "force":
        _say(f"  force from current: K_t = {kt:g} N m/A, lead = {lead_m * 1e3:g} mm")
    for path, what in ((out, "fragment"), (plot, "plot")):
        if path:
            _say(f"wrote {what} {path}")


@identify_app.command("dynamic")
@user_errors
@outputs(out=(".toml",), plot=PLOT_FORMATS)
def dynamic_command(
    file: str = typer.Argument(..., help="CSV of a pre-sliding test (time, force, position)."),
    site: str = typer.Option("screw", "--site", help=_SITE_HELP),
    mass: float | None = typer.Option(
        None, "--mass", help="Moving mass [kg] (default: the site's inertia referred to the "
        "table, J/H² for screw and nut, the table mass for the guide)."),
    model: str = typer.Option("lugre", "--model", help="lugre (full bristle model) or linear "
                              "(m x'' + (σ1+σ2) x' + σ0 x = F, for |F| ≪ F_s)."),
    static: Annotated[list[str] | None, typer.Option(
        "--static", help="Static-fit fragment(s) merged into the parameter set first "
        "(their branches and σ2 are used).")] = None,
    out: str | None = typer.Option(None, "--out", help="Write a TOML fragment here."),
    plot: str | None = typer.Option(None, "--plot", help="Write the fit/profile plot here."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON."),
    time_column: str = typer.Option("time", "--time-column"),
    force_column: str = typer.Option("force", "--force-column"),
    position_column: str = typer.Option("position", "--position-column"),
    time_unit: TimeUnitOption = None,
    force_unit: str | None = typer.Option(None, "--force-unit", help="N (default) or kN."),
    position_unit: str | None = typer.Option(None, "--position-unit",
                                             help="um (default), nm, mm, m."),
    confidence: float = typer.Option(0.95, "--confidence", help="Confidence level [-]."),
    sep: SepOption = None,
    decimal: DecimalOption = ".",
    preset_name: str | None = typer.Option(None, "--preset", help="Named parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Parameter file (TOML)."),
    force: bool = typer.Option(False, "--force", help="Replace existing --out/--plot files."),
) -> None:
    """Fit σ0 and σ1 to a pre-sliding test; says so when σ1 is poorly determined."""
    from ..analysis.fragments import friction_fragment
    from ..analysis.presliding import fit_presliding, site_mass
    from ..io.measured import read_presliding_test

    site = _site(site)
    if model not in ("lugre", "linear"):
        raise ValueError(f"--model = {model!r}: expected lugre or linear")
    if not (0.5 <= confidence < 1.0):
        raise ValueError(f"--confidence = {confidence!r}: expected a level in [0.5, 1)")
    if mass is not None and not (math.isfinite(mass) and mass > 0):  # named as typed, before
        # the file is read (the fit's own check said "mass = 0.0", after reading it)
        raise ValueError(f"--mass = {mass!r}: expected a finite mass > 0 [kg]")
    from ..model.friction.lugre_parameters import LuGreParameters  # numba: at use only

    params = _base(preset_name, params_file, static)
    m = mass if mass is not None else site_mass(params, site, "cdfs")
    data = read_presliding_test(file, time_column=time_column, force_column=force_column,
                                position_column=position_column, time_unit=time_unit,
                                force_unit=force_unit, position_unit=position_unit, sep=sep,
                                decimal=decimal)
    with err_console.status(f"fitting {shown(data.source)}") as status:
        fit = fit_presliding(data.time, data.force, data.position, mass=m,
                             friction=getattr(params.friction, site).require(
                                 LuGreParameters, f"friction.{site}", "identify dynamic"),
                             model=model,  # type: ignore[arg-type]
                             confidence=confidence, lines=data.lines, source=data.source,
                             progress=lambda text: status.update(
                                 f"fitting {shown(data.source)}: {text}"))
    if out:
        with atomic_path(out) as tmp:
            tmp.write_text(friction_fragment(site, dynamic=fit, source=data.source),
                           encoding="utf-8")
    if plot:
        from ..plots.analysis import plot_dynamic_fit

        plot_dynamic_fit(fit, plot)
    if as_json:
        print_json({"site": site, "mass_from": "option" if mass is not None else "parameters",
                    **fit.to_dict(), "warnings": _warnings(fit), "fragment": out,
                    "plot": plot})
        return
    _print_dynamic(fit)
    for path, what in ((out, "fragment"), (plot, "plot")):
        if path:
            _say(f"wrote {what} {path}")


@identify_app.command("merge")
@user_errors
@outputs(out=(".toml",))
def merge_command(
    fragments: Annotated[list[str], typer.Argument(help="TOML fragment(s), merged in order.")],
    out: str = typer.Option(..., "--out", help="Write the merged parameter set here."),
    preset_name: str | None = typer.Option(None, "--preset", help="Base parameter set."),
    params_file: str | None = typer.Option(None, "--params", help="Base parameter file."),
    force: bool = typer.Option(False, "--force", help="Replace an existing --out file."),
) -> None:
    """Merge identified fragments into a parameter set and validate the result."""
    params = _base(preset_name, params_file, fragments)
    names = ", ".join(Path(f).name for f in fragments)
    params = params.with_values(name=f"{params.name}-identified",
                                description=f"{params.description} Merged: {names}.")
    save(params, out)
    _say(f"wrote {out}: {params.name} with {', '.join(fragments)} merged")
