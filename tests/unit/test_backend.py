"""Issue 41 item 9: importing ``feeddrive.plots.result`` switched the user's matplotlib backend
to Agg (and five more modules did at import or plot time), so ``plt.show()`` stopped working in
Jupyter.  Every figure is now drawn on a ``matplotlib.figure.Figure``; the global backend is
never touched."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import feeddrive

SRC = Path(feeddrive.__file__).parent

# Run in a fresh interpreter: in the test process another module may have chosen a backend
# already.  "pdf" is a non-Agg backend that needs no display.  Each plotting entry point of the
# package is called once, on small data shaped as its producer makes it.
SCRIPT = r'''
import importlib, math, pkgutil, sys, types
from pathlib import Path

import matplotlib
matplotlib.use("pdf")

import numpy as np
import xarray as xr

import feeddrive as fd

out = Path(sys.argv[1])
for m in pkgutil.walk_packages(fd.__path__, "feeddrive."):
    importlib.import_module(m.name)
drawn = []


def check(what):
    backend = matplotlib.get_backend()
    if backend != "pdf":
        sys.exit(f"{what} switched the backend to {backend}")
    drawn.append(what)


check("importing every module")

params = fd.preset("wang2021")
run = fd.simulate(fd.DriveSystem(params, "cdfs", 0.4), fd.ConstantSpeed(1.5e-3), 0.05)
from feeddrive.plots.result import plot_result, result_figure
result_figure(run)
run.plot()
plot_result(run, out / "run.png")
check("plots.result")
if "matplotlib.pyplot" in sys.modules:  # (python-control, used below, imports it itself)
    sys.exit("Result.plot or plot_result imported pyplot")

from feeddrive.plots.stribeck import save_figure, stribeck_figure
save_figure(stribeck_figure(params.friction.screw, title="screw"), out / "stribeck.png")
check("plots.stribeck")

from feeddrive.analysis.linear import loop_analysis
from feeddrive.plots.linear import plot_loops
loops = loop_analysis(fd.DriveSystem(params, "cdfs", 0.4), points=40)
for kind in ("bode", "nyquist", "step"):
    plot_loops(loops, out / f"loops_{kind}.png", kind)
check("plots.linear")

from feeddrive.analysis.trace import analyze_trace
from feeddrive.plots.analysis import plot_trace
t = np.linspace(0.0, 4.0, 4001)
plot_trace(analyze_trace(t, 1.5e-3 * t + 2e-6 * np.sin(2 * np.pi * 5 * t)), out / "trace.png")
check("plots.analysis")

from feeddrive.sweep.maps import plot_histogram, plot_map
pos, gain = np.array([0.2, 0.4, 0.6]), np.array([30.0, 45.0, 60.0])
dims = ("table_position", "controller.velocity_gain")
crit = 1e-3 * (1.0 + 0.1 * np.arange(3)[:, None] + 0.2 * np.arange(3)[None, :])
ds = xr.Dataset({"critical_speed": (dims, crit, {"units": "m/s"}),
                 "linear_upper": (dims, 0.9 * crit, {"units": "m/s"}),
                 "status": (dims, np.full((3, 3), "found"))},
                coords={"table_position": (dims[0], pos, {"units": "m"}),
                        "controller.velocity_gain": (dims[1], gain, {"units": "A s/rad"})},
                attrs={"sweep": "s", "quantity": "critical-speed", "design": "grid"})
plot_map(ds, *dims, out / "map.png")
plot_histogram(ds, out / "hist.png")
check("sweep.maps")

from feeddrive.reproduce import figures as F
tr = {"time": [0.0, 0.5, 1.0, 1.5], "table_speed": [0.0, 1.4e-3, 1.6e-3, 1.55e-3],
      "table_speed_reference": [1.55e-3] * 4}
F.fig6({"1.55": {"trace": tr, "verdict": "creeping"},
        "1.56": {"trace": tr, "verdict": "smooth"}}, out)
F.fig7({"traces": {"0": tr, "1": tr, "5": tr},
        "rows": [{"multiple": k, "nut_speed": 1.56e-3 * k, "overshoot": 0.1 / k,
                  "settling_time": 2.0 / k} for k in (1, 5)]}, out)
F.fig8(tr, {"critical_speed_mm_s": 0.5, "nut_speed_mm_s": 16.0}, out)
sine = {"time": list(np.linspace(0.0, 2.0, 201)),
        "table_speed": list(1.6e-3 * np.sin(np.pi * np.linspace(0.0, 2.0, 201))),
        "table_speed_reference": list(1.56e-3 * np.sin(np.pi * np.linspace(0.0, 2.0, 201)))}
F.figs9_10({"frequency": 0.5, "traces": {"1.56/0": sine, "2/0": sine},
            "rows": [{"table_amplitude": a, "nut_amplitude": 0.0, "reversal_overshoot": 0.1}
                     for a in (1.56e-3, 2e-3)]}, out)
F.fig14([{"position": p, "cdfs": 1.5e-3, "ddfs": None, "cdfs_paper": 1.6e-3,
          "ddfs_paper": 0.5e-3, "ddfs_status": "below-range", "speed_range": [2e-5, 5e-3],
          "k_sa": 3e8} for p in (0.2, 0.4)], out)
check("reproduce.figures")

from feeddrive.analysis.sensitivity import Entry, SensitivityResult, plot_tornado
entry = Entry(path="controller.velocity_gain", value=45.0, absolute=False, step=0.1,
              q_minus=1.4e-3, q_plus=1.7e-3, elasticity=1.0, bound=0.1, resolved=True,
              halved=1.0, consistent=True, note="")
plot_tornado(SensitivityResult(parameter_set="wang2021", drive="cdfs", quantity="critical_speed",
                               base=1.56e-3, resolution=1e-5, entries=(entry,), skipped=(),
                               evaluations=3, executor="local"), out / "tornado.png")
check("analysis.sensitivity")

from feeddrive.analysis.predict import Percentile, plot_prediction
values = np.array([1.5e-3, 1.55e-3, 1.6e-3, 1.58e-3])
pred = types.SimpleNamespace(
    values=values, resolution=1e-5, samples=values.size,
    record=types.SimpleNamespace(drive="cdfs"),
    percentiles=tuple(Percentile(level=q, value=float(np.percentile(values, q)), low=1.5e-3,
                                 high=1.6e-3) for q in (5.0, 50.0, 95.0)))
plot_prediction(pred, out / "prediction.png")
check("analysis.predict")

from feeddrive.analysis.fit import plot_residuals
speed = np.full(t.size, 1.5e-3)
exp = types.SimpleNamespace(time=t, reference_time=t, table_speed=speed, source="trace.csv",
                            signals={"table_speed": speed}, noise={"table_speed": 1e-5})
fit = types.SimpleNamespace(experiments=[exp], simulated=[{"table_speed": speed * 1.01}],
                            drive="cdfs", residual_ok=True)
plot_residuals(fit, out / "residuals.png")
check("analysis.fit")

print(len(drawn), "ok", ", ".join(drawn))
'''


def test_a_non_agg_backend_stays_set_after_importing_and_plotting(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:] + done.stdout[-1000:]
    assert done.stdout.startswith("10 ok"), done.stdout
    assert len(list(tmp_path.glob("*.png"))) == 17


def _backend_calls(tree: ast.AST) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names]
            module = getattr(node, "module", None) or ""
            if "matplotlib.pyplot" in names or module == "matplotlib.pyplot" or (
                    module == "matplotlib" and "pyplot" in names):
                found.append(f"line {node.lineno}: imports pyplot")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            if node.func.attr in ("use", "switch_backend") and isinstance(
                    node.func.value, ast.Name) and node.func.value.id in ("matplotlib", "plt"):
                found.append(f"line {node.lineno}: {node.func.value.id}.{node.func.attr}()")
    return found


def test_no_module_imports_pyplot_or_sets_the_backend() -> None:
    """Every module, including code paths the script above cannot reach cheaply."""
    offenders = {str(p.relative_to(SRC)): calls for p in sorted(SRC.rglob("*.py"))
                 if (calls := _backend_calls(ast.parse(p.read_text(encoding="utf-8"))))}
    assert offenders == {}


def test_the_scan_catches_what_the_issue_saw() -> None:
    before = 'import matplotlib\n\nmatplotlib.use("Agg")\nimport matplotlib.pyplot as plt\n'
    assert len(_backend_calls(ast.parse(before))) == 2
