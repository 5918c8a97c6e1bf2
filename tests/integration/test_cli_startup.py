"""Issue 21 item 4: a short ``feeddrive simulate`` in a fresh process imports only its own path.

The time it takes is measured in benchmarks/bench_startup.py, never asserted here; these tests
check what the time depends on: which modules a run imports, that the entry point loads only
the running command's module yet every command stays registered and listed, and that numba's
cache loads skip the compiler's refresh without changing what a later compilation sees.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from feeddrive._jit import HAVE_NUMBA
from feeddrive.cli import COMMAND_MODULES

#: modules a short simulate must not import: none of them is on its path (each cost a fresh
#: process 0.1–0.9 s: xarray and pandas for a Dataset the summary never needs, scipy.signal
#: for a periodogram numpy computes, scipy.optimize for a root no simulation looks for)
NOT_ON_THE_SIMULATE_PATH = ("xarray", "pandas", "scipy.signal", "scipy.stats",
                            "scipy.optimize", "scipy.io", "matplotlib", "feeddrive.cli.sweep_cmd",
                            "feeddrive.cli.analyze_cmd", "feeddrive.reproduce")

# the entry point's main(), the modules loaded when the interpreter exits written to a file
_REPORT_MODULES = """
import atexit, json, sys
target = sys.argv[-1]

def _report():
    with open(target, "w") as fh:
        json.dump(sorted(sys.modules), fh)

atexit.register(_report)
sys.argv = ["feeddrive", *sys.argv[1:-1]]
from feeddrive.__main__ import main
main()
"""


def _modules_of_a_run(tmp_path: Path, *args: str) -> tuple[list[str], str]:
    """The modules loaded when ``feeddrive ARGS`` ends, and what it printed."""
    target = tmp_path / "modules.json"
    done = subprocess.run([sys.executable, "-c", _REPORT_MODULES, *args, str(target)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads(target.read_text()), done.stdout


def _loaded(modules: list[str], name: str) -> bool:
    return any(m == name or m.startswith(name + ".") for m in modules)


def test_a_short_simulate_imports_only_its_own_path(tmp_path: Path) -> None:
    modules, out = _modules_of_a_run(tmp_path, "simulate", "--drive", "cdfs", "--table-speed",
                                     "2", "--duration", "0.2", "--json")
    summary = json.loads(out)
    assert summary["verdict"] in ("smooth", "creeping")  # it ran, and judged the run
    assert "stick_slip_frequency_hz" in summary
    assert [m for m in NOT_ON_THE_SIMULATE_PATH if _loaded(modules, m)] == []
    # every other command's module stays unimported too
    own = {f"feeddrive.cli.{COMMAND_MODULES['simulate']}"}
    others = {f"feeddrive.cli.{m}" for m in COMMAND_MODULES.values()} - own
    assert sorted(others & set(modules)) == []


def test_writing_an_output_still_imports_its_writer(tmp_path: Path) -> None:
    """The lazy imports moved xarray/pandas into the writers: a .csv output gets them."""
    out_file = tmp_path / "run.csv"
    modules, _ = _modules_of_a_run(tmp_path, "simulate", "--drive", "cdfs", "--table-speed",
                                   "2", "--duration", "0.05", "--json", "--output",
                                   str(out_file))
    provenance, header = out_file.read_text().splitlines()[:2]
    assert provenance.startswith("# feeddrive") and header.startswith("time [s],")
    assert _loaded(modules, "pandas")


def _help_commands(text: str) -> list[str]:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip() == "Commands:")
    return [line.split()[0] for line in lines[start + 1:] if line.startswith("  ")
            and not line.startswith("   ")]


def test_every_command_is_registered_and_listed_in_help() -> None:
    """`feeddrive --help` (the entry point: every command module loaded) lists each command of
    COMMAND_MODULES, in its order, and nothing else; each is registered by the module named
    there (the full app, as ``from feeddrive.cli import app`` gives it)."""
    from feeddrive.cli import app

    registered = {c.name: c.callback.__module__ for c in app.registered_commands}
    for group in app.registered_groups:
        info = group.typer_instance.registered_commands[0]
        registered[group.name] = info.callback.__module__
    assert {n: m.rsplit(".", 1)[1] for n, m in registered.items()} == COMMAND_MODULES
    env = dict(os.environ, COLUMNS="120", TERM="dumb")
    shown = subprocess.run([sys.executable, "-m", "feeddrive", "--help"], env=env,
                           capture_output=True, text=True, timeout=300, check=True).stdout
    assert _help_commands(shown) == [c.name for c in app.registered_commands] + [
        g.name for g in app.registered_groups]
    assert sorted(_help_commands(shown)) == sorted(COMMAND_MODULES)


@pytest.mark.parametrize("command", sorted(COMMAND_MODULES))
def test_each_command_runs_with_only_its_module_loaded(command: str) -> None:
    """Through the entry point, a command line that starts with a command's name loads only
    that command's module (app_for): the command must then be there, with its options."""
    env = dict(os.environ, COLUMNS="120", TERM="dumb")
    done = subprocess.run([sys.executable, "-m", "feeddrive", command, "--help"], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"feeddrive {command} [OPTIONS]" in done.stdout.splitlines()[0]


def test_a_mistyped_command_is_still_named_with_a_suggestion() -> None:
    done = subprocess.run([sys.executable, "-m", "feeddrive", "simulat"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert "No such command 'simulat'. Did you mean 'simulate'?" in done.stderr


_KERNEL_MODULE = '''
from feeddrive._jit import kernel

@kernel
def scaled_sum(x, k):
    s = 0.0
    for v in x:
        s += k * v
    return s
'''

_LOAD_THEN_COMPILE = """
import sys
import numpy as np
from feeddrive._jit import start_numba
start_numba()  # the numba build (a process running C never imports numba)
import cached_kernel
value = cached_kernel.scaled_sum(np.arange(4.0), 2.0)
hits = sum(cached_kernel.scaled_sum.stats.cache_hits.values())
refreshed = "numba.typed.typeddict" in sys.modules
# a compilation after the load: numba's compiler refreshes in full (typed lists, linalg)
import numba
from numba.typed import List

@numba.njit
def uses_the_full_compiler(a):
    out = List()
    out.append(np.linalg.det(a))
    return out[0]

det = uses_the_full_compiler(np.array([[2.0, 1.0], [1.0, 3.0]]))
print(value, hits, refreshed, det)
"""


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed (the optional extra "
                    "feeddrive[numba]): this is a test of its cache; .ci/min-versions runs it")
def test_a_cache_load_skips_the_refresh_and_later_compiles_still_work(tmp_path: Path) -> None:
    """feeddrive._jit loads cached kernels without numba's refresh of its compiler (every
    lowering module imported: 0.3–0.4 s of a fresh process); the second process must load
    the kernel from disk with the right result, without that refresh, and still compile new
    code that needs the whole compiler (a typed List, np.linalg) afterwards."""
    (tmp_path / "cached_kernel.py").write_text(textwrap.dedent(_KERNEL_MODULE))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    runs = [subprocess.run([sys.executable, "-c", _LOAD_THEN_COMPILE], env=env, cwd=tmp_path,
                           capture_output=True, text=True, timeout=600)
            for _ in range(2)]
    for run in runs:
        assert run.returncode == 0, run.stderr
    first, second = (run.stdout.split() for run in runs)
    assert first[:3] == ["12.0", "0", "True"]  # compiled: the compiler refreshed
    assert second[:3] == ["12.0", "1", "False"]  # loaded from disk, no refresh
    assert float(second[3]) == pytest.approx(5.0)


#: what a `reproduce` pool worker must not import to find its job, nor the sweep package the
#: sensitivity section's runs use (the parent draws the figures and writes the report):
#: matplotlib, pandas and xarray cost each spawned worker ≈ 0.5–1 CPU s
NOT_IN_A_REPRODUCE_WORKER = ("matplotlib", "pandas", "xarray", "feeddrive.reproduce.figures",
                             "feeddrive.reproduce.report")


def test_a_reproduce_worker_imports_neither_the_figures_nor_the_report() -> None:
    """A spawned worker imports the module of its job, ``feeddrive.reproduce.runner``, and the
    sensitivity section the sweep package; the sweep's maps and exports import matplotlib,
    pandas and xarray only when they draw or export."""
    code = textwrap.dedent("""
        import json, sys
        import feeddrive.reproduce.runner
        import feeddrive.sweep
        import feeddrive.analysis.sensitivity
        print(json.dumps(sorted(sys.modules)))
    """)
    loaded = set(json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                           text=True, check=True).stdout))
    assert {"feeddrive.reproduce.runner", "feeddrive.sweep.maps",
            "feeddrive.sweep.export"} <= loaded
    assert [m for m in NOT_IN_A_REPRODUCE_WORKER if m in loaded] == []


def test_the_report_s_tables_and_indicators_import_neither_pandas_nor_scipy_optimize(
        tmp_path: Path) -> None:
    """What `reproduce`'s parent does after its studies — the CSV tables, the friction
    indicators of the report — without the two imports that cost it ≈ 0.4 CPU s (pandas for the
    tables, scipy.optimize for the negative-slope band's root search: benchmarks/README.md)."""
    code = textwrap.dedent(f"""
        import json, sys
        from pathlib import Path
        import feeddrive as fd
        from feeddrive.reproduce import report, studies
        studies.write_csv([{{"a": 1.5, "b": None}}], Path({str(tmp_path)!r}) / "t.csv")
        rows = report.indicator_rows(fd.preset("wang2021"))
        print(json.dumps([rows[0]["zero-slope speed [mm/s]"], sorted(sys.modules)]))
    """)
    zero, loaded = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                             text=True, check=True).stdout)
    assert zero == "1.605"  # docs/parameters.md's table, screw shaft +
    assert (tmp_path / "t.csv").read_text().splitlines() == ["a,b", "1.5,"]
    assert [m for m in ("pandas", "scipy.optimize") if _loaded(loaded, m)] == []


_C_BUILD_RUN = """
import sys
import feeddrive as fd
from feeddrive.analysis.linear import rightmost_pole
system = fd.DriveSystem(fd.preset("wang2021"), "ddfs", 0.4)
result = fd.simulate(system, fd.ConstantSpeed(0.5e-3, 16e-3), 0.2)
rightmost_pole(fd.DriveSystem(fd.preset("wang2021"), "cdfs", 0.4), 1e-3)
print(result.solver_stats["engine"], "numba" in sys.modules)
"""


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed: nothing to leave unimported")
def test_a_process_running_the_c_build_never_imports_numba() -> None:
    """numba installed and a compiler found: a run and a linearisation (the C build) leave
    numba unimported (its import was ≈ 0.17 CPU s of every process, issue 42); with
    ``FEEDDRIVE_ENGINE=numba`` the same code imports it and runs in it."""
    from feeddrive.backends.c_cache import CompilerNotFound, find_compiler

    try:
        find_compiler()
    except CompilerNotFound:
        pytest.skip("no C compiler: the numba build runs")
    env = {k: v for k, v in os.environ.items() if k != "FEEDDRIVE_ENGINE"}
    c_run = subprocess.run([sys.executable, "-c", _C_BUILD_RUN], env=env, capture_output=True,
                           text=True, timeout=600)
    assert c_run.returncode == 0, c_run.stderr
    assert c_run.stdout.split() == ["c", "False"]
    numba_run = subprocess.run([sys.executable, "-c", _C_BUILD_RUN],
                               env={**env, "FEEDDRIVE_ENGINE": "numba"}, capture_output=True,
                               text=True, timeout=900)
    assert numba_run.returncode == 0, numba_run.stderr
    assert numba_run.stdout.split() == ["numba", "True"]
