"""A replayed force's Result (an outside check of docs/fitting.md, 2026-12-06): its
``summary()`` failed deep in the trace checks with ``ValueError: command_speed = 0.0``, which
also broke the notebook's display (``_repr_html_`` shows a summary it cannot make only for a
ParameterError), and a run the divergence bound stopped early (a 40-N replay without
``speed_scale``: 0.113 s of 0.4 s) said so only in ``solver_stats["diverged"]``."""

from __future__ import annotations

import numpy as np
import pytest

import feeddrive as fd
from feeddrive.model.replay import ForceReplay
from feeddrive.parameters import ParameterError


@pytest.fixture(scope="module")
def pushed() -> tuple[fd.Result, fd.Result]:
    system = fd.DriveSystem(fd.preset("linear-motor-example"), "linear-motor", 0.4)
    t = np.linspace(0.0, 0.4, 401)
    force = np.full_like(t, 40.0)  # [N], a constant push on the free table
    return (fd.simulate(system, ForceReplay(t, force), 0.4),
            fd.simulate(system, ForceReplay(t, force, speed_scale=0.5), 0.4))


def test_a_run_stopped_early_says_so_in_its_repr(pushed: tuple[fd.Result, fd.Result]) -> None:
    stopped, full = pushed
    assert stopped.solver_stats["diverged"] and stopped.time[-1] < 0.4
    assert "stopped at 0.113 s" in repr(stopped) and "diverged" in repr(stopped)
    assert full.time[-1] == pytest.approx(0.4) and "stopped" not in repr(full)


def test_a_replay_has_no_creep_summary_and_says_why(pushed: tuple[fd.Result, fd.Result]
                                                    ) -> None:
    _, full = pushed
    with pytest.raises(ParameterError, match="commanded table speed"):
        full.summary()
    with pytest.raises(ParameterError, match="replay"):
        full.creep_metrics()
    html = full._repr_html_()  # the notebook's display still shows the run
    assert "none (" in html and "commanded table speed" in html
