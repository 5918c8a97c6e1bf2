"""The one unit table: SI inside the package, mm, mm/s and N/µm at the edges (CLI, CSV,
Parquet, report), the names of the friction sites, the text of a speed band in mm/s
(:func:`slope_band_text`) that the report and ``feeddrive friction`` share, and the text of a
number that may be infinite or missing (:func:`number_text`, :func:`absent_value`)."""

from __future__ import annotations

import math

MM = 1e-3  # m per mm
MM_PER_S = 1e-3  # m/s per mm/s
UM = 1e-6  # m per µm
N_PER_UM = 1e6  # N/m per N/µm

#: the largest speed any input may have [m/s]: no feed drive is faster, so a larger one is
#: a wrong unit or a damaged file (measured data, CLI speeds; issue 39 items 4 and 5)
LARGEST_SPEED = 100.0

# SI unit → (engineering unit, factor) for exports and printing
ENGINEERING = {"m": ("mm", 1e3), "m/s": ("mm/s", 1e3), "N/m": ("N/µm", 1e-6)}

# SI unit → the units a tool may display it in, the first its default (display value =
# factor × SI value): the engineering units above, µm for small lengths (following error,
# resolutions), rpm for motor speeds
DISPLAY_UNITS: dict[str, tuple[tuple[str, float], ...]] = {
    "m": (ENGINEERING["m"], ("µm", 1e6)), "m/s": (ENGINEERING["m/s"],),
    "N/m": (ENGINEERING["N/m"],), "rad/s": (("rpm", 60.0 / (2.0 * math.pi)),)}

# the friction sites of Wang2021 Sect. 4 (Table 1), in the parameter file's order
SITES = ("screw", "nut", "guide")


def slope_band_text(lower_mm_s: float, upper_mm_s: float | None) -> str:
    """A negative-slope band as the report and ``feeddrive friction`` print it [mm/s]:
    ``"0.123 … 4.567"``, or ``"0.000 … ∞ (σ2 = 0)"`` for a band without end (no viscous
    friction: the steady curve falls at every speed).

    Parameters
    ----------
    lower_mm_s : float
        The lower edge [mm/s].
    upper_mm_s : float or None
        The upper edge, the zero-slope speed [mm/s]; None when the band has no end.

    Returns
    -------
    str
        The band's text.
    """
    end = "∞ (σ2 = 0)" if upper_mm_s is None else f"{upper_mm_s:.3f}"
    return f"{lower_mm_s:.3f} … {end}"


#: values whose absence is a bound, not a gap: ``…gain_margin_db`` of a loop whose phase does
#: not cross −180° above its gain crossover (``loop_analysis``: 0.5–500 Hz; the wang2021 screw
#: velocity loop has none up to 50 kHz either) — an infinite gain margin, as python-control's
#: ``stability_margins`` gives it; ``feeddrive loops`` prints "∞ dB" (JSON null, as the sweep
#: store keeps it)
INFINITE_WHEN_ABSENT = ("gain_margin_db",)


def absent_value(name: str) -> float:
    """The number a value the computation did not find stands for: +inf for a gain margin
    (:data:`INFINITE_WHEN_ABSENT`: the loop has none), NaN otherwise (no such value at the point:
    a loop without a gain crossover has no crossover frequency, phase margin or bandwidth; a
    search without a critical speed).

    Parameters
    ----------
    name : str
        The value's name (``screw_velocity_loop_gain_margin_db``, ``crossover_hz``).

    Returns
    -------
    float
        ``math.inf`` or ``math.nan``.
    """
    return math.inf if name.endswith(INFINITE_WHEN_ABSENT) else math.nan


def number_text(value: float | None, spec: str = ".3g", unit: str = "", *,
                absent: str = "—") -> str:
    """A number as the text outputs print it: ``∞`` (``−∞``) for an infinite value — a bound,
    e.g. a loop's gain margin without a phase crossover (:func:`absent_value`) — and
    ``absent`` for None or NaN, a value that does not exist (no crossover, no critical speed).

    Parameters
    ----------
    value : float or None
        The number [in ``unit``, any].
    spec : str, default ".3g"
        Its format specification.
    unit : str, default ""
        Printed after a number or ∞, one space apart; not after ``absent``.
    absent : str, default "—"
        The text of a missing value (the sweep map's cells use "–").

    Returns
    -------
    str
        The text.

    Examples
    --------
    >>> number_text(float("inf"), ".2f", "dB"), number_text(None, ".2f", "dB")
    ('∞ dB', '—')
    >>> number_text(float("nan"), absent="–"), number_text(-math.inf), number_text(2.5891)
    ('–', '−∞', '2.59')
    """
    if value is None or math.isnan(value):
        return absent
    text = format(value, spec) if math.isfinite(value) else ("∞" if value > 0 else "−∞")
    return f"{text} {unit}" if unit else text
