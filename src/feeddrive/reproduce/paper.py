"""Wang2021's numbers that results are set beside — one home, each with its source.

Z. Wang, X. Feng, H. Yang, H. Jin, Mech. Sci. 12, 791–800 (2021).  SI units.
"""

from __future__ import annotations

from typing import Any

CDFS_CRITICAL_SPEED = 1.56e-3  # m/s, Sect. 5.2, Fig. 6 (creeps at 1.55, smooth at 1.56)

PAPER: dict[str, Any] = {
    "cdfs_critical_sim": CDFS_CRITICAL_SPEED,  # Sect. 5.2, Fig. 6
    "ddfs_critical_sim": 0.5e-3,  # Fig. 8 (v_s = 16.5, v_n = 16 mm/s)
    "ddfs_sim_nut_speed": 16e-3,
    "cdfs_critical_measured_mid": 1.66e-3,  # Sect. 6, Fig. 13
    "ddfs_critical_measured_mid": 0.52e-3,  # Sect. 6, Fig. 13 (v_n = 20 mm/s)
    "experiment_nut_speed": 20e-3,
    "positions": (0.2, 0.3, 0.4, 0.5, 0.6),  # Table 3
    "k_sa": (276.13e6, 220.9e6, 207.1e6, 220.9e6, 276.13e6),  # Table 3 [N/m]
    "cdfs_table3": (1.21e-3, 1.58e-3, 1.66e-3, 1.59e-3, 1.23e-3),
    "ddfs_table3": (0.35e-3, 0.47e-3, 0.52e-3, 0.46e-3, 0.36e-3),
    "k_eq_mid": 2.16e7,  # Sect. 5.2
    "fig7_rule_multiple": 10.0,  # Sect. 5.2: v_n ≥ 10× the CDFS critical speed
    "fig6b_settling": 7.0,  # [s] Sect. 5.2, Fig. 6b: stable at 1.56 mm/s after about 7 s
}
