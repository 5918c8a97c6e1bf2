"""Maps and Monte Carlo summaries of a stored sweep (matplotlib, Agg; mm and mm/s on axes).

* :func:`plot_map`: a heatmap of one value over two swept axes, one panel per combination of
  the other swept axes (e.g. per drive), with the **simulated creep boundary** (solid) and the
  **linear stability boundary** (dashed) drawn over it, so that where linear theory and
  simulation disagree is seen at once.  For a critical-speed sweep the two boundaries are
  contours, at the same levels, of the simulated critical speed and of the linear band's
  upper edge; for a creep-trial sweep with ``table_speed`` as an axis they are the edges of
  the creeping region and of the linearly unstable region.
* :func:`percentiles`, :func:`plot_histogram`: the distribution of a value (the critical
  speed) over a random or Latin-hypercube design, with the linear prediction beside it.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import units
from ..io.outputs import atomic_path

if TYPE_CHECKING:  # matplotlib and xarray are imported where a map is drawn (a pool worker
    import xarray as xr  # imports this package without drawing: ≈ 0.5 s each time)

__all__ = ["DEFAULT_VALUE", "percentiles", "plot_histogram", "plot_map"]

#: the value a map or histogram shows by default, per quantity
DEFAULT_VALUE = {"critical-speed": "critical_speed", "creep-trial": "ripple_ratio",
                 "linear-band": "linear_upper", "loop-margins": "damping_ratio"}
MAX_PANELS = 12
PERCENTILES = (5.0, 50.0, 95.0)


def _eng(da: xr.DataArray) -> tuple[np.ndarray, str]:
    """Values in engineering units and the unit."""
    unit = str(da.attrs.get("units", ""))
    eng, factor = units.ENGINEERING.get(unit, (unit, 1.0))
    values = np.asarray(da.values)
    if values.dtype.kind in "fiu":
        values = values.astype(float) * factor
    return values, eng


def _label(name: str, da: xr.DataArray) -> str:
    _, unit = _eng(da)
    if da.attrs.get("long_name", "").startswith("factor"):
        return f"{name} [× base]"
    return f"{name} [{unit}]" if unit not in ("", "1") else name


def _check_name(ds: xr.Dataset, name: str, what: str, where: tuple[str, ...]) -> None:
    if name not in where:
        raise ValueError(f"{what} = {name!r}: not {'an axis' if what != '--value' else 'a value'}"
                         f" of sweep {ds.attrs.get('sweep')!r}; expected one of "
                         f"{', '.join(where) or 'none'}")


def plot_map(ds: xr.Dataset, x: str, y: str, path: str | Path, *, value: str | None = None
             ) -> Path:
    """Heatmap of ``value`` over axes ``x`` and ``y`` of a grid sweep (see the module).

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep (:func:`feeddrive.sweep.export.to_dataset`), a grid design.
    x : str
        The axis along x.
    y : str
        The axis along y, another one.
    path : str or Path
        The image file.
    value : str, optional
        The variable shown; the quantity's default value otherwise.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        For a non-grid design, an unknown axis or value, or ``x == y``.
    """
    if "sample" in ds.dims:
        raise ValueError(f"sweep {ds.attrs.get('sweep')!r} is a {ds.attrs.get('design')} design: "
                         "a map needs a grid; use the histogram (no --x/--y)")
    dims = tuple(str(d) for d in ds.dims)
    _check_name(ds, x, "--x", dims)
    _check_name(ds, y, "--y", dims)
    if x == y:
        raise ValueError(f"--x = --y = {x!r}: expected two different axes")
    quantity = str(ds.attrs.get("quantity"))
    value = value or DEFAULT_VALUE.get(quantity, "")
    _check_name(ds, value, "--value", tuple(str(v) for v in ds.data_vars))
    others = [d for d in dims if d not in (x, y) and ds.sizes[d] > 1]
    combos = list(itertools.product(*[range(ds.sizes[d]) for d in others]))
    if len(combos) > MAX_PANELS:
        raise ValueError(f"{len(combos)} panels (one per value of {', '.join(others)}); at most "
                         f"{MAX_PANELS}: export the sweep and plot a subset")
    ncol = min(len(combos), 3)
    nrow = math.ceil(len(combos) / ncol)
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(5.2 * ncol, 4.2 * nrow + 0.5), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False)
    xs, _ = _eng(ds[x])
    ys, _ = _eng(ds[y])
    all_values, vunit = _eng(ds[value])
    scale = [all_values]
    if value == "critical_speed" and "linear_upper" in ds:
        scale.append(_eng(ds["linear_upper"])[0])
    finite = np.concatenate([v[np.isfinite(v)].ravel() for v in scale
                             if v.dtype.kind == "f"] or [np.array([])])
    vmin, vmax = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if vmax <= vmin:
        vmin, vmax = vmin - 0.5 * abs(vmin or 1.0), vmax + 0.5 * abs(vmax or 1.0)
    boundaries = _boundaries(ds, quantity)
    drawn: set[str] = set()  # the boundaries drawn in some panel: only those in the legend
    annotate = ds.sizes[x] * ds.sizes[y] <= 120
    for ax, combo in zip(axes.flat, combos, strict=False):
        sel = {d: i for d, i in zip(others, combo, strict=True)}
        panel = ds.isel(sel)
        z = _field(panel, value, x, y)
        ax.set_facecolor("0.85")  # cells without a finite value
        mesh = ax.pcolormesh(xs, ys, np.ma.masked_invalid(z.astype(float)), shading="nearest",
                             vmin=vmin, vmax=vmax, cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=f"{value} [{vunit}]" if vunit not in ("", "1")
                     else value)
        labelled = False
        for (name, level_source, style) in boundaries:
            if name in panel:
                # contours at the same levels are labelled once: a second set of labels
                # was drawn over the first (issue 24 item 2); with the cells annotated the
                # labels fell on the cell values, so the legend gives the levels instead
                if _contour(ax, xs, ys, _field(panel, name, x, y), level_source, style, vmin,
                            vmax, label=not (labelled or annotate)):
                    drawn.add(name)
                    labelled = labelled or level_source != "half"
        if annotate:
            _annotate(ax, panel, value, x, y, xs, ys)
        ax.set_xlabel(_label(x, ds[x]))
        ax.set_ylabel(_label(y, ds[y]))
        # a single panel is titled by the figure's title alone (it said the name twice)
        ax.set_title(", ".join(f"{d} = {_coord_text(ds[d].values[i])}"
                               for d, i in sel.items()))
    for ax in list(axes.flat)[len(combos):]:
        ax.set_visible(False)
    shown = [(n, st) for n, _, st in boundaries if n in drawn]
    if shown:
        levels = ", ".join(f"{v:.2f}" for v in np.linspace(vmin, vmax, 7)[1:-1])
        unit = f" {vunit}" if vunit not in ("", "1") else ""
        stated = False
        handles = []
        for n, style in shown:
            label = _legend(n)
            if annotate and not stated and any(s == "levels" for m, s, _ in boundaries
                                               if m == n):
                label += f"\n  levels {levels}{unit}"  # the contours carry no labels
                stated = True
            handles.append(Line2D([], [], color=style["colors"], ls=style["linestyles"],
                                  lw=1.5, label=label))
        # one entry a row, below the panels: in one row the entries ran off both sides
        fig.legend(handles=handles, loc="outside lower center", ncol=1, frameon=False,
                   fontsize=8)
    fig.suptitle(f"sweep {ds.attrs.get('sweep')}: {value}")
    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight")  # nothing cut off at the edges
    return p


def _field(panel: xr.Dataset, name: str, x: str, y: str) -> np.ndarray:
    da = panel[name]
    da = da.isel({d: 0 for d in da.dims if d not in (x, y)})
    return _eng(da.transpose(y, x))[0]


def _cell_text(panel: xr.Dataset, value: str, x: str, y: str) -> np.ndarray:
    """Per cell: the value, and for a critical speed the linear band's upper edge beneath it
    (or the search's status where there is no number: 'smooth', 'creeps', 'undecided'; "∞"
    for an infinite value, "–" for a missing one)."""
    z = _field(panel, value, x, y)
    text = np.empty(z.shape, dtype=object)
    status = _field(panel, "status", x, y) if "status" in panel else None
    error = _field(panel, "error", x, y) if "error" in panel else None
    lin = _field(panel, "linear_upper", x, y) if value == "critical_speed" and \
        "linear_upper" in panel else None
    for idx in np.ndindex(z.shape):
        v = z[idx]
        if error is not None and error[idx]:
            t = "failed"
        elif isinstance(v, float | np.floating) and np.isnan(v):
            t = {"below-range": "smooth", "above-range": "creeps",
                 "undecided": "undecided"}.get(str(status[idx]) if status is not None else "",
                                               "–")
        else:  # an infinite value (the gain margin of a loop without phase crossover) is ∞, not "–"
            t = (units.number_text(float(v), ".3g", absent="–")
                 if isinstance(v, float | np.floating) else str(v))
        if lin is not None:
            t += f"\nlin {lin[idx]:.3g}" if np.isfinite(lin[idx]) else "\nlin stable"
        text[idx] = t
    return text


def _annotate(ax: Any, panel: xr.Dataset, value: str, x: str, y: str, xs: np.ndarray,
              ys: np.ndarray) -> None:
    text = _cell_text(panel, value, x, y)
    for (i, j), t in np.ndenumerate(text):
        ax.text(xs[j], ys[i], t, ha="center", va="center", fontsize=6.5, color="k",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.6, "lw": 0})


def _coord_text(v: Any) -> str:
    if isinstance(v, float | np.floating):
        return f"{float(v):g}"
    return str(v)


def _legend(name: str) -> str:
    return {"critical_speed": "simulated creep boundary (critical speed contours)",
            "creeping": "simulated creep boundary",
            "linear_upper": "linear stability boundary (band upper edge, same levels)",
            "linear_unstable": "linear stability boundary"}[name]


def _boundaries(ds: xr.Dataset, quantity: str) -> list[tuple[str, str, dict[str, Any]]]:
    solid = {"colors": "black", "linestyles": "solid"}
    dashed = {"colors": "red", "linestyles": "dashed"}
    if quantity == "critical-speed":
        out = [("critical_speed", "levels", solid)]
        if "linear_upper" in ds:
            out.append(("linear_upper", "levels", dashed))
        return out
    if quantity == "creep-trial":
        out = [("creeping", "half", solid)]
        if "linear_unstable" in ds:
            out.append(("linear_unstable", "half", dashed))
        return out
    if quantity == "linear-band":
        return [("linear_upper", "levels", dashed)]
    return []


def _contour(ax: Any, xs: np.ndarray, ys: np.ndarray, z: np.ndarray, levels: str,
             style: dict[str, Any], vmin: float, vmax: float, label: bool = True) -> bool:
    """Draw one boundary's contours; whether any line was drawn."""
    if len(xs) < 2 or len(ys) < 2 or z.dtype.kind not in "fiu":
        return False
    z = np.ma.masked_invalid(z.astype(float))
    if z.count() < 4:
        return False
    if levels == "half":
        lv = [0.5]
    else:
        if not vmax > vmin:
            return False
        lv = list(np.linspace(vmin, vmax, 7)[1:-1])
    if z.min() > lv[-1] or z.max() < lv[0] or z.max() - z.min() < 1e-9 * max(abs(z.max()), 1):
        return False
    cs = ax.contour(xs, ys, z, levels=lv, linewidths=1.5, **style)
    if not any(len(p.vertices) for p in cs.get_paths()):
        return False
    if levels != "half" and label:
        ax.clabel(cs, fmt="%.2f", fontsize=7)
    return True


def percentiles(ds: xr.Dataset, value: str | None = None) -> dict[str, Any]:
    """Count, found and the 5/50/95 % percentiles (engineering units) of ``value``.

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep.
    value : str, optional
        The variable; the quantity's default value otherwise.

    Returns
    -------
    dict
        Value name, unit, point, finite and infinite counts, ``p5``/``p50``/``p95`` and mean
        and standard deviation of the finite values [engineering unit of the value].
    """
    value = value or DEFAULT_VALUE.get(str(ds.attrs.get("quantity")), "")
    _check_name(ds, value, "--value", tuple(str(v) for v in ds.data_vars))
    v, unit = _eng(ds[value])
    v = v.ravel()
    finite = v[np.isfinite(v)] if v.dtype.kind == "f" else v
    # an infinite value (the gain margin of a loop without phase crossover) is a bound, not
    # a gap: counted apart
    out: dict[str, Any] = {"value": value, "unit": unit, "points": int(v.size),
                           "finite": int(finite.size),
                           "infinite": int(np.isinf(v).sum()) if v.dtype.kind == "f" else 0}
    for p in PERCENTILES:
        out[f"p{p:g}"] = float(np.percentile(finite, p)) if finite.size else None
    if finite.size:
        out["mean"], out["std"] = float(finite.mean()), float(finite.std())
    return out


def plot_histogram(ds: xr.Dataset, path: str | Path, *, value: str | None = None
                   ) -> dict[str, Any]:
    """Histogram of ``value`` with its percentiles; the linear band's upper edge beside a
    critical speed.  Returns :func:`percentiles`.

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep.
    path : str or Path
        The image file.
    value : str, optional
        The variable; the quantity's default value otherwise.

    Returns
    -------
    dict
        :func:`percentiles` of the value.
    """
    stats = percentiles(ds, value)
    value = stats["value"]
    v, unit = _eng(ds[value])
    v = v.ravel()
    v = v[np.isfinite(v)]
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.5))
    ax = fig.subplots()
    bins = max(5, min(40, int(math.sqrt(max(v.size, 1))) * 2))
    ax.hist(v, bins=bins, color="tab:blue", alpha=0.75, label=f"simulated {value}")
    if value == "critical_speed" and "linear_upper" in ds:
        lin, _ = _eng(ds["linear_upper"])
        lin = lin.ravel()
        lin = lin[np.isfinite(lin)]
        if lin.size:
            ax.hist(lin, bins=bins, histtype="step", color="tab:red", lw=1.5,
                    label="linear band upper edge")
    for p in PERCENTILES:
        q = stats[f"p{p:g}"]
        if q is not None:
            ax.axvline(q, color="k", ls=":", lw=1)
            ax.text(q, ax.get_ylim()[1] * 0.95, f" P{p:g} = {q:.3g}", rotation=90,
                    va="top", fontsize=8)
    ax.set_xlabel(f"{value} [{unit}]" if unit not in ("", "1") else value)
    ax.set_ylabel("points")
    ax.set_title(f"sweep {ds.attrs.get('sweep')}: {stats['finite']} of {stats['points']} "
                 f"points with a finite {value}")
    ax.legend(loc="upper right")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    return stats
