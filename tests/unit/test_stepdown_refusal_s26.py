"""A step-down search whose staircase would not fit in memory is refused before any work,
naming where it starts (session 26).

``feeddrive creep --high 200 --method stepdown`` was refused by the output-memory check of
its first run, in words its user never typed (``duration = 24000.0 … shorten the duration
[s] or raise output_interval (options.output_interval …)``), and under ``--method both``
only after the search from rest had run.  The host's memory is set in each test
(``budget.available_memory``), so the refusal does not depend on the machine."""

from __future__ import annotations

import pytest

import feeddrive as fd
from feeddrive.analysis import critical
from feeddrive.engine import budget
from feeddrive.engine.budget import BYTES_PER_SAMPLE
from feeddrive.parameters import ParameterError

GIB = 2**30


@pytest.fixture
def small_host(monkeypatch: pytest.MonkeyPatch) -> None:
    """1 GiB available, and no trial, walk or run may start."""
    monkeypatch.setattr(budget, "available_memory", lambda: GIB)

    def refused(*args: object, **kwargs: object) -> None:
        raise AssertionError("work started on a request that should have been refused")

    monkeypatch.setattr(critical, "_run_trial", refused)
    monkeypatch.setattr(critical, "walk_down", refused)


def test_the_staircase_is_refused_on_its_start_with_its_length(small_host: None) -> None:
    """From 20 mm/s down to 0.05 mm/s in 0.1-mm/s steps held 12 s (the protocol's first
    dwell): 201 steps (19.95 mm/s and 20 mm/s itself at the top), 2 412 s, 2.4e6 samples at
    1 ms, each 2 × BYTES_PER_SAMPLE bytes with its copy — 2.2 GiB, more than half of 1 GiB;
    0.5 GiB holds 45 of the 201 steps."""
    system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)
    samples = int(201 * 12.0 / 1e-3) + 1
    need = samples * BYTES_PER_SAMPLE * 2.0
    with pytest.raises(ParameterError) as err:
        fd.critical_speed_stepdown(system, start_speed=20e-3, coarse_step=1e-4)
    assert err.value.field == "start_speed" and err.value.value == 20e-3
    text = str(err.value)
    assert "down to 0.05 mm/s (201 steps held 12 s each, 2412 s" in text, text
    assert f"about {need / GIB:.3g} GiB, more than half the 1 GiB available" in text, text
    assert f"about {int(201 * 0.5 * GIB / need)} steps fit" in text, text


def test_a_staircase_that_fits_is_not_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """The protocol's own staircase (3 → 0.05 mm/s, 30 steps, 360 s: 0.33 GiB) fits in 1 GiB:
    the check lets it through to the walk (stopped here by the test)."""
    monkeypatch.setattr(budget, "available_memory", lambda: GIB)

    class Reached(Exception):
        pass

    def reached(*args: object, **kwargs: object) -> None:
        raise Reached

    monkeypatch.setattr(critical, "walk_down", reached)
    with pytest.raises(Reached):
        fd.critical_speed_stepdown(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4))


@pytest.mark.parametrize("method", ["stepdown", "both"])
def test_the_command_line_names_high_before_any_search(small_host: None, method: str) -> None:
    """`creep --high 20` refuses the step-down as --high in mm/s, with exit status 2 — under
    --method both before the search from rest has run a trial."""
    from typer.testing import CliRunner

    from feeddrive.cli import app

    res = CliRunner().invoke(app, ["creep", "--high", "20", "--method", method, "--json"])
    assert res.exit_code == 2, res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("error: --high = 20 [mm/s]: its staircase down to 0.02 mm/s "
                           "(201 steps held 12 s each"), line
    assert "duration" not in line and "start_speed" not in line, line
