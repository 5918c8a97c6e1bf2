"""The window-independent creep verdict: a limit cycle, a decayed transient, or not yet
decided.  SI units.

:func:`trace_verdict` judges a table-speed trace by the *limit-cycle rule*
(:class:`VerdictRule`): the speed settles within a band around the command (``smooth``), or
the oscillation repeats as a limit cycle (``stick-slip`` when the table stops, ``oscillation``
when it never does), or neither yet (``undecided``: a longer trace decides).  The rule does not
depend on the trace's length, so ``feeddrive creep``, ``reproduce``, the explorer and the
critical-speed search (:mod:`feeddrive.analysis.critical`) run each trial until it is decided.
The words are those of :mod:`feeddrive.analysis.verdict_words`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from . import protocol
from .trace_input import MIN_WINDOW_SAMPLES, as_trace, check_command, time_below
from .verdict_words import CREEPING_KINDS, OSCILLATION, SMOOTH, STICK_SLIP, UNDECIDED

__all__ = ["TraceVerdict", "VerdictRule", "growing", "trace_verdict"]


@dataclass(frozen=True)
class VerdictRule:
    """When a trial's outcome is decided (:func:`trace_verdict`).

    Ratios are relative to |v_cmd|.  The trial length doubles from ``initial_duration`` until
    decided; both duration defaults are the protocol of ``feeddrive creep`` and ``reproduce``
    (``feeddrive.analysis.protocol``).

    Parameters
    ----------
    smooth_band : float, default 0.02
        *Decayed*: the speed has stayed within ±``smooth_band``·|v_cmd| of the command for the
        settling stretch [-].  A limit cycle whose peak-to-peak ripple is below
        2·``smooth_band`` is smooth too.
    settle_time : float, default 2.0
        The settling stretch lasts at least this long and at least two of the longest
        oscillation periods seen [s].
    growth_blocks : int, default 8
        *Decayed* also needs the deviation not to be growing: the settling stretch is cut
        into this many equal blocks (≥ 0.25 s each at the default ``settle_time``) …
    growth_run : int, default 4
        … and the trace is not decayed while the peak-to-peak speed of each of its last
        ``growth_run`` blocks exceeds the block's before (a mode growing inside the band,
        seeded by the start transient or the integration error: it leaves the band later,
        so a longer trial decides).  A decaying transient shrinks block after block and
        never rises so; a steady (noise-like) deviation rises over ``growth_run`` blocks by
        chance 1/``growth_run``! (1/24), which only makes the trial longer.
    cycle_tolerance : float, default 0.02
        *Limit cycle*: the compared cycles' highest speed, lowest speed and period agree within
        this fraction of the ripple and of the mean period [-].  A cycle runs from one upward
        crossing of the command to the next.
    min_cycles : int, default 3
        At least this many repetitions are compared; the compared cycles are those of the last
        half of the trace (never the first cycle, which starts from rest or from the previous
        state) …
    min_compare_time : float, default 2.0
        … or of the last ``min_compare_time`` if longer, so a slowly decaying envelope is not
        mistaken for a limit cycle, and they span at least ``min_compare_time`` (a mode that
        has just grown across the command's band is not yet a cycle) [s].  The drift
        between the quarters of the compared stretch must also not speed up (a trajectory
        lingering by a limit cycle that has just vanished drifts ever faster), unless below a
        tenth of ``cycle_tolerance``.
    max_multiplicity : int, default 8
        Period-doubled cycles repeat after p cycles; p up to this is tried.
    envelope_tolerance : float, default 0.05
        An irregular oscillation (no repetition) is sustained when the highest and lowest speeds
        of the last ``envelope_blocks`` blocks of cycles agree within this fraction of the
        ripple [-] and the ripple does not shrink block after block by more than a tenth of
        this in all (the floor of the periodic drift test: the widths of a steady chaotic
        envelope fall block after block by chance 1/``envelope_blocks``!, by 0.02 % on the
        ``wang2021-literal`` CDFS at 0.04 mm/s, 24–48 s).
    envelope_blocks : int, default 3
        Blocks compared, each ≥ 8 cycles and ≥ ``min_compare_time``.
    stick_level : float, default 0.01
        A limit cycle is *stick-slip* when the table speed in the command's direction falls
        below ``stick_level``·|v_cmd| (the table stops, up to the bristles' micro-motion, or
        moves backwards), else *oscillation* [-].
    initial_duration : float
        First trial length, the protocol's ``TRIAL_DURATION`` (12 s) [s].
    max_duration : float
        Longest trial, the protocol's ``TRIAL_MAX_DURATION`` (240 s) [s]: a trial still
        undecided then answers "undecided".

    Raises
    ------
    ValueError
        For a value out of range, naming ``rule.<field>``.
    """

    smooth_band: float = 0.02
    settle_time: float = 2.0
    growth_blocks: int = 8
    growth_run: int = 4
    cycle_tolerance: float = 0.02
    min_cycles: int = 3
    min_compare_time: float = 2.0
    max_multiplicity: int = 8
    envelope_tolerance: float = 0.05
    envelope_blocks: int = 3
    stick_level: float = 0.01
    initial_duration: float = protocol.TRIAL_DURATION
    max_duration: float = protocol.TRIAL_MAX_DURATION

    def __post_init__(self) -> None:
        for name in ("smooth_band", "settle_time", "cycle_tolerance", "min_compare_time",
                     "envelope_tolerance", "stick_level", "initial_duration", "max_duration"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not math.isfinite(value) or value <= 0:
                raise ValueError(f"rule.{name} = {value!r}: expected a finite number > 0")
        for name in ("min_cycles", "max_multiplicity", "envelope_blocks", "growth_run"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 2 - (
                    name == "max_multiplicity"):
                raise ValueError(f"rule.{name} = {value!r}: expected an integer ≥ "
                                 f"{2 - (name == 'max_multiplicity')}")
        for name in ("smooth_band", "stick_level"):
            if getattr(self, name) >= 1.0:
                raise ValueError(f"rule.{name} = {getattr(self, name)!r}: expected < 1 (a "
                                 "fraction of the command speed)")
        if isinstance(self.growth_blocks, bool) or not isinstance(self.growth_blocks, int) \
                or self.growth_blocks <= self.growth_run:
            raise ValueError(f"rule.growth_blocks = {self.growth_blocks!r}: expected an "
                             f"integer > growth_run = {self.growth_run!r}")
        if self.max_duration < self.initial_duration:
            raise ValueError(f"rule.max_duration = {self.max_duration!r}: must not be below "
                             f"initial_duration = {self.initial_duration!r} [s]")

    def durations(self) -> list[float]:
        """Trial lengths [s] tried in turn: initial_duration doubling up to max_duration.

        Returns
        -------
        list of float
            The lengths [s].
        """
        out = [self.initial_duration]
        while out[-1] < self.max_duration * (1 - 1e-12):
            out.append(min(2.0 * out[-1], self.max_duration))
        return out

    def describe(self) -> str:
        """The rule in words, with its numbers (printed beside every verdict).

        Returns
        -------
        str
            One paragraph.
        """
        return (
            f"Limit-cycle rule. A trial runs {self.initial_duration:g} s, doubling up to "
            f"{self.max_duration:g} s "
            f"until decided. smooth: the speed stays within ±{100 * self.smooth_band:g} % of "
            f"the command for the last max({self.settle_time:g} s, 2 longest periods), and "
            f"not growing: the peak-to-peak speed of the last {self.growth_run} of "
            f"{self.growth_blocks} equal blocks of that stretch does not rise block after "
            f"block. "
            f"Limit cycle: over the last half of the trial (≥ {self.min_compare_time:g} s, the "
            f"first cycle excluded, spanning ≥ {self.min_compare_time:g} s) ≥ "
            f"{self.min_cycles} repetitions of 1 to "
            f"{self.max_multiplicity} cycles agree in highest speed, lowest speed and period "
            f"within {100 * self.cycle_tolerance:g} % and their drift is not speeding up, or "
            f"(irregular) the envelope of the last "
            f"{self.envelope_blocks} blocks of ≥ 8 cycles agrees within "
            f"{100 * self.envelope_tolerance:g} % and does not shrink by more than "
            f"{10 * self.envelope_tolerance:g} %; it is stick-slip if "
            f"the speed falls below {100 * self.stick_level:g} % of the command, oscillation "
            f"if not. Otherwise, at {self.max_duration:g} s: undecided. Frequency: 1 / mean "
            f"cycle period (command crossing to crossing) of the compared cycles; none is "
            f"given until 2 periods are seen.")

    def to_dict(self) -> dict[str, Any]:
        """The rule for JSON reports.

        Returns
        -------
        dict
            Its fields and ``description`` (:meth:`describe`).
        """
        return {**asdict(self), "description": self.describe()}


@dataclass(frozen=True)
class TraceVerdict:
    """What :func:`trace_verdict` decided about one trace (times [s], frequency [Hz]).

    ``kind``: one of :data:`~feeddrive.analysis.verdict_words.KINDS` ("undecided" on a
    finite trace means: not decided yet).
    ``ripple_ratio``, ``min_ratio`` and ``stick_fraction`` describe the compared cycles of a
    limit cycle, else the last settling stretch (smooth) or the trace's last quarter.
    ``frequency`` is None until two complete periods are seen, and for a smooth trace.
    ``decided_at``: the time at which the outcome was first decided.

    Parameters
    ----------
    kind : str
        ``"stick-slip"``, ``"oscillation"``, ``"smooth"`` or ``"undecided"``.
    frequency : float or None
        Frequency of the limit cycle [Hz].
    ripple_ratio : float
        Peak-to-peak speed over |v_cmd| [-].
    min_ratio : float
        Lowest speed along the motion over |v_cmd| [-].
    stick_fraction : float
        Fraction of the judged stretch spent below the stick level [-].
    cycles : int
        Cycles compared.
    decided_at : float or None
        When the outcome was first decided [s].
    reason : str
        Why, in words.
    """

    kind: str
    frequency: float | None
    ripple_ratio: float
    min_ratio: float
    stick_fraction: float
    cycles: int
    decided_at: float | None
    reason: str

    @property
    def creeping(self) -> bool:
        """Whether the kind is a creeping one (stick-slip or oscillation)."""
        return self.kind in CREEPING_KINDS

    @property
    def decided(self) -> bool:
        """Whether the trace was decided (any kind but ``"undecided"``)."""
        return self.kind != UNDECIDED


def _up_crossings(t: np.ndarray, u: np.ndarray, hysteresis: float) -> np.ndarray:
    """Times [s] at which u crosses 0 upward, counted once per swing from below −h to
    above +h (h = ``hysteresis``); the crossing time is interpolated linearly."""
    state = np.where(u > hysteresis, 1, np.where(u < -hysteresis, -1, 0))
    idx = np.flatnonzero(state)
    if idx.size < 2:
        return np.empty(0)
    s = state[idx]
    events = idx[1:][(s[1:] == 1) & (s[:-1] == -1)]  # first sample above +h after −h
    zero_up = np.flatnonzero((u[:-1] <= 0.0) & (u[1:] > 0.0))
    # the last upward zero crossing before each event (events with none before are dropped)
    k = np.searchsorted(zero_up, events, side="left") - 1
    i = zero_up[k[k >= 0]]
    return (t[i] + (t[i + 1] - t[i]) * (-u[i]) / (u[i + 1] - u[i])).astype(float)


def _cycle_extrema(x: np.ndarray, bounds: np.ndarray, sign: float) -> np.ndarray:
    """Largest (sign 1) or smallest (−1) value of x over each stretch x[bounds[j]:bounds[j+1]]
    (``bounds`` non-decreasing), refined by a parabola through the extreme sample — the first
    one on a plateau — and its neighbours, so the cycle-to-cycle drift is not sampling noise;
    an empty stretch gives x[bounds[j]].  All stretches at once: a 12-s trace of a 200-Hz
    mode has 2 400 cycles (a Python call per cycle and extremum cost ≈ 1 s of the literal
    readings' searches)."""
    i0, i1 = bounds[:-1], bounds[1:]
    out = np.empty(i0.size)
    full = i1 > i0
    empty = ~full
    out[empty] = x[np.minimum(i0[empty], x.size - 1)]
    if not full.any():
        return out
    # the full stretches tile x[b0:bn] (an empty one between two adds nothing)
    b0, bn = int(i0[full][0]), int(i1[full][-1])
    seg = sign * x[b0:bn]
    starts = i0[full] - b0
    best = np.maximum.reduceat(seg, starts)
    positions = np.arange(seg.size)
    lengths = (i1 - i0)[full]
    first = np.minimum.reduceat(np.where(seg == np.repeat(best, lengths), positions,
                                         seg.size), starts)
    k = first + b0
    value = x[k].astype(float)
    inner = (k > 0) & (k < x.size - 1)
    ki = k[inner]
    ym, y0, yp = x[ki - 1], x[ki], x[ki + 1]
    denom = ym - 2.0 * y0 + yp
    with np.errstate(divide="ignore", invalid="ignore"):
        value[inner] = np.where(denom * sign < 0, y0 - 0.125 * (ym - yp) ** 2 / denom, y0)
    out[full] = value
    return out


def _converging(block: np.ndarray, scale: float, mean_period: float, floor: float) -> bool:
    """Whether the drift of a repeating pattern (rows: repetitions; columns: phases; last
    axis: highest speed, lowest speed, period) slows down: the change between the means of the
    last two quarters of the repetitions is at most the change between the first two, or
    below ``floor`` (a fraction of the ripple and period).  A trajectory passing
    slowly by a vanished limit cycle drifts ever faster; an attracting cycle ever slower."""
    reps = block.shape[0]
    q = max(reps // 4, 1)
    norm = np.array([scale, scale, mean_period])
    first = np.abs(block[q:2 * q].mean(axis=0) - block[:q].mean(axis=0)) / norm
    last = np.abs(block[reps - q:].mean(axis=0) - block[reps - 2 * q:reps - q].mean(axis=0)) \
        / norm
    return bool(np.all((last <= first) | (last <= floor)))


def _repeating(cycles: np.ndarray, rule: VerdictRule) -> tuple[int, int] | None:
    """(cycles used, multiplicity) if the compared cycles repeat, else None.

    ``cycles``: rows (highest speed, lowest speed, period) per complete cycle, those of the
    compared stretch.  Periodic with multiplicity p ≤ ``rule.max_multiplicity``: ≥
    ``min_cycles`` repetitions of p cycles agree, phase by phase, within
    ``cycle_tolerance``, and their drift slows down or is below a tenth of the tolerance
    between quarters of the compared stretch (:func:`_converging`).  Otherwise an
    irregular (e.g. chaotic) oscillation counts as sustained when the envelope (highest and
    lowest speed) of ``envelope_blocks`` blocks of ≥ 8 cycles agrees within
    ``envelope_tolerance`` and the ripple does not shrink block after block by more than a
    tenth of that tolerance; multiplicity 0.
    """
    n = cycles.shape[0]
    tol = rule.cycle_tolerance
    for p in range(1, rule.max_multiplicity + 1):
        reps = n // p
        if reps < rule.min_cycles:
            break
        block = cycles[n - reps * p:].reshape(reps, p, 3)
        scale = float(np.max(block[:, :, 0] - block[:, :, 1]))  # ripple of the compared cycles
        spread = np.ptp(block, axis=0)  # per phase of the repeating pattern
        mean_period = float(np.mean(block[:, :, 2]))
        if (scale > 0.0 and np.all(spread[:, :2] <= tol * scale)
                and np.all(spread[:, 2] <= tol * mean_period)
                and _converging(block, scale, mean_period, 0.1 * tol)):
            return reps * p, p
    k = rule.envelope_blocks
    size = n // k
    if size < 8:
        return None
    blocks = cycles[n - k * size:].reshape(k, size, 3)
    high, low = blocks[:, :, 0].max(axis=1), blocks[:, :, 1].min(axis=1)
    width = high - low
    scale = float(np.max(width))
    if (scale > 0.0 and np.ptp(high) <= rule.envelope_tolerance * scale
            and np.ptp(low) <= rule.envelope_tolerance * scale
            and not (np.all(np.diff(width) < 0)
                     and width[0] - width[-1] > 0.1 * rule.envelope_tolerance * scale)):
        return k * size, 0
    return None


def growing(t: np.ndarray, u: np.ndarray, a: float, b: float, rule: VerdictRule) -> bool:
    """Whether the deviation ``u`` grows over [a, b]: the peak-to-peak of each of the last
    ``rule.growth_run`` of ``rule.growth_blocks`` equal blocks exceeds the block's before.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    u : numpy.ndarray
        Speed deviation from the command, a fraction of |v_cmd| [-].
    a, b : float
        The stretch judged [s].
    rule : VerdictRule
        ``growth_blocks`` and ``growth_run``.

    Returns
    -------
    bool
        True if the deviation rises block after block up to ``b``.
    """
    edges = np.searchsorted(t, np.linspace(a, b, rule.growth_blocks + 1))
    ptp = [float(np.ptp(u[i0:i1 + 1])) if i1 > i0 else 0.0
           for i0, i1 in zip(edges[:-1], edges[1:], strict=True)]
    return bool(np.all(np.diff(ptp[-rule.growth_run - 1:]) > 0.0))


def trace_verdict(time: object, speed: object, command_speed: float,
                  rule: VerdictRule | None = None, *, start: float | None = None
                  ) -> TraceVerdict:
    """Decide a trace: limit cycle (stick-slip or oscillation), decayed (smooth), or not yet
    decided.  The rule (:class:`VerdictRule`) does not depend on the trace's length: a
    longer trace can only turn "undecided" into a decision.

    ``start`` [s]: ignore samples before it (default: the first sample).

    Parameters
    ----------
    time : array_like
        Sample times [s].
    speed : array_like
        Table speed [m/s].
    command_speed : float
        Commanded table speed, non-zero [m/s].
    rule : VerdictRule, optional
        The rule; the protocol's default when omitted.
    start : float, optional
        Ignore samples before this time [s].

    Returns
    -------
    TraceVerdict
        The verdict.
    """
    rule = rule or VerdictRule()
    t, v = as_trace(time, speed)
    vc = check_command(command_speed)
    if start is not None:
        sel = t >= start
        if int(np.count_nonzero(sel)) < MIN_WINDOW_SAMPLES:
            raise ValueError(f"start = {start!r}: fewer than {MIN_WINDOW_SAMPLES} samples "
                             "after it")
        t, v = t[sel], v[sel]
    along = v * math.copysign(1.0, vc) / abs(vc)
    u = along - 1.0
    t_end = float(t[-1])
    ups = _up_crossings(t, u, 0.5 * rule.smooth_band)
    periods = np.diff(ups)
    longest = float(periods.max()) if periods.size else 0.0

    def describe(a: float, b: float) -> tuple[float, float, float]:
        sel = (t >= a) & (t <= b)
        seg_t, seg = t[sel], along[sel]
        if seg.size < 2:
            return 0.0, float(seg.min()) if seg.size else 1.0, 0.0
        stick = time_below(seg_t, seg, rule.stick_level) / float(seg_t[-1] - seg_t[0])
        return float(np.ptp(seg)), float(seg.min()), stick

    # -- limit cycle: the cycles of the compared stretch (the last half of the trace, at
    # least min_compare_time; never the first cycle) repeat
    compare_from = t_end - max(0.5 * (t_end - float(t[0])), rule.min_compare_time)
    first = 1 + int(np.searchsorted(ups[1:], compare_from - 1e-12))  # never the first cycle
    # … and the compared cycles span min_compare_time: an oscillation that has only just
    # grown across the hysteresis (its first few cycles agree to a fraction of a per cent
    # when a fast mode grows slowly per cycle) is not yet a limit cycle
    if ups.size - 1 - first >= rule.min_cycles \
            and float(ups[-1] - ups[first]) >= rule.min_compare_time:
        bounds = np.searchsorted(t, ups[first:])
        arr = np.column_stack([_cycle_extrema(along, bounds, 1.0),
                               _cycle_extrema(along, bounds, -1.0),
                               np.diff(ups[first:])])
        found = _repeating(arr, rule)
        if found is not None:
            used, multiplicity = found
            a, b = float(ups[-used - 1]), float(ups[-1])
            ripple, low, stick = describe(a, b)
            freq = 1.0 / float(np.mean(arr[-used:, 2]))
            if ripple < 2.0 * rule.smooth_band:
                return TraceVerdict(SMOOTH, None, ripple, low, stick, periods.size, b,
                                    f"limit cycle below ±{100 * rule.smooth_band:g} % ripple")
            kind = STICK_SLIP if low < rule.stick_level else OSCILLATION
            how = ("periodic" if multiplicity == 1 else
                   f"periodic over {multiplicity} cycles" if multiplicity > 0 else
                   "irregular, steady envelope")
            return TraceVerdict(kind, freq, ripple, low, stick, periods.size, b,
                                f"limit cycle ({how}, {used} cycles compared)")
    # -- decayed: within the band for the settling stretch
    settle = max(rule.settle_time, 2.0 * longest)
    outside = np.flatnonzero(np.abs(u) > rule.smooth_band)
    inside_from = float(t[outside[-1] + 1]) if outside.size and outside[-1] + 1 < t.size \
        else (float(t[0]) if not outside.size else math.inf)
    rising = t_end - inside_from >= settle and growing(t, u, t_end - settle, t_end, rule)
    if t_end - inside_from >= settle and not rising:
        decided_at = inside_from + settle
        ripple, low, stick = describe(inside_from, t_end)
        return TraceVerdict(SMOOTH, None, ripple, low, stick, periods.size, decided_at,
                            f"within ±{100 * rule.smooth_band:g} % of the command for ≥ "
                            f"{settle:g} s")
    a = t[0] + 0.75 * (t_end - t[0])
    ripple, low, stick = describe(a, t_end)
    seen = 1.0 / float(np.mean(periods[-rule.min_cycles:])) if periods.size >= 2 else None
    return TraceVerdict(UNDECIDED, seen, ripple, low, stick, periods.size, None,
                        "inside the band but the deviation is growing" if rising else
                        "neither a repeating cycle nor decayed yet")
