"""Analyses of table-speed traces and friction measurements (simulated or measured).

metrics         creep metrics of any speed trace (ripple, stick fraction, frequency, verdict)
trace           position trace → speed → step-down segments → metrics, critical speed
identification  LuGre static (Stribeck) and pre-sliding (σ0, σ1) fits with uncertainties
fragments       identified values as TOML fragments, merged into parameter sets
plots           figures of the fits and of the trace analysis
"""
