"""`feeddrive fit` with explicit tolerances (outside check 35, defect 1).

``fit ... --rtol 1e-6`` (or ``--position-tolerance 1e-4 --speed-tolerance 0.1``) stopped after
its first integration-error estimate: ``options.accuracy = 0.1: given with rtol in one setting
(API)``.  The fit's runs rebuild their options from ``SolverOptions.record()``
(``from_record``), which carries no origin, so the tightened options (the explicit rtol ÷ 10,
``accuracy`` 0.1 for the defaults) looked like both given in one setting.  With a
``[solver]`` table of explicit tolerances the fit ran, but printed ``refit at accuracy 1``
after every tightening and ended ``integrator accuracy 1 (2 tightening(s))``.

Now a record round-trips, a tightening divides each explicit tolerance (and ``accuracy`` for
the defaults and dopri5's step caps: docs/model.md's rule, docs/fitting.md), and the fit's
labels and JSON state the tolerances used.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import feeddrive as fd
from feeddrive.cli import app
from feeddrive.engine import options as opt
from feeddrive.engine.error_estimate import tightened

runner = CliRunner()


# ------------------------------------------------------------------ the record round-trips


def _layered_cases() -> list[fd.SolverOptions]:
    file = "[solver] in run.toml"
    return [
        opt.layered([(file, {"accuracy": 0.1}), ("command line", {"rtol": (1e-7, "--rtol")})]),
        opt.layered([(file, {"accuracy": 0.01}),
                     ("API", {"position_tolerance": 1e-12, "speed_tolerance": 1e-9}),
                     ("command line", {"current_tolerance": (1e-7, "--current-tolerance")})]),
        opt.layered([(file, {"method": "dopri5", "rtol": 1e-5, "position_tolerance": 1e-12,
                             "speed_tolerance": 1e-7, "current_tolerance": 1e-4})]),
        opt.layered([("command line", {"accuracy": (0.5, "--accuracy")})]),
    ]


@pytest.mark.parametrize("options", _layered_cases(),
                         ids=["file-accuracy-cli-rtol", "file-api-cli", "file-explicit-dopri5",
                              "cli-accuracy"])
def test_a_record_round_trips_before_and_after_tightening(options: fd.SolverOptions) -> None:
    for o in (options, tightened(options), tightened(tightened(options, 10.0), 10.0)):
        back = fd.SolverOptions.from_record(o.record())
        assert back == o and back.record() == o.record()
        # as a fit's worker uses it (engine.simulate's shadow, analysis.fit.simulate_experiment)
        dataclasses.replace(back, output_interval=5e-4, sample_steps=True)
        tightened(back)
        # the record stays a key of the settings alone, not of where they came from; a fit's
        # task carries the sources beside it, and the worker's options name them again
        assert "origin" not in o.record()
        named = fd.SolverOptions.from_record(o.record(), [list(p) for p in o.origin])
        assert named == o and named.origin == o.origin
        assert named.tolerances_label() == o.tolerances_label()


def test_one_setting_with_both_is_still_refused() -> None:
    with pytest.raises(fd.ParameterError, match="in one setting"):
        fd.SolverOptions(rtol=1e-7, accuracy=0.1)
    with pytest.raises(fd.ParameterError, match="--accuracy"):
        opt.layered([("command line", {"rtol": (1e-7, "--rtol"), "accuracy": (0.1, "--accuracy")})])


def test_tightening_divides_each_explicit_tolerance_and_names_where_it_came_from() -> None:
    o = opt.layered([("[solver] in run.toml", {"accuracy": 0.1}),
                     ("command line", {"rtol": (1e-7, "--rtol")})])
    once = tightened(o, 10.0)
    assert (once.rtol, once.accuracy) == pytest.approx((1e-8, 0.01))
    assert once.source("rtol") == "--rtol ÷ 10"
    twice = tightened(once, 10.0)
    assert (twice.rtol, twice.accuracy) == pytest.approx((1e-9, 1e-3))
    assert twice.source("rtol") == "--rtol ÷ 100"
    assert twice.setting_text("rtol") == "rtol 1e-9 (--rtol ÷ 100)"
    assert twice.tolerances_label() == "rtol 1e-9, accuracy 0.001"
    # every tolerance explicit: accuracy acts only on dopri5's step caps, and is tightened there
    explicit = {"rtol": 1e-5, "position_tolerance": 1e-12, "speed_tolerance": 1e-7,
                "current_tolerance": 1e-4}
    modal = tightened(fd.SolverOptions(**explicit))
    assert modal.accuracy == 1.0 and modal.tolerances_label() == \
        "rtol 1e-6, positions 1e-10 mm, speeds 1e-5 mm/s, currents 1e-5 A"
    dopri5 = tightened(fd.SolverOptions(method="dopri5", **explicit))
    assert dopri5.accuracy == pytest.approx(0.1)
    assert dopri5.largest_step < fd.SolverOptions(method="dopri5", **explicit).largest_step


# ------------------------------------------------------------------ the fit, end to end


@pytest.fixture(scope="module")
def trace(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The outside check's trace: ``simulate --table-speed 2 --duration 2 --output``."""
    path = tmp_path_factory.mktemp("s19") / "tr1.csv"
    result = runner.invoke(app, ["simulate", "--table-speed", "2", "--duration", "2",
                                 "--output", str(path)])
    assert result.exit_code == 0, result.output
    return path


FIT = ["--command-speed", "2", "--free", "controller.velocity_integral_gain", "--no-profile"]


def _fit(trace: Path, *args: str) -> tuple[str, dict]:
    text = runner.invoke(app, ["fit", str(trace), *FIT, *args], terminal_width=400)
    assert text.exit_code == 0, text.output
    assert "error" not in text.stderr, text.stderr
    out = runner.invoke(app, ["fit", str(trace), *FIT, *args, "--json"])
    assert out.exit_code == 0, out.output
    return text.stdout, json.loads(out.stdout)


def test_fit_with_an_explicit_rtol_finishes_with_the_tightened_rtol_in_its_label(
        trace: Path) -> None:
    text, data = _fit(trace, "--rtol", "1e-6", "--workers", "1")
    check = data["integration_check"]
    assert check["met"] is True and check["steps"] >= 1
    steps = check["steps"]
    rtol, accuracy = 1e-6 / 10 ** steps, 0.1 ** steps
    assert check["rtol"] == pytest.approx(rtol) and check["accuracy"] == pytest.approx(accuracy)
    label = f"rtol {rtol:.3g}, accuracy {accuracy:.3g}".replace("e-0", "e-")
    assert check["integrator"]["label"] == label
    assert check["integrator"]["rtol"] == pytest.approx(rtol)
    assert [h["integrator"]["label"] for h in check["history"]][0] == "rtol 1e-6, accuracy 1"
    assert f"integrator {label} ({steps} tightening(s)): estimated integration error" in text
    assert f"refit at {label}:" in text
    assert "refit at accuracy" not in text
    # and the stationarity check's last step, as the history records it
    step = check["history"][-1]["gauss_newton_step_stderr"]
    assert step <= 0.1
    assert f"the Gauss–Newton step at the optimum {step:.2g} standard errors" in " ".join(
        text.split())


def test_fit_with_explicit_absolute_tolerances_finishes(trace: Path) -> None:
    text, data = _fit(trace, "--position-tolerance", "1e-4", "--speed-tolerance", "0.1")
    check = data["integration_check"]
    assert check["met"] is True
    steps = check["steps"]
    pos, speed = 1e-4 / 10 ** steps, 0.1 / 10 ** steps
    assert check["integrator"]["position_tolerance"] == pytest.approx(pos * 1e-3)
    assert check["integrator"]["speed_tolerance"] == pytest.approx(speed * 1e-3)
    assert check["integrator"]["label"].startswith(f"positions {pos:.3g} mm, speeds {speed:.3g}"
                                                   .replace("e-0", "e-"))
    assert f"integrator {check['integrator']['label']} ({steps} tightening(s))" in text


def test_fit_with_a_solver_tables_tolerances_labels_what_it_tightened(
        trace: Path, tmp_path: Path) -> None:
    """Every tolerance explicit in a ``[solver]`` table (dopri5): each tightening divides them
    (and dopri5's step caps through ``accuracy``), and the labels say so, not ``accuracy 1``."""
    path = tmp_path / "s3.toml"
    path.write_text('extends = "wang2021"\nname = "s3"\n[solver]\nrtol = 1e-5\n'
                    "position_tolerance = 1e-12\nspeed_tolerance = 1e-7\n"
                    'current_tolerance = 1e-4\nmethod = "dopri5"\n', encoding="utf-8")
    text, data = _fit(trace, "--params", str(path))
    check = data["integration_check"]
    assert check["met"] is True and check["steps"] >= 1
    k = 10 ** check["steps"]
    entry = check["integrator"]
    assert (entry["rtol"], entry["position_tolerance"], entry["speed_tolerance"],
            entry["current_tolerance"], entry["accuracy"]) == pytest.approx(
        (1e-5 / k, 1e-12 / k, 1e-7 / k, 1e-4 / k, 1 / k))
    assert entry["label"] == fd.SolverOptions(
        method="dopri5", rtol=1e-5 / k, position_tolerance=1e-12 / k,
        speed_tolerance=1e-7 / k, current_tolerance=1e-4 / k,
        accuracy=1 / k, origin=(("accuracy", "x"),)).tolerances_label()
    assert f"integrator {entry['label']} ({check['steps']} tightening(s))" in text
    assert "refit at accuracy 1" not in text and "integrator accuracy 1 (" not in text
