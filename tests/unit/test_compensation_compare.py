"""`feeddrive compensate --compare` (issue 37 item 4): every friction compensation side by
side — the wiring (each scheme's row from its own run, settings from the parts' rules), the
refusals, and the help and docs labels against the code."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from feeddrive.analysis import compensation_compare as cc
from feeddrive.cli import app
from feeddrive.cli.compensate_cmd import COMPARE_SCHEMES
from feeddrive.parameters import ParameterError, preset

DRIVE = preset("wang2021-drive")
DOC = (Path(__file__).resolve().parents[2] / "docs" / "linear.md").read_text(encoding="utf-8")
FLAT = " ".join(DOC.split())


def test_each_scheme_is_set_by_its_parts_rule_and_differs_only_in_its_compensation():
    """I_r = F_c·H/K_t and J_n/K_t = (J_m + J_s + m_t·H²)/K_t computed here from wang2021
    Tables 1–2 (F_c of the screw and the guide, K_t, J's, m_t, lead); DOB g = 300 rad/s,
    v_w = 2 mm/s as docs/extending.md measures them."""
    h = DRIVE.screw.lead / (2 * math.pi)
    k_t = DRIVE.screw_motor.torque_constant
    f_c = (DRIVE.friction.screw.positive.coulomb_force
           + DRIVE.friction.guide.positive.coulomb_force)
    got = {s.name: s for s in cc.schemes(DRIVE)}
    assert list(got) == list(cc.SCHEMES)
    rff = got["reversal-feedforward"].parameters.reversal_feedforward
    assert rff.current == pytest.approx(f_c * h / k_t, rel=1e-12)
    assert rff.width == 2e-3 and rff.period == DRIVE.controller.velocity_period
    dob = got["disturbance-observer"].parameters.disturbance_observer
    j = DRIVE.screw_motor.inertia + DRIVE.screw.shaft_inertia + DRIVE.table.mass * h**2
    assert dob.inertia_gain == pytest.approx(j / k_t, rel=1e-12) and dob.bandwidth == 300.0
    assert got["reset-integrator"].parameters.reset_integrator.fraction == 0.0
    assert got["feedforward"].parameters.controller.compensation.mode == "feedforward"
    assert got["observer"].parameters.controller.compensation.mode == "observer"
    assert got["observer"].parameters.controller.compensation.observer_gain == 0.0
    # a sampled scheme is the set with one section more; a continuous one, its loops changed
    for name, s in got.items():
        extra = {k for k, _ in s.parameters.sections} - {k for k, _ in DRIVE.sections}
        c = s.parameters.controller
        if name in cc.CONTINUOUS:
            assert (c.velocity_period, c.current_period, c.encoder_counts) == (0, 0, 0)
            assert "continuous" in s.settings["loops"] and not extra
        else:
            assert c == dataclasses.replace(DRIVE.controller, compensation=c.compensation)
            assert c.compensation.mode == "none" and "sampled" in s.settings["loops"]
            assert len(extra) == (0 if name == "none" else 1)


def test_settling_time_is_read_to_the_band_and_stays_there():
    t = np.arange(0.0, 1.0, 0.1)
    e = np.array([5, 3, 2, 0.5, 1.5, 0.5, 0.2, 0.1, 0.0, 0.0]) * 1e-6
    assert cc.settling_time(t, e, 1e-6, 0.0) == pytest.approx(0.5)  # leaves at 0.4 s
    assert cc.settling_time(t, e, 1e-6, 0.55) == 0.0
    assert math.isnan(cc.settling_time(t, e[::-1], 1e-6, 0.0))  # outside at the end


def test_each_row_comes_from_its_own_run_and_a_zero_reversal_current_is_the_baseline():
    """The settling run of each sampled scheme (the cheapest quantity): I_r = 0 reproduces
    the uncompensated row exactly; the DOB changes it.  (The reset integrator gives the
    baseline's settling at wang2021-drive's own gains: the 10-µm move does not overshoot, so
    the position error never crosses zero and nothing is reset — docs/linear.md.)"""
    rows = cc.compare_compensations(
        DRIVE, names=["none", "reversal-feedforward"], metrics=["settling"],
        reversal_current=0.0)
    assert [r["scheme"] for r in rows] == ["none", "reversal-feedforward"]
    assert rows[1]["settings"]["current_A"] == 0.0
    for key in ("settling_time_s", "error_after_settling_um"):
        assert rows[1][key] == rows[0][key]
    done = []
    rows = cc.compare_compensations(
        DRIVE, names=["none", "disturbance-observer", "reset-integrator"],
        metrics=["settling"], progress=lambda d, n, label: done.append((d, n, label)))
    assert done[-1][:2] == (3, 3) and len(done) == 4
    base = rows[0]
    assert base["settling_band_um"] == 1.0
    for r in rows:
        assert r["error_after_settling_um"] <= 1.0  # it stays within the band once settled
        assert set(r) >= {"settling_time_s", "settings", "parameter_set"}
    dob = rows[1]
    assert (dob["settling_time_s"], dob["error_after_settling_um"]) != (
        base["settling_time_s"], base["error_after_settling_um"])


def test_every_scheme_has_its_row():
    rows = cc.compare_compensations(DRIVE, metrics=["settling"])
    assert [r["scheme"] for r in rows] == list(cc.SCHEMES)
    assert all(math.isfinite(r["settling_time_s"]) for r in rows)
    assert "critical_speed_mm_s" not in rows[0]  # only the quantities asked for


def test_csv_has_every_column_and_the_settings():
    rows = [{"scheme": "none", "parameter_set": "p", "settings": {"loops": "sampled"},
             "settling_time_s": 0.5, "settling_band_um": 1.0}]
    head, line = cc.comparison_csv(rows).splitlines()
    assert head.split(",")[1:5] == [k for k, _ in cc.COLUMNS]
    assert line.split(",")[4] == "0.5" and "loops=sampled" in line


@pytest.mark.parametrize(("call", "field"), [
    (lambda: cc.compare_compensations(preset("wang2021")), "controller.velocity_period"),
    (lambda: cc.compare_compensations(DRIVE, names=["magic"]), "names"),  # its argument
    (lambda: cc.compare_compensations(DRIVE, metrics=["speed"]), "metrics"),
    (lambda: cc.compare_compensations(DRIVE, band=0.0), "band"),
])
def test_bad_requests_are_refused_before_any_run(call, field):
    with pytest.raises(ParameterError) as err:
        call()
    assert err.value.field == field


def test_the_cli_refuses_in_one_line_before_any_work(tmp_path):
    runner = CliRunner()
    r = runner.invoke(app, ["compensate", "--compare", "--preset", "wang2021"])
    assert r.exit_code == 2 and "controller.velocity_period" in r.output
    assert len(r.output.strip().splitlines()) == 1
    r = runner.invoke(app, ["compensate", "--compare", "--band", "-1"])
    assert r.exit_code == 2 and "--band" in r.output
    existing = tmp_path / "t.csv"
    existing.write_text("keep")
    r = runner.invoke(app, ["compensate", "--compare", "--output", str(existing)])
    assert r.exit_code == 2 and existing.read_text() == "keep"
    r = runner.invoke(app, ["compensate", "--compare", "--plot", str(tmp_path / "f.txt")])
    assert r.exit_code == 2
    r = runner.invoke(app, ["compensate", "--compare", "--no-search"])
    assert r.exit_code == 2 and "--no-search" in r.output
    r = runner.invoke(app, ["compensate", "--output", str(tmp_path / "n.csv")])
    assert r.exit_code == 2 and "--compare" in r.output


def test_help_and_docs_name_what_the_code_does():
    assert COMPARE_SCHEMES == ",".join(cc.SCHEMES)
    r = CliRunner().invoke(app, ["compensate", "--help"], terminal_width=200)
    flat = " ".join(r.output.split())
    for option in ("--compare", "--schemes", "--metrics", "--band", "--output", "--plot"):
        assert option in flat
    rows = re.findall(r"^\| `([a-z-]+)` \| (sampled|continuous) \|", DOC, flags=re.M)
    assert [n for n, _ in rows] == list(cc.SCHEMES)
    for name, loops in rows:
        assert (name in cc.CONTINUOUS) == (loops == "continuous"), name
    for _, heading in cc.COLUMNS:
        assert f"`{heading}`" in FLAT, heading
    # the stated search resolution, circle and test settings are the module's
    assert f"bisected to {1e3 * cc.CRITICAL_RESOLUTION:g} mm/s" in FLAT
    assert f"R = {1e3 * cc.CIRCLE_RADIUS:g} mm, F = {1e3 * cc.CIRCLE_FEED:g} mm/s" in FLAT
    assert f"{cc.DOB_BANDWIDTH:g} rad/s" in FLAT and "`error_after_settling_um`" in FLAT
    assert f"{cc.POSITIONING_OVERSHOOT * 1e3:g}-mm overshoot, {cc.POSITIONING_DWELL:g}-s dwell" \
        in FLAT
    for key in ("`reversal_reading_motion_um`", "`resets_per_s_at_top_speed`",
                "`critical_speed_bands`", "`not at rest (… µm moving)`",
                "`spike_lead_arc_deg`",
                f"`none smooth ≤ {1e3 * cc.CRITICAL_RANGE[1]:.2f}: reset cycle`"):
        assert key in FLAT, key


def test_the_circular_and_positioning_rows_are_the_baselines_at_zero_reversal_current():
    """The spike (ISO 230-4 on an XY table of two such axes) and B (ISO 230-2) of each row
    come from its own runs: I_r = 0 gives the uncompensated numbers, I_r = F_c·H/K_t others."""
    names = ["none", "reversal-feedforward"]
    zero = cc.compare_compensations(DRIVE, names=names, metrics=["spike", "reversal"],
                                    reversal_current=0.0)
    assert zero[1]["largest_spike_um"] == zero[0]["largest_spike_um"] > 0.0
    assert zero[1]["reversal_value_B_um"] == zero[0]["reversal_value_B_um"] > 0.0
    assert zero[0]["spikes_found"] == 8  # four quadrant reversals, CCW and CW
    # the circle's lead arcs are the settling rule's (the sampled loops linearised as
    # continuous: the rule's 221.6°, tests/unit/test_circular_stability.py)
    assert zero[0]["spike_lead_arc_deg"] == pytest.approx(221.6, abs=0.05)
    on = cc.compare_compensations(DRIVE, names=names[1:], metrics=["spike", "reversal"])[0]
    assert on["largest_spike_um"] != zero[0]["largest_spike_um"]
    assert on["reversal_value_B_um"] != zero[0]["reversal_value_B_um"]


def test_the_figure_has_a_panel_per_column_and_writes_a_bound():
    from feeddrive.plots.acceptance import compensation_figure

    rows = [{"scheme": "none", "critical_speed_mm_s": "< 0.20", "settling_time_s": 0.5},
            {"scheme": "observer", "critical_speed_mm_s": "1.75", "settling_time_s": 0.3}]
    fig = compensation_figure(rows)
    assert [ax.get_ylabel() for ax in fig.axes] == [h for _, h in cc.COLUMNS]
    assert [t.get_text() for t in fig.axes[0].texts] == ["< 0.20"]
    heights = [p.get_height() for p in fig.axes[3].patches]
    assert heights == [0.5, 0.3]


def test_b_is_read_at_rest_or_not_given(monkeypatch):
    """Guards the observer's B of 273 µm (docs/linear.md before issue 37 item 1): at a 0.3-s
    dwell the LuGre-observer axis still rang in its 5.5-Hz servo mode (the friction that
    damps it when sticking is compensated) and the reading windows saw hundreds of µm of
    motion; B was the ringing's phase.  Such a reading is now "not at rest"; at the
    comparison's dwell every window is within the 1-µm band and B is a number."""
    from feeddrive.analysis.positioning_run import run_positioning_test

    observer = cc.schemes(DRIVE, ["observer"])[0]
    targets = [0.4 + t for t in cc.POSITIONING_TARGETS]
    short = run_positioning_test(observer.parameters, "cdfs", targets,
                                 feed=cc.POSITIONING_FEED, dwell=0.3,
                                 overshoot=cc.POSITIONING_OVERSHOOT)
    assert short.reading_motion > 100e-6 and short.test.reversal > 100e-6
    row = cc.measure(observer, "cdfs", 0.4, ["reversal"], band=1e-6)
    assert row["reversal_reading_motion_um"] <= 1.0
    assert isinstance(row["reversal_value_B_um"], float) and row["reversal_value_B_um"] < 1.0
    monkeypatch.setattr(cc, "POSITIONING_DWELL", 0.3)
    row = cc.measure(observer, "cdfs", 0.4, ["reversal"], band=1e-6)
    assert row["reversal_value_B_um"].startswith("not at rest (")
    assert row["reversal_reading_motion_um"] > 100.0


def test_the_reset_integrators_missing_critical_speed_is_its_own_cycle():
    """The reset integrator's "> 3.20 mm/s" (docs/linear.md before issue 37 item 1): at
    3.2 mm/s the loop without resets slides smoothly, with them the table never sticks but
    oscillates, two resets per period — the resets drive the cycle, not friction (measured:
    6.1 Hz, 12 resets/s)."""
    from feeddrive.analysis.critical import creep_trial
    from feeddrive.engine.simulate import DriveSystem

    top = cc.CRITICAL_RANGE[1]
    none, reset = cc.schemes(DRIVE, ["none", "reset-integrator"])
    assert creep_trial(DriveSystem(none.parameters, "cdfs", 0.4), top).kind == "smooth"
    system = DriveSystem(reset.parameters, "cdfs", 0.4)
    trial = creep_trial(system, top)
    assert trial.kind == "oscillation" and trial.stick_fraction == 0.0
    rate = cc.reset_rate(system, top)
    assert rate == pytest.approx(2.0 * trial.stick_slip_frequency, rel=0.05)
    # γ = 1 keeps the integral (crossings counted, not acted on): the loop tracks smoothly
    # with its error at zero, crossing it hundreds of times a second — a set-point reset law
    # finds a crossing to act on all the time while the table moves
    kept = DriveSystem(dataclasses.replace(reset.parameters, sections=tuple(
        (k, dataclasses.replace(v, fraction=1.0)) if k == "reset_integrator" else (k, v)
        for k, v in reset.parameters.sections)), "cdfs", 0.4)
    assert creep_trial(kept, top).kind == "smooth"
    assert cc.reset_rate(kept, top) > 10.0 * rate
