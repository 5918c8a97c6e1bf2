"""A replayed force's Result (an outside check of docs/fitting.md, 2026-12-06): its
``summary()`` failed deep in the trace checks with ``ValueError: command_speed = 0.0``, which
also broke the notebook's display (``_repr_html_`` shows a summary it cannot make only for a
ParameterError), and a run the divergence bound stopped early (a 40-N replay without
``speed_scale``: 0.113 s of 0.4 s) said so only in ``solver_stats["diverged"]``.  Since
2026-12-07 that run is refused with the advice to give ``speed_scale`` (its bound is the
floor's, not a speed the run was judged against), and a run stopped at a bound the user set
names the bound in its repr."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.engine.simulate import SimulationError
from feeddrive.model.replay import ForceReplay
from feeddrive.parameters import ParameterError

PUSH = 40.0  # [N], a constant push on the free table


@pytest.fixture(scope="module")
def pushed() -> tuple[fd.Result, fd.Result]:
    system = fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor", 0.4)
    t = np.linspace(0.0, 0.4, 401)
    force = np.full_like(t, PUSH)
    # speed_scale 1 mm/s: the bound 100 × that, 0.1 m/s, reached at 0.113 s (measured
    # 2026-12-06, then without speed_scale, whose floor gives the same bound)
    return (fd.simulate(system, ForceReplay(t, force, speed_scale=1e-3), 0.4),
            fd.simulate(system, ForceReplay(t, force, speed_scale=0.5), 0.4))


def test_a_run_stopped_early_says_so_in_its_repr(pushed: tuple[fd.Result, fd.Result]) -> None:
    stopped, full = pushed
    assert stopped.solver_stats["diverged"] and stopped.time[-1] < 0.4
    assert stopped.solver_stats["divergence_speed_m_s"] == pytest.approx(0.1)
    assert "stopped at 0.113 s" in repr(stopped) and "diverged" in repr(stopped)
    assert "bound 100 mm/s" in repr(stopped)
    assert full.time[-1] == pytest.approx(0.4) and "stopped" not in repr(full)


def test_a_replay_without_speed_scale_that_reaches_the_floors_bound_is_refused() -> None:
    system = fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor", 0.4)
    t = np.linspace(0.0, 0.4, 401)
    with pytest.raises(SimulationError, match=r"reached 0\.1 m/s at t = 0\.113.* without "
                       r"speed_scale .*ForceReplay\(\.\.\., speed_scale=\.\.\.\) the "
                       r"largest table speed"):
        fd.simulate(system, ForceReplay(t, np.full_like(t, PUSH)), 0.4)
    # one that stays below it runs as before
    slow = fd.simulate(system, ForceReplay(t, np.full_like(t, PUSH)), 0.05)
    assert slow.time[-1] == pytest.approx(0.05) and not slow.solver_stats.get("diverged")


def test_a_replay_has_no_creep_summary_and_says_why(pushed: tuple[fd.Result, fd.Result]
                                                    ) -> None:
    _, full = pushed
    with pytest.raises(ParameterError, match="commanded table speed"):
        full.summary()
    with pytest.raises(ParameterError, match="replay"):
        full.creep_metrics()
    html = full._repr_html_()  # the notebook's display still shows the run
    assert "none (" in html and "commanded table speed" in html
