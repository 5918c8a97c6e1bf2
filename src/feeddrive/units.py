"""The one unit table: SI inside the package, mm, mm/s and N/µm at the edges (CLI, CSV,
Parquet, report), the names of the friction sites, and the text of a speed band in mm/s
(:func:`slope_band_text`) that the report and ``feeddrive friction`` share."""

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
