"""The exported FMU is safe at run time (issue 38 item 3): every settable parameter is checked
when it is set against the range its parameter-file field is checked against (declared as
min/max), outputs are not settable, and ``solver.max_steps_per_call`` bounds the integrator's
steps and the sample instants of each communication step.  The hang cases of the issue return
Error after at most 10 000 integrator steps, counted by the FMU's own step counter (the
integrator's, ``solver.steps``), never timed."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from fmu_helpers import SharedExports, Slave, require_c_compiler

from feeddrive.fmu.description import MAX_STEPS_PER_CALL, variables
from feeddrive.fmu.model import build
from feeddrive.model.mechanisms.shared import Table
from feeddrive.model.slot_ranges import slot_range
from feeddrive.parameters import preset

pytest.importorskip("fmpy")
require_c_compiler()

#: the issue's acceptance bound on the integrator steps before Error
MAX_STEPS = 10_000


@pytest.fixture(scope="module")
def fmus(shared_fmus: SharedExports) -> dict[tuple[str, int], Path]:
    """The CDFS with continuous (wang2021) and sampled (wang2021-drive) loops, FMI 2.0 and
    3.0 co-simulation, exported once in the session (``shared_fmus``)."""
    return {(params, fmi): Path(shared_fmus.drive(preset(params), "cdfs", fmi=fmi).path)
            for params, fmi in (("wang2021", 2), ("wang2021", 3), ("wang2021-drive", 2),
                                ("wang2021-drive", 3))}


def _slave(fmus: dict, params: str, fmi: int, tmp_path: Path, name: str = "x") -> Slave:
    return Slave(fmus[(params, fmi)], tmp_path, name)


def _refused(slave: Slave, name: str, value: float) -> str:
    """Set ``name`` = ``value``; require Error and return the logger's message."""
    n = len(slave.log)
    with pytest.raises(Exception, match="status 3"):
        slave.set(name, value)
    (status, text), = slave.log[n:]
    assert status == 3
    return text


# ---------------------------------------------------------------- the hang cases
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize(("name", "value"), [
    ("controller.current_period", 5e-324), ("controller.current_period", 1e-300),
    ("controller.velocity_period", 5e-324), ("controller.velocity_period", 1e-300),
    ("table.mass", -1.0)])
def test_hang_parameters_are_refused_when_set(fmus: dict, tmp_path: Path, fmi: int, name: str,
                                              value: float) -> None:
    """Before initialisation (where a fixed parameter may be set): the set call itself
    returns Error, the message names the parameter, the value and the parameter file's range;
    the FMU then initialises and steps with its start value, 0 integrator steps wasted."""
    slave = _slave(fmus, "wang2021", fmi, tmp_path)
    text = _refused(slave, name, value)
    assert text.startswith(f"{name} = ")
    if name == "table.mass":  # Table.mass: quantity("kg", low=0.01, high=1e5)
        assert text.endswith("expected 0.01 … 100000 [kg]")
    else:  # Controller._check: "0 (a continuous loop) or 1e-6 … 0.1 [s]"
        assert text.endswith("expected 0 or 1e-06 … 0.1 [s]")
    slave.initialize()
    assert slave.get("solver.steps") == 0
    slave.step(1e-2)
    assert 0 < slave.get("solver.steps") <= MAX_STEPS
    slave.free()


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("params", ["wang2021", "wang2021-drive"])
def test_a_huge_communication_step_returns_error_after_bounded_work(
        fmus: dict, tmp_path: Path, fmi: int, params: str) -> None:
    """A 1e9-s doStep: the continuous drive stops after solver.max_steps_per_call = 10 000
    integrator steps (counted by the integrator), the sampled one (8/4/2 kHz) before any
    step (8e12 sample instants counted first); the message names the setting."""
    slave = _slave(fmus, params, fmi, tmp_path)
    slave.initialize()
    assert slave.get("solver.max_steps_per_call") == MAX_STEPS_PER_CALL == MAX_STEPS
    with pytest.raises(Exception, match="status 3"):
        slave.step(1e9)
    steps = slave.get("solver.steps")
    assert steps == (MAX_STEPS if params == "wang2021" else 0)
    assert slave.log[-1][0] == 3
    assert slave.log[-1][1].startswith("solver.max_steps_per_call = 10000: ")
    assert ("sample instants" in slave.log[-1][1]) == (params == "wang2021-drive")
    slave.free()


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_stiff_but_allowed_set_is_bounded_too(fmus: dict, tmp_path: Path, fmi: int) -> None:
    """Values inside every range can still make the drive stiff (the lightest table, the
    stiffest bristles the parameter file allows, tight tolerances): one 1-s step returns
    Error after at most max_steps_per_call steps — here lowered to 500, as a host may."""
    slave = _slave(fmus, "wang2021", fmi, tmp_path)
    slave.set("table.mass", 0.011)
    slave.set("friction.guide.bristle_stiffness", 1e12)
    slave.set("solver.relative_tolerance", 1e-12)
    slave.set("solver.max_steps_per_call", 500)
    slave.initialize()
    slave.set("table_speed_reference", 2e-3)
    with pytest.raises(Exception, match="status 3"):
        slave.step(1.0)
    assert 0 < slave.get("solver.steps") <= 500
    assert "solver.max_steps_per_call = 500" in slave.log[-1][1]
    slave.free()


# ---------------------------------------------------------------- what may be set, when
@pytest.mark.parametrize("fmi", [2, 3])
def test_outputs_and_computed_variables_are_not_settable(fmus: dict, tmp_path: Path,
                                                         fmi: int) -> None:
    slave = _slave(fmus, "wang2021", fmi, tmp_path)
    for name in ("table_position", "screw_motor_torque", "following_error", "solver.steps"):
        assert _refused(slave, name, 1.0) == (
            f"{name}: computed by the FMU (an output or local variable), not settable")
    slave.initialize()
    # a fixed parameter only before initialisation ends; a tunable one at any time
    text = _refused(slave, "controller.current_period", 1e-4)
    assert text.startswith("controller.current_period: settable only before initialisation")
    assert "settable only before" in _refused(slave, "stiffness.support", 1.0)
    slave.set("table.mass", 25.0)
    assert slave.get("table.mass") == 25.0
    assert _refused(slave, "table.mass", math.nan).startswith("table.mass = nan: expected")
    assert slave.get("table.mass") == 25.0  # a refused value is not taken
    assert _refused(slave, "table_speed_reference", math.inf).endswith(
        "expected a finite value [m/s]")
    slave.step(1e-3)
    slave.free()


def test_switches_take_only_their_values(fmus: dict, tmp_path: Path) -> None:
    slave = _slave(fmus, "wang2021", 2, tmp_path)
    assert _refused(slave, "controller.screw.kv_place", 0.5).endswith(
        "expected one of 0, 1, 2")
    assert _refused(slave, "stiffness.support", 2.0).endswith("expected one of 0, 1")
    assert _refused(slave, "solver.max_steps_per_call", 0).startswith(
        "solver.max_steps_per_call = 0: expected an integer 1 … 2147483647")
    slave.set("controller.screw.kv_place", 2.0)
    slave.set("controller.current_period", 0.0)  # the split range's 0: a continuous loop
    slave.set("controller.current_period", 1e-6)  # and its lowest period
    slave.free()


def test_max_steps_per_call_is_tunable_between_steps(fmus: dict, tmp_path: Path) -> None:
    """Lowered after initialisation it stops the next step; raised again, the run goes on
    from where the last successful step left it."""
    slave = _slave(fmus, "wang2021", 2, tmp_path)
    slave.initialize()
    slave.step(1e-3)
    before = slave.get("solver.steps")
    slave.set("solver.max_steps_per_call", 1)
    with pytest.raises(Exception, match="status 3"):
        slave.step(0.05)
    assert slave.get("solver.steps") - before == 1
    slave.free()


# ---------------------------------------------------------------- declared ranges
def _xml(path: Path) -> ET.Element:
    with zipfile.ZipFile(path) as zf:
        return ET.fromstring(zf.read("modelDescription.xml"))


@pytest.mark.parametrize("fmi", [2, 3])
def test_every_settable_real_declares_the_parameter_files_range(fmus: dict, fmi: int) -> None:
    """min/max of every parameter are the nearest inclusive bounds of its slot's range
    (the range of the parameter-file field it comes from); table.mass's are Table.mass's
    declaration (0.01 … 1e5 kg); the loop periods' the split range's 0 and 0.1 s."""
    root = _xml(fmus[("wang2021", fmi)])
    fm = build(preset("wang2021"), "cdfs", 0.4)
    declared = {}
    for e in root.iter():
        name = e.get("name")
        if name is None:
            continue
        inner = e if fmi == 3 else next(iter(e), e)
        declared[name] = (e.get("causality"), inner.get("min"), inner.get("max"),
                          inner.get("start"))
    meta = Table.__dataclass_fields__["mass"].metadata
    assert declared["table.mass"][1:3] == (repr(float(meta["low"])), repr(float(meta["high"])))
    assert declared["controller.current_period"][1:3] == ("0.0", "0.1")
    assert declared["solver.max_steps_per_call"][1:] == ("1", "2147483647", "10000")
    n = 0
    for v in variables(fm, "cs"):
        if v.causality != "parameter" or v.type != "Real":
            continue
        causality, lo, hi, start = declared[v.name]
        assert v.range is not None and v.range.contains(float(start)), v.name
        if v.kind == 4:  # a model slot: its slot's range
            r = slot_range(fm.model, fm.model.parameter_names[v.a])
            assert (lo, hi) == tuple(repr(float(x)) if math.isfinite(x) else None
                                     for x in (r.minimum, r.maximum)), v.name
            n += 1
    assert n > 50


def test_every_preset_start_value_lies_in_its_range() -> None:
    """The declared ranges hold the exported values of every shipped preset and drive (an
    FMU whose start value lies outside its own min/max would be invalid)."""
    from feeddrive.model.mechanisms import drive_names
    from feeddrive.parameters import PRESETS, ParameterError

    checked = 0
    for name in PRESETS:
        for drive in drive_names():
            try:
                fm = build(preset(name), drive, 0.4)
            except ParameterError:
                continue  # a drive the set has no parts for
            for k, slot in enumerate(fm.model.parameter_names):
                assert slot_range(fm.model, slot).contains(float(fm.model.P[k])), (name, slot)
                checked += 1
    assert checked > 500


# ---------------------------------------------------------------- the solver's tolerances
@pytest.mark.parametrize("fmi", [2, 3])
def test_the_tolerances_take_the_range_the_command_line_takes(fmus: dict, tmp_path: Path,
                                                              fmi: int) -> None:
    """An outside check (2026-12-06): the FMU took solver.relative_tolerance = 1e-20, which
    the command line and the API refuse (1e-14 … 0.1), and declared min 0 for every tolerance
    while refusing 0.  The ranges are SolverOptions' (``MIN_RELATIVE`` … ``MAX_RTOL``,
    ``MIN_ABSOLUTE`` … ``MAX_ABSOLUTE``), declared and checked; an importer's tolerance
    outside it is a warning and the FMU keeps its own."""
    from feeddrive.engine import options

    root = _xml(fmus[("wang2021", fmi)])
    declared = {e.get("name"): (e if fmi == 3 else next(iter(e), e)) for e in root.iter()
                if e.get("name") is not None}
    for name, field in (("solver.relative_tolerance", "rtol"),
                        ("solver.position_tolerance", "position_tolerance"),
                        ("solver.speed_tolerance", "speed_tolerance"),
                        ("solver.current_tolerance", "current_tolerance")):
        low, high = ((options.MIN_RELATIVE, options.MAX_RTOL) if field == "rtol" else
                     (options.MIN_ABSOLUTE[field], options.MAX_ABSOLUTE[field]))
        assert (declared[name].get("min"), declared[name].get("max")) == (
            repr(low), repr(high)), name
    slave = _slave(fmus, "wang2021", fmi, tmp_path)
    assert "solver.relative_tolerance = 1e-20" in _refused(slave, "solver.relative_tolerance",
                                                           1e-20)
    slave.set("solver.relative_tolerance", 1e-8)
    n = len(slave.log)
    if fmi == 2:
        slave.fmu.setupExperiment(tolerance=1e-20, startTime=0.0)
        slave.fmu.enterInitializationMode()
    else:
        slave.fmu.enterInitializationMode(tolerance=1e-20, startTime=0.0)
    slave.fmu.exitInitializationMode()
    (status, text), = slave.log[n:]
    assert status == 1 and "the importer's tolerance 1e-20 is outside" in text
    assert slave.get("solver.relative_tolerance") == 1e-8
    slave.free()


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_step_cap_takes_at_least_a_nanosecond_and_is_named_when_it_binds(
        fmus: dict, tmp_path: Path, fmi: int) -> None:
    """An outside check, 2026-12-07: solver.max_step = 1e-300 s was taken, and every step then
    failed with "the parameters may make the drive too stiff or unstable" (with the largest
    step limit a 0.01-s step would have run for most of an hour)."""
    slave = _slave(fmus, "wang2021", fmi, tmp_path)
    for value in (1e-300, 5e-324, 1e-10):
        text = _refused(slave, "solver.max_step", value)
        assert text.startswith("solver.max_step = ") and "1e-09" in text, text
    slave.set("solver.max_step", 1e-6)
    slave.initialize()
    with pytest.raises(Exception, match="status 3"):
        slave.step(0.1)  # 1e5 steps of the cap, more than 10 000
    assert slave.log[-1][1].startswith("solver.max_steps_per_call = 10000: ")
    assert "solver.max_step = 1e-06 s alone asks for 1e+05 steps" in slave.log[-1][1]
    slave.free()
