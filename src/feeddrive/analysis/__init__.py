"""Analyses of table-speed traces and friction measurements (simulated or measured).

verdict_words   the words a creep verdict uses (smooth, creeping, stick-slip, …), one vocabulary
creep_window    window creep metrics of any speed trace (ripple, stick fraction, frequency)
cycle_verdict   the window-independent verdict: limit cycle, decayed, or undecided
tracking        sine tracking, following error, travel of the table
trace_input     the checks, resampling and stick time the metrics share
trace           position trace → speed → step-down segments → metrics, critical speed
fit_statistics  estimates with confidence intervals, identifiability, a record's noise
static_fit      LuGre static (Stribeck) fit of constant-speed tests
presliding      pre-sliding fit of σ0, σ1 (the test simulated by presliding_rig on the engine)
fragments       identified values as TOML fragments, merged into parameter sets
plots           figures of the fits and of the trace analysis
"""
