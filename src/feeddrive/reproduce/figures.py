"""Figures of the reproduction, one PNG per paper figure (engineering units)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def _save(fig: Any, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _speed_axes(ax: Any, trace: dict[str, list[float]], label: str) -> None:
    t = trace["time"]
    ax.plot(t, [1e3 * v for v in trace["table_speed"]], lw=0.8, label=label)


def fig6(data: dict[str, Any], out: Path) -> Path:
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, (key, d) in zip(axes, data.items(), strict=True):
        _speed_axes(ax, d["trace"], "table")
        ax.plot(d["trace"]["time"], [1e3 * v for v in d["trace"]["table_speed_reference"]],
                "k--", lw=0.8, label="command")
        ax.set_title(f"CDFS, v = {key} mm/s: {d['verdict']}")
        ax.set_xlabel("time [s]")
    axes[0].set_ylabel("table speed [mm/s]")
    axes[0].legend()
    return _save(fig, out / "fig6_cdfs_1p55_1p56.png")


def fig7(data: dict[str, Any], out: Path) -> Path:
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for key, trace in data["traces"].items():
        _speed_axes(axes[0], trace, f"v_n = {key}× v_crit,CDFS")
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("table speed [mm/s]")
    axes[0].set_title("DDFS at 1.55 mm/s")
    axes[0].legend(fontsize=7)
    rows = [r for r in data["rows"] if r["multiple"] > 0]
    vn = [1e3 * r["nut_speed"] for r in rows]
    axes[1].plot(vn, [100 * r["overshoot"] for r in rows], "o-", label="overshoot [%]")
    st = [r["settling_time"] if r["settling_time"] is not None else float("nan") for r in rows]
    ax2 = axes[1].twinx()
    ax2.plot(vn, st, "s--", color="C1", label="settling time [s]")
    axes[1].set_xlabel("hollow-motor speed v_n [mm/s]")
    axes[1].set_ylabel("overshoot [%]")
    ax2.set_ylabel("settling time (±5 %) [s]")
    axes[1].set_title("overshoot and settling against v_n")
    return _save(fig, out / "fig7_ddfs_nut_speed.png")


def fig8(trace: dict[str, Any], critical: dict[str, Any], out: Path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 3.6))
    _speed_axes(ax, trace, "table")
    ax.plot(trace["time"], [1e3 * v for v in trace["table_speed_reference"]], "k--", lw=0.8,
            label="command")
    c = critical["critical_speed_mm_s"]
    ax.set_title(f"DDFS, v_n = {critical['nut_speed_mm_s']:g} mm/s, at its critical speed "
                 f"{c if c is None else f'{c:.2f}'} mm/s (Fig. 8: 0.5 mm/s)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("table speed [mm/s]")
    ax.legend()
    return _save(fig, out / "fig8_ddfs_critical.png")


def figs9_10(data: dict[str, Any], out: Path) -> list[Path]:
    paths = []
    for amp, name in ((1.56, "fig9_sine_1p56"), (2.0, "fig10_sine_2")):
        fig, ax = plt.subplots(figsize=(8, 3.8))
        for key, trace in data["traces"].items():
            a, vn = key.split("/")
            if abs(float(a) - amp) < 1e-9:
                _speed_axes(ax, trace, f"v_np = {vn} mm/s")
        first = next(t for k, t in data["traces"].items() if abs(float(k.split("/")[0]) - amp)
                     < 1e-9)
        ax.plot(first["time"], [1e3 * v for v in first["table_speed_reference"]], "k--", lw=0.8,
                label="command")
        ax.set_title(f"sinusoidal table speed, amplitude {amp:g} mm/s")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("table speed [mm/s]")
        ax.legend(fontsize=7)
        paths.append(_save(fig, out / f"{name}.png"))
    return paths


def fig14(rows: list[dict[str, Any]], out: Path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4))
    pos = [1e3 * r["position"] for r in rows]

    def mm(v: float | None) -> float:
        return float("nan") if v is None else 1e3 * v

    for drive, marker, color in (("cdfs", "o", "C0"), ("ddfs", "s", "C2")):
        name = drive.upper()
        ax.plot(pos, [mm(r[drive]) for r in rows], marker + "-", color=color,
                label=f"{name} (feeddrive)")
        ax.plot(pos, [mm(r[f"{drive}_paper"]) for r in rows], marker + "--", color=color,
                alpha=0.6, label=f"{name} (Table 3, measured)")
        # out-of-range searches: a triangle at the bound they give
        below = [(p, mm(r["speed_range"][0])) for p, r in zip(pos, rows, strict=True)
                 if r[drive] is None and r[f"{drive}_status"] == "below-range"]
        if below:
            ax.plot(*zip(*below, strict=True), "v", color=color, ms=9,
                    label=f"{name} (feeddrive): smooth down to {below[0][1]:.2f} mm/s")
    ax.set_xlabel("table position x_t [mm]")
    ax.set_ylabel("critical creeping speed [mm/s]")
    ax2 = ax.twinx()
    ax2.plot(pos, [1e-6 * r["k_sa"] for r in rows], "k:", label="k_sa")
    ax2.set_ylabel("k_sa [N/µm]")
    ax.legend(fontsize=7, loc="center")
    ax.set_title("critical speed against table position (Table 3, Fig. 14)")
    return _save(fig, out / "fig14_position.png")
