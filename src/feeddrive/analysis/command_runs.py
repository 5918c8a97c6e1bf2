"""The segments a command column defines (:func:`feeddrive.analysis.trace.analyze_trace`):
each run of one command speed that lasts ``min_segment_time`` is a segment.  What is left out
is said in terms a user finds in the record: the spans where the command keeps changing (a
ramp between levels) and the holds too short to judge, each counted with its duration and the
option that sets the shortest segment.  A simulated constant-speed run's 0.1-s ramp at 1 kHz
was "99 shorter than 1 s skipped": one sample per run of its changing command (session 27).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: a command held for fewer samples than this is a step of a changing command (a ramp), not
#: a hold: the fewest samples the creep metrics judge (``analyze_trace``'s segment minimum)
HOLD_SAMPLES = 16


@dataclass(frozen=True)
class CommandRun:
    """One run of equal command speed.

    Parameters
    ----------
    start : float
        Its first sample [s].
    end : float
        Its last sample [s].
    command : float
        The command speed [m/s].
    samples : int
        Its samples [-].
    """
    start: float  # [s]
    end: float  # [s]
    command: float  # [m/s]
    samples: int


def run_bounds(command: np.ndarray, atol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) index of each run of equal command speed: a sample starts a
    new run where it differs from the one before by more than ``atol`` + 1e-6 of itself.

    Parameters
    ----------
    command : numpy.ndarray
        Command speed per sample [m/s].
    atol : float, default 1e-9
        The absolute part of the tolerance [m/s] (a recorded column's; a simulated
        reference's is 1e-12).

    Returns
    -------
    tuple of numpy.ndarray
        The runs' first indices and their ends (one past the last index).
    """
    change = np.flatnonzero(np.abs(np.diff(command)) > atol + 1e-6 * np.abs(command[1:]))
    return np.r_[0, change + 1], np.r_[change + 1, command.size]


def command_runs(time: np.ndarray, command: np.ndarray) -> list[CommandRun]:
    """The runs of equal command speed (within 1e-9 m/s and 1e-6 of the command), in order.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times [s].
    command : numpy.ndarray
        Command speed per sample [m/s].

    Returns
    -------
    list of CommandRun
        The runs, covering every sample once.
    """
    starts, ends = run_bounds(command)
    return [CommandRun(float(time[a]), float(time[b - 1]), float(command[a]), int(b - a))
            for a, b in zip(starts, ends, strict=True)]


@dataclass(frozen=True)
class ColumnSegments:
    """A command column's segments and what it leaves out.

    Parameters
    ----------
    kept : list of CommandRun
        The runs lasting ``min_segment_time`` or more: the segments.
    changing : list of list of CommandRun
        The spans where the command keeps changing (consecutive runs of fewer than
        :data:`HOLD_SAMPLES` samples each).
    holds : list of CommandRun
        The holds of :data:`HOLD_SAMPLES` samples or more but shorter than
        ``min_segment_time``.
    sample_time : float
        The record's sample interval [s] (durations count samples).
    min_segment_time : float
        The shortest segment [s].
    """
    kept: list[CommandRun]
    changing: list[list[CommandRun]]
    holds: list[CommandRun]
    sample_time: float
    min_segment_time: float

    def head(self) -> str:
        """The note on the segments: the one run's speed and span, or how many.

        Returns
        -------
        str
            One line.
        """
        if len(self.kept) == 1:
            r = self.kept[0]
            return (f"segments: one run of constant command speed, {1e3 * r.command:.4g} mm/s "
                    f"over {r.start:.2f}–{r.end:.2f} s")
        if not self.kept:
            return (f"segments: none, no run of constant command speed lasts --min-segment "
                    f"{self.min_segment_time:g} s")
        return f"segments: {len(self.kept)} runs of constant command speed"

    def left_out(self) -> str | None:
        """What the segments leave out, or None when nothing is.

        Returns
        -------
        str or None
            E.g. ``left out, as no command is held there for --min-segment 1 s: 0.00–0.10 s,
            where the command keeps changing (0.01 → 0.99 mm/s)``.
        """
        parts = self.left_out_parts()
        if not parts:
            return None
        return (f"left out, as no command is held there for --min-segment "
                f"{self.min_segment_time:g} s: {'; '.join(parts)}")

    def left_out_parts(self) -> list[str]:
        """The spans of changing command and the short holds, each kind described once
        (where it is, or how many and how long in all).

        Returns
        -------
        list of str
            Nothing when nothing is left out.
        """
        parts = []
        if len(self.changing) == 1:
            span = self.changing[0]
            parts.append(f"{span[0].start:.2f}–{span[-1].end:.2f} s, where the command keeps "
                         f"changing ({1e3 * span[0].command:.4g} → "
                         f"{1e3 * span[-1].command:.4g} mm/s)")
        elif self.changing:
            total = sum(r.samples for span in self.changing for r in span) * self.sample_time
            parts.append(f"{len(self.changing)} spans where the command keeps changing "
                         f"({total:.3g} s in all)")
        if len(self.holds) == 1:
            r = self.holds[0]
            parts.append(f"a {r.samples * self.sample_time:.3g}-s hold at "
                         f"{1e3 * r.command:.4g} mm/s ({r.start:.2f}–{r.end:.2f} s)")
        elif self.holds:
            lengths = [r.samples * self.sample_time for r in self.holds]
            parts.append(f"{len(self.holds)} holds of constant command ({sum(lengths):.3g} s "
                         f"in all, the longest {max(lengths):.3g} s)")
        return parts


def column_segments(time: np.ndarray, command: np.ndarray,
                    min_segment_time: float) -> ColumnSegments:
    """Sort a command column's runs into segments, spans of changing command and short holds;
    runs at zero command (rests) are in none.

    Parameters
    ----------
    time : numpy.ndarray
        Sample times on a uniform grid [s].
    command : numpy.ndarray
        Command speed per sample [m/s].
    min_segment_time : float
        The shortest segment [s].

    Returns
    -------
    ColumnSegments
        The segments and what is left out.
    """
    kept: list[CommandRun] = []
    changing: list[list[CommandRun]] = []
    holds: list[CommandRun] = []
    span: list[CommandRun] = []
    for r in command_runs(time, command):
        if r.command != 0.0 and r.end - r.start < min_segment_time \
                and r.samples < HOLD_SAMPLES:
            span.append(r)
            continue
        if span:
            changing.append(span)
            span = []
        if r.command == 0.0:
            continue
        (kept if r.end - r.start >= min_segment_time else holds).append(r)
    if span:
        changing.append(span)
    dt = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    return ColumnSegments(kept, changing, holds, dt, min_segment_time)
