"""A machine of axes as one FMU (issue 40, item 4): its variables named ``<axis>.<name>`` with
units, fmpy's validation, and the FMU in fmpy following ``simulate_machine`` of the same
machine driven by the same references — co-simulation, and model exchange with its
directional derivatives through the axes and the coupling parts."""

from __future__ import annotations

import dataclasses as dc
from pathlib import Path

import numpy as np
import pytest
from fmu_helpers import FMU_TIGHT, STEP, TIGHT, Model, SharedExports, check_jacobian

from feeddrive.engine.options import SolverOptions
from feeddrive.fmu import export_machine_fmu
from feeddrive.machine import (
    MachineProfile,
    load_machine,
    machine_from_dict,
    make_contour,
    simulate_machine,
)
from feeddrive.machine.couplings.gantry import CrossCoupled
from feeddrive.model.reference import SampledSpeed

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("fmpy.validation")
CC = pytest.importorskip("feeddrive.backends.c_backend")
try:
    CC.find_compiler()
except CC.CompilerNotFound:  # pragma: no cover - CI has a compiler
    pytest.skip("no C compiler", allow_module_level=True)

#: an XY table whose x axis carries a 40-kg mass guided by y (feeddrive.machine.couplings.
#: inertial): y's load force is −mass·(x's table acceleration)
INERTIAL = {"name": "xy-inertial", "extends": "xy-table",
            "couplings": {"carried": {"part": "inertial", "source": "x", "target": "y",
                                      "mass": 40.0, "factor": 1.0}}}
#: an XY table of sampled axes (wang2021-drive: 8/4/2-kHz current/velocity/position loops),
#: each axis' periods a setting of its own
SAMPLED = {"name": "xy-sampled", "axes": {
    "x": {"extends": "wang2021-drive", "drive": "cdfs"},
    "y": {"extends": "wang2021-drive", "drive": "cdfs"}}}
MACHINES = {"xy-table": None, "inertial": INERTIAL, "sampled": SAMPLED}
#: the gantry with Koren's cross-coupled controller: coupling code between the axes' scope
#: functions that reads both axes' states and writes both axes' inputs
GANTRY = {"name": "gantry-cc", "extends": "gantry",
          "couplings": {"sync": {"part": "cross_coupled"}}}


def _circle_profile(machine):  # type: ignore[no-untyped-def]
    """A quarter of the R = 50 mm, F = 5000 mm/min circle (lead-in at 1 m/s²), each axis'
    speed held over the communication step (SampledSpeed(hold=True)), as the FMU holds its
    inputs."""
    contour = make_contour("circle", feed=5000 / 60e3, acceleration=1.0, radius=0.05,
                           turns=0.25)
    profile = MachineProfile.from_contour(contour, machine, interval=STEP)
    return dc.replace(profile, axes=tuple((n, dc.replace(r, hold=True))
                                          for n, r in profile.axes))


def _run_fmu(path: Path, profile: MachineProfile, outputs: list[str]) -> np.ndarray:
    axes = [n for n, _ in profile.axes]
    columns = [(f"{n}.{k}", float) for n in axes
               for k in ("table_position_reference", "table_speed_reference", "load_force")]
    table = np.zeros(len(profile.time), dtype=[("time", float), *columns])
    table["time"] = profile.time
    for n in axes:
        table[f"{n}.table_speed_reference"] = profile.axis(n).table_speed
    return fmpy.simulate_fmu(str(path), start_time=0.0, stop_time=float(profile.time[-1]),
                             output_interval=STEP, input=table, start_values=FMU_TIGHT,
                             output=outputs)


def _deviation(rec: np.ndarray, ds, name: str) -> float:  # type: ignore[no-untyped-def]
    t = np.asarray(ds["time"])
    idx = np.searchsorted(rec["time"], t + 1e-9 * STEP, side="right") - 1
    return float(np.max(np.abs(rec[name][idx] - np.asarray(ds[name]))))


@pytest.mark.parametrize("fmi", [2, 3])
def test_machine_fmu_declares_each_axis_and_validates(tmp_path: Path, fmi: int) -> None:
    """One FMU for the XY table: per axis the reference and load inputs, the outputs and the
    tunable parameters of its single-drive FMU, named ``<axis>.<name>`` with units; the
    loop periods a setting per axis; fmpy's validation finds no problem."""
    from fmpy.validation import validate_fmu

    path = tmp_path / "xy.fmu"
    fmu = export_machine_fmu(load_machine("xy-table"), path, fmi=fmi)
    assert validate_fmu(str(path)) == []
    assert fmu.inputs == tuple(f"{a}.{k}" for a in "xy" for k in (
        "table_position_reference", "table_speed_reference", "load_force"))
    md = fmpy.read_model_description(str(path))
    vs = {v.name: v for v in md.modelVariables}
    for a in "xy":
        assert vs[f"{a}.table_position"].causality == "output"
        assert vs[f"{a}.table_position"].unit == "m"
        assert vs[f"{a}.screw_motor_torque"].unit == "N m"
        assert vs[f"{a}.load_force"].unit == "N"
        assert vs[f"{a}.table.mass"].variability == "tunable"
        assert vs[f"{a}.table.mass"].unit == "kg"
        assert vs[f"{a}.controller.position_period"].causality == "parameter"
    assert "controller.position_period" not in vs
    assert fmu.n_states == 30  # 15 per wang2021 CDFS axis (its single-drive FMU's count)


@pytest.mark.parametrize("fmi", [2, 3])
def test_machine_model_exchange_fmu_declares_every_rate_and_validates(
        shared_fmus: SharedExports, fmi: int) -> None:
    """Model exchange: the same ``<axis>.<name>`` variables, and the rate of every continuous
    state (each axis' own and its two reference integrals, the coupling parts' states) with
    its unit; fmpy's validation finds no problem."""
    from fmpy.validation import validate_fmu

    fmu = shared_fmus.machine(repr(GANTRY), machine_from_dict(GANTRY), fmi=fmi, kind="me")
    path = fmu.path
    assert fmu.kind == "me"
    assert validate_fmu(str(path)) == []
    md = fmpy.read_model_description(str(path))
    rates = {d.variable.name: d.variable for d in md.derivatives}
    assert len(rates) == fmu.n_states + 4  # 2 × 15 per axis, beam 4, integral 1; 2 × 2 refs
    for name, unit in (("x1.table_position", "m/s"), ("x2.table_speed", "m/s2"),
                       ("x1.reference.table_position", "m/s"), ("beam.yaw", "rad/s"),
                       ("beam.yaw_rate", "rad/s2"), ("sync.integral", "m")):
        assert rates[f"der({name})"].unit == unit, name
        assert rates[f"der({name})"].derivative.name == name
    assert "evaluations.tangents" in {v.name for v in md.modelVariables}


def _point(m: Model) -> tuple[float, np.ndarray]:
    """Away from rest: the states at 10× their nominal magnitudes, signs mixed, mid-run."""
    rng = np.random.default_rng(40)
    return 0.05, rng.standard_normal(m.n) * 10 * m.nominals()


def test_machine_directional_derivatives_match_central_differences(
        tmp_path: Path, shared_fmus: SharedExports) -> None:
    """The machine's tangent — each axis' scope function and the beam's and the cross-coupled
    controller's code between them — against central differences of the FMU's own
    derivatives on every declared pair (1e-6 relative), the declared sparsity holding where
    nothing is declared; the coupling parts make x2's rates depend on x1's states, by the
    controller's gains exactly."""
    path = shared_fmus.machine(repr(GANTRY), machine_from_dict(GANTRY), kind="me").path
    m = Model(path, tmp_path)
    m.start({"x1.table_speed_reference": 2e-3, "x2.table_speed_reference": 2e-3,
             "x1.load_force": 50.0})
    t, x = _point(m)
    assert check_jacobian(m, t, x, "gantry") >= m.n
    index = {s.name: j for j, s in enumerate(m.states)}
    m.states_at(t, x)
    seed = [0.0] * m.n
    seed[index["x1.table_position"]] = 1.0
    column = dict(zip([d.name for d in m.ders],
                      m.directional([d.valueReference for d in m.ders],
                                    [s.valueReference for s in m.states], seed), strict=True))
    # the controller: x1's speed command falls by (K_p + K_c) per metre of x1, x2's rises by
    # K_c (the velocity errors the loop integrals integrate); the beam's joint pulls the beam
    kp, kc = 8.0, CrossCoupled(name="sync").gain  # wang2021's position gain, the default
    assert (column["der(x2.screw_velocity_integral)"]
            / column["der(x1.screw_velocity_integral)"]) == pytest.approx(-kc / (kp + kc),
                                                                          rel=1e-12)
    assert column["der(beam.speed)"] > 0.0
    assert column["der(sync.integral)"] == pytest.approx(1.0, rel=1e-15)


@pytest.mark.slow
@pytest.mark.parametrize(("machine", "bound"), [("gantry", 1e-10), ("sampled", 1e-10)])
def test_machine_model_exchange_in_fmpy_follows_simulate_machine(
        shared_fmus: SharedExports, machine: str, bound: float) -> None:
    """As model-exchange FMUs integrated by fmpy's CVODE (rtol 1e-10): the gantry with the
    cross-coupled controller, and the XY table of sampled axes (its loops' instants as time
    events), every axis commanded 2 mm/s from rest, against ``simulate_machine`` of the same
    machine at the tight tolerances (TIGHT).  Table positions within 1e-10 m (measured
    5.0e-13 m over the gantry's 0.3 s, 1.4e-11 m over the sampled table's 0.1 s)."""
    definition = GANTRY if machine == "gantry" else SAMPLED
    m = machine_from_dict(definition)
    path = shared_fmus.machine(repr(definition), m, kind="me").path
    duration = 0.3 if machine == "gantry" else 0.1
    t = np.arange(0.0, duration + 0.5 * STEP, STEP)
    speed = dc.replace(SampledSpeed(time=t, table_speed=np.full(t.size, 2e-3)), hold=True)
    profile = MachineProfile.common(m, speed)
    outputs = [f"{ax.name}.table_position" for ax in m.axes]
    rec = fmpy.simulate_fmu(str(path), stop_time=float(t[-1]), output_interval=STEP,
                            relative_tolerance=1e-10, output=outputs,
                            start_values={f"{ax.name}.table_speed_reference": 2e-3
                                          for ax in m.axes})
    ds = simulate_machine(m, profile, float(t[-1]),
                          options=SolverOptions(**TIGHT)).dataset  # type: ignore[arg-type]
    for name in outputs:
        assert _deviation(rec, ds, name) <= bound, name
        assert float(np.asarray(ds[name])[-1]) > 0.5 * 2e-3 * duration  # it moved


def test_cli_exports_a_machine_and_refuses_single_drive_options(tmp_path: Path) -> None:
    """``export fmu --machine`` writes the FMU the API writes (its inputs listed); options of
    one drive and an unknown kind are refused in one line, exit status 2, before any work."""
    import json

    from typer.testing import CliRunner

    from feeddrive.cli import app

    runner = CliRunner()
    out = tmp_path / "xy.fmu"
    res = runner.invoke(app, ["export", "fmu", "--machine", "xy-table", "--out", str(out),
                              "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.output)["inputs"] == [
        f"{a}.{k}" for a in "xy"
        for k in ("table_position_reference", "table_speed_reference", "load_force")]
    for extra, option in ((["--kind", "xx"], "--kind"), (["--drive", "cdfs"], "--drive"),
                          (["--preset", "wang2021"], "--preset"),
                          (["--table-speed", "5"], "--table-speed")):
        bad = tmp_path / f"bad{option}.fmu"
        res = runner.invoke(app, ["export", "fmu", "--machine", "xy-table", *extra, "--out",
                                  str(bad)])
        assert res.exit_code == 2, res.output
        assert res.output.strip().startswith(f"error: {option} = ")
        assert len(res.output.strip().splitlines()) == 1
        assert not bad.exists()
