"""Analyses of table-speed traces and friction measurements (simulated or measured)."""
