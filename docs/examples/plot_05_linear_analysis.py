"""
Linear analysis: poles, loop margins and the unstable band of steady sliding
=============================================================================

Linearised at steady sliding, the closed loop tells without a time simulation where creep can
start: the speeds at which sliding is linearly unstable (a pole with positive real part)
and the frequency of that mode, next to the loop margins of the servo
(docs: ``docs/linear.md``; CLI: ``feeddrive loops`` and ``feeddrive stability``).
"""

import matplotlib.pyplot as plt
import numpy as np

import feeddrive as fd
from feeddrive.analysis.linear import loop_analysis, margin_text, stability_band

system = fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4)

loops = loop_analysis(system, table_speed=1e-3)
mode = loops.dominant()
print(f"least-damped mode: {mode.frequency_hz:.2f} Hz, damping ratio {mode.damping_ratio:.3f}")

# margin_text prints a value as `feeddrive loops` does: a gain margin the loop has not (its
# phase never crosses −180°) is infinite, "∞"; any other value it has not (no gain crossover:
# no crossover frequency, no phase margin) is "—"
for loop in loops.loops:
    gain = margin_text("gain_margin_db", loop.gain_margin_db, ".1f", "dB")
    phase = margin_text("phase_margin_deg", loop.phase_margin_deg, ".1f", "deg")
    crossover = margin_text("crossover_hz", loop.crossover_hz, ".1f", "Hz")
    print(f"{loop.name}: gain margin {gain}, phase margin {phase}, crossover {crossover}")

band = stability_band(system, low=0.05e-3, high=3e-3, points=24)
for (lower, upper), freq in zip(band.intervals, band.mode_frequency_hz, strict=True):
    print(f"steady sliding unstable from {1e3 * lower:.3f} to {1e3 * upper:.3f} mm/s "
          f"(mode {freq:.2f} Hz)")

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
ax1.semilogx(1e3 * band.speeds, band.max_real_part, ".-")
ax1.axhline(0.0, color="k", lw=0.8)
for lower, upper in band.intervals:
    ax1.axvspan(1e3 * lower, 1e3 * upper, color="C3", alpha=0.15)
ax1.set_xlabel("table speed [mm/s]")
ax1.set_ylabel("rightmost pole, real part [1/s]")
ax1.set_title("unstable band (shaded)")
poles = loops.linear.poles()
ax2.plot(poles.real, poles.imag / (2 * np.pi), "x")
ax2.set_xlim(-200, 20)
ax2.set_ylim(-30, 30)
ax2.axvline(0.0, color="k", lw=0.8)
ax2.set_xlabel("real part [1/s]")
ax2.set_ylabel("imaginary part / 2π [Hz]")
ax2.set_title("poles at 1 mm/s, frictionless loop")
plt.show()
