"""Figures (matplotlib, Agg backend): engineering units on the axes."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

if TYPE_CHECKING:
    from .result import Result


def plot_result(result: Result, path: str | Path) -> Path:
    """Table speed against its command, motor speeds and friction forces of one run."""
    t = result.time
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax = axes[0]
    ax.plot(t, 1e3 * result["table_speed"], lw=0.8, label="table")
    ax.plot(t, 1e3 * result["table_speed_reference"], "k--", lw=0.8, label="command")
    ax.set_ylabel("table speed [mm/s]")
    ax.legend(loc="best")
    ax = axes[1]
    if "screw_linear_speed" in result.dataset:
        ax.plot(t, 1e3 * result["screw_linear_speed"], lw=0.8, label="screw × H")
        ax.plot(t, 1e3 * result["nut_linear_speed"], lw=0.8, label="nut × H")
        ax.set_ylabel("motor speed [mm/s]")
    else:
        ax.plot(t, result["motor_current"], lw=0.8, label="motor current")
        ax.set_ylabel("current [A]")
    ax.legend(loc="best")
    ax = axes[2]
    for name in [n for n in result.dataset.data_vars if str(n).endswith("_friction")]:
        ax.plot(t, result[str(name)], lw=0.8, label=str(name).replace("_", " "))
    ax.set_ylabel("friction [N]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="best")
    attrs = result.dataset.attrs
    fig.suptitle(f"{attrs['drive'].upper()} — {attrs['parameter_set']}")
    fig.tight_layout()
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    from .outputs import atomic_path

    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return p
