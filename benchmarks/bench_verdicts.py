"""Benchmark (issue 21): creep verdicts of the default integrator against a tight reference.

Run from the repository root::

    python benchmarks/bench_verdicts.py [--only NAME,...] [--reference-only]

Each trial of :data:`CORPUS` is judged twice by the same verdict rule
(:class:`feeddrive.analysis.cycle_verdict.VerdictRule`, the protocol's 12 s doubling to 240 s until
decided, :func:`feeddrive.analysis.critical.decide`):

* **reference**: scipy ``solve_ivp(method="Radau", rtol=1e-10)`` on the plain-Python model
  ``reference/scipy_model.ReferenceModel`` with absolute tolerances 1000× tighter than the
  engine's defaults, split at the end of the start ramp, its analytic Jacobian — the settings
  of ``reference/make_radau_reference.py``; a longer trial continues the shorter one from its
  last state.  Readings with sampled loops: ``reference/sampled.py`` (DOP853 at rtol 1e-10
  between the sample instants, the held outputs updated at each; the same absolute
  tolerances), each longer trial from rest;
* **engine**: :func:`feeddrive.analysis.critical.creep_trial` with the default
  ``SolverOptions()`` (and, for comparison, ``auto`` and ``dopri5``).

The corpus (89 trials): the ``wang2021`` CDFS at mid-screw on both sides of every band edge and
of the critical speed that ``feeddrive reproduce`` reports (0.17–0.21, 1.41/1.42, 1.55–1.57
mm/s), Table 3's positions at their critical speeds, the DDFS with v_n = 16 mm/s, the
``wang2021-literal`` CDFS (0.2 mm/s: the growing table mode; 0.02–0.06 where the band starts)
and DDFS, both sides of every critical speed of the model-reading study (velocity integral
0.5–1.5×, table feedback, the paper's K_eq, damping × 4, the sampled 1-kHz loops, the ball–nut
shares 1 and 0.5), the trials where that study's band lists moved with the default method,
and stress variants with the screw bristle stiffness σ0 × 10 and × 100.

The reference verdicts are kept in ``benchmarks/results/bench_verdicts_reference*.json`` (they
do not depend on the engine; delete the file to recompute them).  Writes
``benchmarks/results/bench_verdicts.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from reference.scipy_model import ReferenceModel  # noqa: E402

import feeddrive as fd  # noqa: E402
from feeddrive.analysis.critical import creep_trial, decide  # noqa: E402
from feeddrive.analysis.cycle_verdict import VerdictRule, trace_verdict  # noqa: E402
from feeddrive.engine.simulate import DriveSystem, SolverOptions  # noqa: E402
from feeddrive.model.reference import ConstantSpeed  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "bench_verdicts.json"
REFERENCE = ROOT / "benchmarks" / "results" / "bench_verdicts_reference.json"
TRACES = ROOT / "benchmarks" / "results" / "verdict_traces"
RTOL = 1e-10
#: the kind of reference kept: the growth-checked verdict rule on the step-capped Radau run
RULE = "growth-checked, step-capped"
CHUNK = 0.05  # [s] the reference's step cap is evaluated at the start of each such stretch
ZETA_REF = 0.02  # oscillatory modes below this damping ratio are resolved (step_cap)
H_LAMBDA_REF = 0.25  # … to h·|λ| ≤ this (Radau IIA's numerical damping ratio 1.1e-7)
ATOL_SCALE = 1e-3
RAMP = 0.1  # [s] the creep trials' start ramp


def step_cap(jac: np.ndarray) -> float:
    """The reference's step cap [s]: ``H_LAMBDA_REF``/max|λ| over the eigenvalues λ of the
    Jacobian with Im λ ≠ 0 and damping ratio −Re λ/|λ| < ``ZETA_REF`` (inf if none).

    Radau IIA is L-stable: on a step h|λ| ≫ 1 it damps an oscillatory mode that its error
    estimate does not see — one whose amplitude is below the absolute tolerance, such as a
    mode growing from the start transient's seed.  Its amplification on the imaginary axis,
    R(iy) = (1 + 2iy/5 − y²/20)/(1 − 3iy/5 − 3y²/20 + iy³/60), gives a numerical damping
    ratio −ln|R(iy)|/y of 1.1e-7 at y = 0.25, 1.3e-4 at 1, 0.045 at 4 and 0.11 at 8 (the
    uncapped steps of the literal CDFS at 0.06 mm/s: ≈ 18 ms, h|λ| ≈ 23 on its 202-Hz table
    mode, whose damping ratio is −7.3e-4: a growing mode, damped away).  Capped,
    the numerical damping is ≤ 1.5e-4 of the smallest |ζ| in the corpus."""
    ev = np.linalg.eigvals(jac)
    a = np.abs(ev)
    light = (ev.imag != 0.0) & (a > 0.0)
    light[light] = -ev.real[light] / a[light] < ZETA_REF
    return H_LAMBDA_REF / float(a[light].max()) if np.any(light) else math.inf


def _readings() -> dict[str, dict[str, Any]]:
    """Model readings of ``reproduce``'s model-reading study with a continuous-loop critical
    speed (feeddrive.reproduce.reading_study.variants), by a short name: the changes to
    ``wang2021``."""
    ship = fd.preset("wang2021")
    kvi = ship.controller.velocity_integral_gain
    out: dict[str, dict[str, Any]] = {
        f"vi{f:g}": {"controller.velocity_integral_gain": f * kvi}
        for f in (0.5, 0.6, 0.7, 0.8, 0.9, 1.5)}
    out["vfb-table"] = {"controller.velocity_feedback": "table"}
    out["keq-paper"] = {"stiffness.equivalent_stiffness": 2.16e7}
    out["damping4"] = {"stiffness.axial_damping": 4 * ship.stiffness.axial_damping}
    out["nut-position-loop"] = {"controller.nut_loop": "position"}
    out["sampled-1khz"] = {"controller.position_period": 1e-3,
                           "controller.velocity_period": 1e-3,
                           "controller.encoder_counts": 10000.0,
                           "controller.grating_resolution": 1e-7}
    return out


def _variant(name: str) -> fd.DriveParameters:
    name, _, reading = name.partition("~")
    name, _, share = name.partition("+share")
    base, _, factor = name.partition("*sigma0x")
    p = fd.preset(base)
    for path, value in (_readings()[reading] if reading else {}).items():
        p = p.replace_path(path, value)
    if share:
        p = p.replace_path("friction.ball_nut_share", float(share))
    if factor:
        p = p.replace_path("friction.screw.bristle_stiffness",
                           float(factor) * p.friction.screw.bristle_stiffness)
    return p


def _corpus() -> list[tuple[str, str, float, float, float]]:
    """(preset[*sigma0xN], drive, table position [m], table speed [mm/s], nut speed [mm/s])."""
    out = []
    for v in (0.17, 0.18, 0.20, 0.21, 0.5, 1.0, 1.41, 1.42, 1.55, 1.56, 1.57, 2.0, 3.0):
        out.append(("wang2021", "cdfs", 0.4, v, 0.0))
    for a in (0.2, 0.3, 0.5, 0.6):
        for v in (1.0, 1.5, 1.6, 1.7):
            out.append(("wang2021", "cdfs", a, v, 0.0))
    for a in (0.2, 0.6):  # Table 3's critical speed, 1.56 mm/s at every position
        for v in (1.55, 1.56):
            out.append(("wang2021", "cdfs", a, v, 0.0))
    for v in (0.02, 0.5, 1.0, 1.55):
        out.append(("wang2021", "ddfs", 0.4, v, 16.0))
    for v in (0.2, 0.5, 1.0, 3.0):
        out.append(("wang2021-literal", "cdfs", 0.4, v, 0.0))
    out.append(("wang2021-literal", "ddfs", 0.4, 0.5, 16.0))
    # where `reproduce`'s model-reading study moved with the default method (issue 21):
    # literal CDFS 0.02/0.03 (dopri5 smooth, modal stick-slip), literal DDFS band edges,
    # ball-nut share 0.2 DDFS at 0.48 (dopri5 undecided, modal smooth)
    for v in (0.02, 0.03, 0.04, 0.05, 0.06):  # modal: the band from 0.06 (dopri5: 0.04)
        out.append(("wang2021-literal", "cdfs", 0.4, v, 0.0))
    for v in (0.15, 1.82, 2.02, 3.02):
        out.append(("wang2021-literal", "ddfs", 0.4, v, 16.0))
    out.append(("wang2021+share0.2", "ddfs", 0.4, 0.48, 16.0))
    # both sides of every continuous-loop critical speed of the model-reading study (the
    # last creeping and the first smooth speed of reproduce's 0.01-mm/s search)
    for reading, drive, crit, vn in (("vi0.5", "cdfs", 1.24, 0.0), ("vi0.6", "cdfs", 1.29, 0.0),
                                     ("vi0.7", "cdfs", 1.35, 0.0), ("vi0.8", "cdfs", 1.42, 0.0),
                                     ("vi0.9", "cdfs", 1.48, 0.0), ("vi1.5", "cdfs", 1.98, 0.0),
                                     ("vfb-table", "cdfs", 1.54, 0.0),
                                     ("keq-paper", "cdfs", 1.56, 0.0),
                                     ("damping4", "cdfs", 1.56, 0.0),
                                     ("sampled-1khz", "cdfs", 2.21, 0.0),
                                     ("sampled-1khz", "ddfs", 1.75, 16.0)):
        for v in (round(crit - 0.01, 2), crit):
            out.append((f"wang2021~{reading}", drive, 0.4, v, vn))
    # the sampled 1-kHz DDFS's upper band: from 0.94 under modal, from 1.07 under dopri5
    for v in (0.93, 0.94, 1.06, 1.07):
        out.append(("wang2021~sampled-1khz", "ddfs", 0.4, v, 16.0))
    # the hollow motor on a position loop too: no critical speed (undecided at 2.02); the top
    # of its oscillation band
    out.append(("wang2021~nut-position-loop", "ddfs", 0.4, 1.82, 16.0))
    for share, crit in (("1", 1.98), ("0.5", 1.55)):  # the ball–nut share DDFS readings
        for v in (round(crit - 0.01, 2), crit):
            out.append((f"wang2021+share{share}", "ddfs", 0.4, v, 16.0))
    for f in ("10", "100"):
        out.append((f"wang2021*sigma0x{f}", "ddfs", 0.4, 0.5, 16.0))
        out.append((f"wang2021*sigma0x{f}", "cdfs", 0.4, 1.2, 0.0))
        out.append((f"wang2021*sigma0x{f}", "cdfs", 0.4, 2.0, 0.0))
    return out


CORPUS = _corpus()


def key(case: tuple[str, str, float, float, float]) -> str:
    preset, drive, a, v, vn = case
    return f"{preset}/{drive}/a{a:g}/v{v:g}/vn{vn:g}"


def _keep_trace(case: tuple[str, str, float, float, float], t: np.ndarray,
                speed: np.ndarray) -> None:
    """Keep a reference trial's table-speed trace (``TRACES``, not committed: 1-2 MB a
    trial), so a verdict can be judged again without integrating again."""
    TRACES.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(TRACES / (key(case).replace("/", "_") + ".npz"), time=t, speed=speed)


def rejudge(case: tuple[str, str, float, float, float]) -> dict[str, Any] | None:
    """The current rule's verdict on a kept reference trace (``TRACES``), trial length by
    trial length as :func:`~feeddrive.analysis.critical.decide` runs them; None if there is
    no trace or the rule is still undecided at its end short of the maximum (a longer run is
    needed)."""
    path = TRACES / (key(case).replace("/", "_") + ".npz")
    if not path.exists():
        return None
    kept = np.load(path)
    t, speed = kept["time"], kept["speed"]
    v = case[3] * 1e-3
    rule = VerdictRule()
    for duration in rule.durations():
        if duration > t[-1] + 1e-9:
            return None
        sel = t <= duration + 1e-9
        verdict = trace_verdict(t[sel], speed[sel], v, rule)
        if verdict.decided or duration >= rule.max_duration:
            return {"kind": verdict.kind, "ripple_ratio": verdict.ripple_ratio,
                    "duration_s": duration, "decided_at_s": verdict.decided_at}
    return None


def sampled_reference_trial(case: tuple[str, str, float, float, float]) -> dict[str, Any]:
    """The reference of a trial with sampled loops: ``reference/sampled.py`` (the plant by
    DOP853 at rtol 1e-10 between sample instants, the held outputs updated at each, as
    tests/validation/test_reference_sampled.py checks the engine against), absolute
    tolerances 1000× the engine's; each longer trial runs again from rest (the held values
    are not carried over)."""
    from reference.sampled import simulate_sampled
    preset, drive, a, v, vn = case
    profile = ConstantSpeed(v * 1e-3, vn * 1e-3, ramp_time=RAMP)
    model = ReferenceModel(_variant(preset), drive, a, profile)
    v_t = model.state_names.index("table_speed")
    atol = model.tolerances() * ATOL_SCALE

    runs: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def run(duration: float) -> tuple[np.ndarray, np.ndarray]:
        if duration not in runs:
            t, y, _ = simulate_sampled(model, duration, rtol=RTOL, atol=atol)
            runs[duration] = (t, y[:, v_t])
        return runs[duration]

    started = time.process_time()
    verdict, duration = decide(run, v * 1e-3)
    _keep_trace(case, *run(duration))
    return {"kind": verdict.kind, "ripple_ratio": verdict.ripple_ratio, "duration_s": duration,
            "decided_at_s": verdict.decided_at, "cpu_s": time.process_time() - started,
            "method": "DOP853 between sample instants", "rule": RULE}


def reference_trial(case: tuple[str, str, float, float, float]) -> dict[str, Any]:
    preset, drive, a, v, vn = case
    params = _variant(preset)
    c = params.controller
    if c.position_period > 0 or c.velocity_period > 0 or c.current_period > 0:
        return sampled_reference_trial(case)
    profile = ConstantSpeed(v * 1e-3, vn * 1e-3, ramp_time=RAMP)
    model = ReferenceModel(params, drive, a, profile)
    atol = model.tolerances() * ATOL_SCALE  # per state (= tolerances(H) for 15 states)
    v_t = model.state_names.index("table_speed")
    # the model's own state count: a ball–nut share 0 < f < 1 adds a bristle state
    state: dict[str, Any] = {"t": 0.0, "y": np.zeros(model.n_state), "time": [np.zeros(1)],
                             "speed": [np.zeros(1)], "nfev": 0, "steps": 0, "capped": 0,
                             "min_cap": math.inf, "h": 1e-6}

    def run(duration: float) -> tuple[np.ndarray, np.ndarray]:
        while state["t"] < duration - 1e-12:
            a0 = state["t"]
            # on the 1-ms grid: the ramp's end, then chunks of CHUNK
            n0 = int(round(a0 * 1e3))
            n1 = min(int(round((RAMP if a0 < RAMP else duration) * 1e3)),
                     n0 + int(round(CHUNK * 1e3)))
            b = n1 * 1e-3
            grid = np.arange(n0 + 1, n1 + 1) * 1e-3
            cap = step_cap(model.jacobian(a0, state["y"]))
            state["capped"] += math.isfinite(cap)
            state["min_cap"] = min(state["min_cap"], cap)
            sol = solve_ivp(model, (a0, b), state["y"], method="Radau", rtol=RTOL, atol=atol,
                            jac=model.jacobian, t_eval=grid, dense_output=True,
                            max_step=cap, first_step=min(state["h"], cap, b - a0))
            if sol.status != 0:
                raise RuntimeError(f"{key(case)}: Radau failed at {sol.t[-1]:g} s")
            state["time"].append(sol.t)
            state["speed"].append(sol.y[v_t])
            state["y"] = sol.sol(b)
            state["t"] = b
            state["nfev"] += int(sol.nfev)
            steps = np.diff(sol.sol.ts)
            state["steps"] += steps.size
            # the last full step (the chunk's end cuts the final one short)
            state["h"] = float(steps[-2] if steps.size > 1 else steps[-1])
        t = np.concatenate(state["time"])
        s = np.concatenate(state["speed"])
        keep = t <= duration + 1e-9
        return t[keep], s[keep]

    started = time.process_time()
    verdict, duration = decide(run, v * 1e-3)
    _keep_trace(case, *run(duration))
    return {"kind": verdict.kind, "ripple_ratio": verdict.ripple_ratio, "duration_s": duration,
            "decided_at_s": verdict.decided_at, "cpu_s": time.process_time() - started,
            "rhs_calls": state["nfev"], "steps": state["steps"],
            "capped_chunks": state["capped"], "chunks": int(round(duration / CHUNK)),
            "min_step_cap_s": state["min_cap"] if math.isfinite(state["min_cap"]) else None,
            "rule": RULE}


def engine_trial(case: tuple[str, str, float, float, float], method: str | None,
                 rosenbrock: str | None = None) -> dict[str, Any]:
    preset, drive, a, v, vn = case
    system = DriveSystem(_variant(preset), drive, a)
    options = SolverOptions() if method is None else SolverOptions(method=method)
    if rosenbrock is not None:
        options = replace(options, rosenbrock=rosenbrock)
    started = time.process_time()
    trial = creep_trial(system, v * 1e-3, nut_speed=vn * 1e-3, options=options)
    return {"kind": trial.kind, "ripple_ratio": trial.ripple_ratio,
            "duration_s": trial.duration, "decided_at_s": trial.decided_at,
            "cpu_s": time.process_time() - started}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", default="", help="comma-separated substrings of case keys")
    parser.add_argument("--rosenbrock", default=None,
                        help="the engine's SolverOptions.rosenbrock (default: the default's); "
                             "writes results/bench_verdicts_<rosenbrock>.json instead")
    parser.add_argument("--reference-only", action="store_true")
    parser.add_argument("--available", action="store_true",
                        help="judge only the cases whose reference is already kept")
    parser.add_argument("--reference-file", default=str(REFERENCE),
                        help="where the reference verdicts are kept (several files are "
                        "read: this one and the default)")
    parser.add_argument("--recompute", action="store_true",
                        help="compute again the selected cases' references of an older rule "
                        "(kept in --reference-file; they replace the older ones)")
    parser.add_argument("--engine-all", action="store_true",
                        help="judge every selected case by the engine, computing no "
                        "reference (cases without one are listed as not computed)")
    parser.add_argument("--resummarise", action="store_true",
                        help="judge the engine rows of the results file against the "
                        "references kept now (no integration)")
    parser.add_argument("--rejudge", action="store_true",
                        help="judge the kept reference traces again by the current rule and "
                        "update the kept verdicts (no integration)")
    parser.add_argument("--compare", default="auto,dopri5",
                        help="other methods judged too (comma-separated; '' for none)")
    args = parser.parse_args()
    cases = [c for c in CORPUS if not args.only
             or any(s in key(c) for s in args.only.split(","))]
    kept = Path(args.reference_file)
    refs: dict[str, Any] = {}
    for path in sorted({kept, REFERENCE, *REFERENCE.parent.glob("bench_verdicts_reference*.json")}):
        if path.exists():
            for k, ref in json.loads(path.read_text()).items():
                # a reference of the current rule and step cap replaces an older one; of two
                # such, the tighter one (``rtol`` recorded where it is not RTOL)
                if (k not in refs or refs[k].get("rule") != RULE
                        or (ref.get("rule") == RULE
                            and ref.get("rtol", RTOL) <= refs[k].get("rtol", RTOL))):
                    refs[k] = ref
    if args.resummarise:  # the engine rows kept, judged against the references kept now
        kept_rows = json.loads(RESULTS.read_text())
        methods = [m for m in kept_rows["rows"][0] if m not in ("case", "reference")]
        for row in kept_rows["rows"]:
            row["reference"] = refs.get(row["case"])
            for m in methods:
                row[m]["agrees"] = (None if row["reference"] is None
                                    else row[m]["kind"] == row["reference"]["kind"])
        kept_rows["summary"] = summarise(kept_rows["rows"], methods)
        print(json.dumps(kept_rows["summary"], indent=1))
        RESULTS.write_text(json.dumps(kept_rows, indent=1) + "\n")
        return
    if args.rejudge:
        for path in sorted(REFERENCE.parent.glob("bench_verdicts_reference*.json")):
            stored = json.loads(path.read_text())
            for c in CORPUS:
                ref = stored.get(key(c))
                if ref is None or ref.get("rule") != RULE:
                    continue
                again = rejudge(c)
                if again is None:
                    print(f"{key(c)}: no trace, or undecided at its end", flush=True)
                    continue
                if any(again[k] != ref[k] for k in ("kind", "duration_s")):
                    print(f"{key(c)}: {ref['kind']} at {ref['duration_s']:g} s -> "
                          f"{again['kind']} at {again['duration_s']:g} s", flush=True)
                ref.update(again)
            path.write_text(json.dumps(stored, indent=1) + "\n")
        return
    if args.available:
        cases = [c for c in cases if key(c) in refs]
    if args.engine_all:  # no reference is computed: a case without one is judged unmatched
        args.reference_only = False
        missing = {key(c) for c in cases if key(c) not in refs}
    else:
        missing = set()
    own: dict[str, Any] = json.loads(kept.read_text()) if kept.exists() else {}
    for c in cases:
        if key(c) in missing:
            continue
        if key(c) not in refs or (args.recompute and refs[key(c)].get("rule") != RULE):
            refs[key(c)] = own[key(c)] = reference_trial(c)
            print(f"reference {key(c)}: {refs[key(c)]}", flush=True)
            kept.parent.mkdir(parents=True, exist_ok=True)
            kept.write_text(json.dumps(own, indent=1) + "\n")

    if args.reference_only:
        return
    default = SolverOptions().method
    methods = [default, *[m for m in args.compare.split(",") if m and m != default]]
    rows = []
    for c in cases:
        ref = refs.get(key(c))
        row: dict[str, Any] = {"case": key(c), "reference": ref}
        for m in methods:
            row[m] = engine_trial(c, None if m == default else m, args.rosenbrock)
            row[m]["agrees"] = None if ref is None else row[m]["kind"] == ref["kind"]
        rows.append(row)
        print(f"{key(c):45s} ref {ref['kind'] if ref else '(none)':11s} "
              + "  ".join(f"{m} {row[m]['kind']:11s}"
                          f"{' ✗' if row[m]['agrees'] is False else ''}"
                          for m in methods), flush=True)
    summary = summarise(rows, methods)
    print(json.dumps(summary, indent=1))
    out = RESULTS if args.rosenbrock is None else RESULTS.with_name(
        f"{RESULTS.stem}_{args.rosenbrock}.json")
    out.write_text(json.dumps({"default_method": default, "rosenbrock": args.rosenbrock,
                               "summary": summary, "rows": rows}, indent=1) + "\n")


def summarise(rows: list[dict[str, Any]], methods: list[str]) -> dict[str, Any]:
    """Agreement per method over the rows with a reference, and what the references are."""
    judged = [r for r in rows if r["reference"] is not None]
    summary: dict[str, Any] = {
        m: {"agree": sum(bool(r[m]["agrees"]) for r in judged), "of": len(judged),
            "cpu_s": sum(r[m]["cpu_s"] for r in rows),
            "disagree": [r["case"] for r in judged if not r[m]["agrees"]]}
        for m in methods}
    summary["reference"] = {
        "cpu_s": sum(r["reference"]["cpu_s"] for r in judged),
        # the references of the current rule and step cap, and those kept from before
        "current": sum(r["reference"].get("rule") == RULE for r in judged),
        "older": [r["case"] for r in judged if r["reference"].get("rule") != RULE]}
    summary["not_computed"] = [r["case"] for r in rows if r["reference"] is None]
    return summary

if __name__ == "__main__":
    main()
