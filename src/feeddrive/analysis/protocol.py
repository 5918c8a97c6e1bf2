"""The critical-speed protocol `feeddrive creep` and `feeddrive reproduce` share.  SI units.

Both used to search different speed grids (0.05–3.0 mm/s in 0.1-mm/s steps against
0.02–3.02 mm/s in 0.2-mm/s steps), and a step-down search remembers the steps it came down,
so the CLI and the report gave the CDFS 1.35 and 1.32 mm/s by "the same" protocol (issue 12
item 18).  One set of numbers now serves both; the report and the CLI print it.
"""

from __future__ import annotations

SPEED_RANGE = (0.02e-3, 3.02e-3)  # [m/s] lowest and highest speed tested
COARSE_STEP = 0.2e-3  # [m/s] scan step from rest, before the bisection
STAIRCASE_COARSE_STEP = 0.1e-3  # [m/s] first staircase of the step-down search
RESOLUTION = 0.01e-3  # [m/s] Wang2021 Sect. 6: the speed was stepped down by 0.01 mm/s
TRIAL_DURATION = 12.0  # [s] first trial length (doubled until the verdict is decided)
TRIAL_MAX_DURATION = 240.0  # [s] longest trial; still undecided then: 'undecided'
# the linear stability scan of steady sliding (`feeddrive stability`, the sweep's
# `linear-band` quantity, the explorer, linear.stability_band): one default range (issue 24
# item 8: the command scanned 0.01–5 mm/s and the sweep 0.02–3.02 mm/s)
LINEAR_SPEED_RANGE = (0.01e-3, 5e-3)  # [m/s] log-spaced scan, edges bisected
LINEAR_POINTS = 40  # [-] scan points


def describe(start: str) -> str:
    """The protocol in words, in mm/s, for the CLI and the report."""
    lo, hi = (1e3 * v for v in SPEED_RANGE)
    if start == "rest":
        return (f"from rest: trials of {TRIAL_DURATION:g} s doubled up to "
                f"{TRIAL_MAX_DURATION:g} s until decided, scan {lo:g}–{hi:g} mm/s in "
                f"{1e3 * COARSE_STEP:g}-mm/s steps, then bisection to {1e3 * RESOLUTION:g} mm/s")
    return (f"step-down on a running table: staircase from {hi:g} mm/s in "
            f"{1e3 * STAIRCASE_COARSE_STEP:g}-mm/s steps, then {1e3 * RESOLUTION:g}-mm/s steps "
            f"from the last smooth one (down to {lo:g} mm/s)")
