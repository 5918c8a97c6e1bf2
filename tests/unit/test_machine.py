"""A machine of axes (issue 40): machine files, named signals, coupling parts, contours."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from feeddrive.machine import (
    Circle,
    Line,
    check_machine,
    corner,
    from_csv,
    load_machine,
    machine_from_dict,
    simulate_machine,
)
from feeddrive.machine.couplings import Coupling, register_coupling
from feeddrive.parameters import ParameterError

CARRY = {"part": "inertial", "source": "x", "target": "y", "mass": 30.0, "factor": 0.5}


def test_each_axis_is_any_topology_and_its_signals_are_named_axis_dot_signal() -> None:
    machine = machine_from_dict({"name": "mixed", "axes": {
        "x": {"extends": "wang2021", "drive": "cdfs"},
        "y": {"drive": "linear-motor", "table": {"mass": 30.0}}}})
    assert [(a.name, a.drive) for a in machine.axes] == [("x", "cdfs"), ("y", "linear-motor")]
    assert machine.axis("y").parameters.table.mass == 30.0
    result = simulate_machine(machine, Line(feed=0.01, acceleration=0.5, distance=0.002,
                                            angle=math.pi / 4), 0.2)
    ds = result.dataset
    assert ds["x.table_position"].attrs["units"] == "m"
    assert ds["y.motor_current"].attrs["units"] == "A"
    assert ds["contour_error"].attrs["units"] == "m"
    # both axes follow the 45° line: each moved 0.2 s of its own reference
    for axis in "xy":
        assert abs(ds[f"{axis}.table_position"].values[-1]
                   - ds[f"{axis}.table_position_reference"].values[-1]) < 1e-4
    assert all(name.split(".")[0] in ("x", "y") for name in ds.data_vars
               if name != "contour_error")


@pytest.mark.parametrize(("data", "line"), [
    ({"axes": {"x": {"extends": "nope"}}}, "axes.x.extends = 'nope'"),
    ({"axes": {"x": {"drive": "linear-motor", "table": {"mass": -1}}}},
     "axes.x.table.mass = -1"),
    ({"axes": {"x": {"drive": "warp"}}}, "axes.x.drive = 'warp'"),
    ({"extends": "xy-table", "couplings": {"a": {**CARRY}, "b": {**CARRY}}},
     "y.external_force = 'couplings.a, couplings.b': a signal written by two parts"),
    ({"extends": "xy-table", "couplings": {"a": {**CARRY, "source": "z"}}},
     "couplings.a = 'der(z.table_speed)': a signal read that no axis or part writes"),
    ({"extends": "xy-table", "couplings": {
        "a": CARRY, "b": {**CARRY, "source": "y", "target": "x"}}},
     "a cycle of algebraic signals"),
    ({"extends": "xy-table", "couplings": {"a": {"part": "magic"}}},
     "couplings.a.part = 'magic'"),
])
def test_bad_machine_files_are_refused_in_one_line_naming_the_signal_or_part(
        data: dict, line: str) -> None:
    with pytest.raises(ParameterError) as info:
        machine_from_dict({"name": "bad", **data})
    assert line in str(info.value)
    assert "\n" not in str(info.value)
    assert line in "\n".join(check_machine({"name": "bad", **data}))


def test_check_lists_every_axis_error_one_line_each() -> None:
    errors = check_machine({"name": "bad", "axes": {
        "x": {"extends": "nope"}, "y": {"drive": "linear-motor", "table": {"mass": -1}}}})
    assert len(errors) == 2
    assert errors[0].startswith("axes.x.") and errors[1].startswith("axes.y.")


def test_xy_table_is_built_in() -> None:
    machine = load_machine("xy-table")
    assert [a.name for a in machine.axes] == ["x", "y"]


def test_inertial_coupling_writes_the_target_force_from_the_source_acceleration() -> None:
    """F_y = −κ·m·ẍ (feeddrive.machine.couplings.inertial): compared with the central
    difference of x's recorded speed (its O(Δt²) error is below 1 % of the peak here)."""
    machine = machine_from_dict({"name": "carry", "extends": "xy-table",
                                 "couplings": {"carry": CARRY}})
    result = simulate_machine(machine, Line(feed=0.05, acceleration=0.5, distance=0.02), 0.3)
    force = result["y.external_force"]
    accel = np.gradient(result["x.table_speed"], result.time)
    assert np.max(np.abs(force)) > 5.0  # 0.5 × 30 kg × ≥ 0.5 m/s²
    assert np.max(np.abs(force + 0.5 * 30.0 * accel)) < 0.01 * np.max(np.abs(force))
    # the force moves the y table, which is commanded to stay
    assert np.max(np.abs(result["y.following_error"])) > 1e-8


def test_contours_trace_their_paths() -> None:
    circle = Circle(feed=0.05, acceleration=1.0, radius=0.02, start_angle=0.3, clockwise=True)
    refs = circle.references()
    x, y = (refs[a].encode()[1][0] for a in "xy")  # the exact integrals of the speeds
    assert np.max(np.abs(circle.contour_error(x, y))) < 1e-9
    # the polyline distance (vertices every 0.1 mm) agrees with the exact radius error off
    # the path within the chords' sagitta Δs²/(8R) = 6.25e-8 m
    s = np.linspace(0.0, circle.length, 50)
    p = circle.point(s) * 1.001 - 0.001 * np.array(circle.centre)[:, None]
    from feeddrive.machine import Contour

    np.testing.assert_allclose(Contour.contour_error(circle, p[0], p[1]),
                               circle.contour_error(p[0], p[1]), atol=6.3e-8)
    path = corner(feed=0.05, acceleration=1.0, leg=0.03, angle=90.0, radius=0.005)
    assert path.length == pytest.approx(0.06 + math.pi / 2 * 0.005, rel=1e-6)
    end = path.point(np.array([path.length]))[:, 0]
    np.testing.assert_allclose(end, [0.035, 0.035], atol=1e-12)
    assert circle.duration == pytest.approx(circle.length / 0.05 + 0.05 / 1.0)


def test_csv_path_and_refusals(tmp_path) -> None:  # type: ignore[no-untyped-def]
    f = tmp_path / "path.csv"
    f.write_text("x_mm,y_mm\n10,10\n40,10\n40,30\n")
    path = from_csv(f, feed=0.02, acceleration=1.0)
    assert path.length == pytest.approx(0.05)
    with pytest.raises(ParameterError, match="contour.acceleration"):
        Circle(feed=1.0, acceleration=0.1, radius=0.01)
    with pytest.raises(ParameterError, match="contour.radius"):
        Circle(feed=0.01, acceleration=1.0, radius=-1.0)


def test_a_coupling_part_defined_outside_the_package_runs() -> None:
    """A part is one class: registered from a test file, it is assembled, ordered and
    simulated with no edit elsewhere (docs/machine.md, "Adding one")."""
    @register_coupling
    @dataclass(frozen=True)
    class TableSpring(Coupling):
        stiffness: float = 0.0
        part: ClassVar[str] = "test_table_spring"
        units: ClassVar[dict[str, str]] = {"stiffness": "N/m"}

        def equations(self) -> dict[str, str]:
            return {"y.external_force": "{stiffness} * ({x.table_position} - "
                    "{y.table_position})"}

    machine = machine_from_dict({"name": "spring", "extends": "xy-table", "couplings": {
        "k": {"part": "test_table_spring", "stiffness": 1e5}}})
    result = simulate_machine(machine, Line(feed=0.05, acceleration=0.5, distance=0.01), 0.2)
    np.testing.assert_allclose(
        result["y.external_force"],
        1e5 * (result["x.table_position"] - result["y.table_position"]), rtol=1e-12,
        atol=1e-12)
    assert np.max(np.abs(result["y.external_force"])) > 100.0  # ≈ 1e5 N/m × 5 mm


def test_independent_axes_of_a_machine_move_as_each_drive_alone() -> None:
    """A machine of a sampled DDFS and a linear motor (no coupling part): each axis follows
    its contour reference as the single drive does under the same reference and solver
    settings — to 1e-10 m, the machine's step control seeing both axes' errors (measured:
    1.4e-14 and 1.6e-12 m)."""
    import feeddrive as fd
    from feeddrive.machine import MachineProfile

    sampled = {"position_period": 1e-3, "velocity_period": 5e-4, "current_period": 1.25e-4}
    machine = machine_from_dict({"name": "mixed", "axes": {
        "x": {"extends": "wang2021", "drive": "ddfs", "controller": sampled},
        "y": {"drive": "linear-motor"}}})
    circle = Circle(feed=0.02, acceleration=0.5, radius=0.005)
    options = fd.SolverOptions(method="dopri5", rtol=1e-9, position_tolerance=1e-12,
                               speed_tolerance=1e-10, current_tolerance=1e-9)
    result = simulate_machine(machine, circle, 0.3, options=options)
    refs = MachineProfile.from_contour(circle, machine)
    for ax in machine.axes:
        alone = fd.simulate(fd.DriveSystem(ax.parameters, ax.drive, ax.table_position),
                            refs.axis(ax.name), 0.3, options=options)
        assert np.max(np.abs(alone["table_position"] - result[f"{ax.name}.table_position"])
                      ) < 1e-10
        assert np.max(np.abs(alone["table_position"])) > 1e-3


def test_params_show_text_reads_back_to_the_same_machine() -> None:
    import tomllib

    from feeddrive.machine import machine_toml

    machine = machine_from_dict({"name": "g", "extends": "gantry", "couplings": {
        "sync": {"part": "cross_coupled", "gain": 1.5}}})
    assert machine_from_dict(tomllib.loads(machine_toml(machine))) == machine
    with pytest.raises(ParameterError, match="couplings.sync.citation"):
        machine_from_dict({"name": "g", "extends": "gantry", "couplings": {
            "sync": {"part": "cross_coupled", "citation": "x"}}})


def test_a_machine_model_translates_to_c_and_agrees_with_numba(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The C backend takes a machine's model (its axes' functions _rhs_<axis>,
    _sample_<axis>): the gantry's rates and signals at random states agree with numba's
    to 1e-12 relative (docs/c-backend.md's bound for one model)."""
    from feeddrive.backends.c_backend import c_model_source, compile_shared, load_shared
    from feeddrive.machine import MachineProfile, Together, assemble_machine

    machine = load_machine("gantry")
    model = assemble_machine(machine, MachineProfile.from_contour(
        Together(feed=0.01, acceleration=1.0, distance=0.01), machine))
    lib = load_shared(compile_shared(c_model_source(model), tmp_path, name="gantry"))
    rng = np.random.default_rng(40)
    n, n_aux = len(model.states), len(model.aux)
    for _ in range(5):
        y = rng.normal(size=n) * 1e-3
        out = {}
        for key, backend in (("numba", model.module), ("c", lib)):
            dy, aux = np.empty(n), np.empty(n_aux)
            backend.rhs(0.3, y, np.zeros(model.n_held), model.P, model.T, dy, aux)
            out[key] = np.concatenate([dy, aux])
        scale = np.maximum(np.abs(out["numba"]), 1e-300)
        assert np.max(np.abs(out["c"] - out["numba"]) / scale) < 1e-12
