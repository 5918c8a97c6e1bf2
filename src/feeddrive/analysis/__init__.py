"""Analyses of table-speed traces and friction measurements (simulated or measured).

verdict_words   the words a creep verdict uses (smooth, creeping, stick-slip, …), one vocabulary
creep_window    window creep metrics of any speed trace (ripple, stick fraction, frequency)
cycle_verdict   the window-independent verdict: limit cycle, decayed, or undecided
tracking        sine tracking, following error, travel of the table
trace_input     the checks, resampling and stick time the metrics share
trace           position trace → speed → step-down segments → metrics, critical speed
identification  LuGre static (Stribeck) and pre-sliding (σ0, σ1) fits with uncertainties
fragments       identified values as TOML fragments, merged into parameter sets
plots           figures of the fits and of the trace analysis
"""
