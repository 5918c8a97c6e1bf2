"""The one driver (issue 19 item 5): its specialisation by constant folding, and the reusable
output buffers of the dense-output use (issue 21: no fresh output array per call)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine.simulate import (
    Simulation,
    SolverOptions,
    profile_breakpoints,
    sampling,
)
from feeddrive.solvers import driver, driver_text, switching

W = fd.preset("wang2021")


def _template(a: float, flag: bool, mode: int, out: np.ndarray) -> float:
    """A small template: every construct the specialiser folds."""
    x = 0.0
    fast = mode == 1
    if flag and a > 0.0:
        x = a
    elif not flag:
        x = -a
    if fast:
        x *= 2.0
    unused = np.zeros(3)  # noqa: F841 - a dead store the specialiser drops
    while False:
        x += 1.0
    out[0] = x if flag else 0.0
    if flag:
        return x
    return -x


def test_specialise_folds_flags_branches_and_one_valued_locals() -> None:
    text = driver_text.specialise(_template, "f", ["a", "out"], {"flag": True, "mode": 0},
                                  "doc")
    body = text.split('"""')[-1]
    for gone in ("flag", "fast", "mode", "unused", "while", "-a", "-x", "* 2.0"):
        assert gone not in body, (gone, text)
    assert text.startswith("def f(a: float, out: np.ndarray)")
    fn = driver_text.define(text, "f")
    out = np.zeros(1)
    assert fn(3.0, out) == 3.0 and out[0] == 3.0
    other = driver_text.define(driver_text.specialise(_template, "g", ["a", "out"],
                                                      {"flag": False, "mode": 1}, "doc"),
                               "g")
    assert other(3.0, out) == 6.0 and out[0] == 0.0  # x = -6, returned -x
    with pytest.raises(ValueError, match="not parameters"):
        driver_text.specialise(_template, "h", ["a", "b"], {"flag": True, "mode": 0}, "doc")
    with pytest.raises(ValueError, match="reads"):  # a dropped parameter still read
        driver_text.specialise(_template, "h", ["out"], {"flag": True, "mode": 0}, "doc")


def test_each_use_is_the_one_template_and_the_explicit_ones_hold_no_rodas4() -> None:
    for use in driver.USES:
        text = driver_text.source(use)
        assert f"def {use}(" in text and "_dp5_step(" not in text  # the step written in
    # the dense driver's step attempt (numba inlines it: the Rosenbrock step in its text)
    assert "step_attempt(" in driver_text.source("integrate_dense")
    assert "_r4_rodas4_step(" in driver_text.piece_source("step_attempt")
    for use in ("integrate", "advance"):
        text = driver_text.source(use)
        assert "_r4_" not in text and "modal_step_cap" not in text


def test_output_buffers_are_written_and_returned_as_views_bit_identical() -> None:
    """A run into reused buffers gives the same arrays as one into fresh ones; a buffer too
    small for the call is not used."""
    system = fd.DriveSystem(W, "cdfs", 0.4)
    profile = fd.ConstantSpeed(2e-3)
    model = system.model(profile)
    options = SolverOptions()
    grid = sampling(system.parameters, options.output_interval, model)
    n_break = int(round(0.5 / grid.base))
    t_end = n_break * grid.base
    sim = Simulation(system, profile, options)  # the run's resolved tolerances
    atol, rel = sim.atol, sim.rel
    mode, _ = options.driver_mode

    def run(out: tuple[np.ndarray, np.ndarray, np.ndarray] | None, want_aux: bool
            ) -> tuple[np.ndarray, ...]:
        return switching.integrate(
            model, system.initial_vector(model), t_end, grid.out_every, grid.base,
            grid.schedule, sim.tolerances.rtol, atol, rel, 1e-6, math.inf, 1, options.max_steps,
            mode, profile_breakpoints(profile, t_end, grid.base), want_aux, out=out)

    n_out = n_break // grid.out_every + 1
    for want_aux in (False, True):
        fresh = run(None, want_aux)
        buf = switching.new_output(model, n_out + 7, want_aux)
        buf[1][:] = np.nan  # nothing of the buffer's past shows
        reused = run(buf, want_aux)
        for a, b in zip(fresh[:3], reused[:3], strict=True):
            np.testing.assert_array_equal(a, b)
        assert np.shares_memory(reused[1], buf[1]) and reused[1].shape == (n_out, len(model.states))
        np.testing.assert_array_equal(fresh[3][:4], reused[3][:4])  # same steps and calls
    small = switching.new_output(model, n_out - 1)
    again = run(small, False)
    assert not np.shares_memory(again[1], small[1])
    np.testing.assert_array_equal(again[1], fresh[1])


def test_the_specialised_text_is_the_template_specialised() -> None:
    """What ``source`` gives is the template with the use's flags folded (the FMU's
    ``advance``, its step functions called, not written in)."""
    driver_text.source.cache_clear()
    made = driver_text.source("advance", inline=False)
    params, fixed, doc = driver.USES["advance"]
    fresh = driver_text.specialise(driver.driver_template, "advance", params,
                                   {"LAND": False, "DENSE": False, **driver_text._MODES,
                                    **fixed}, doc, "int")
    assert fresh == made
    assert driver_text.source("advance", inline=False) is made  # memoised in the process
    with pytest.raises(KeyError):
        driver_text.source("nothing")
