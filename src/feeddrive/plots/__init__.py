"""Figures (matplotlib object API, Agg canvas; engineering units on the axes): a simulation
result (:mod:`~feeddrive.plots.result`), the linearised loops (:mod:`~feeddrive.plots.linear`),
the Stribeck curve (:mod:`~feeddrive.plots.stribeck`), the identification fits and trace
analysis (:mod:`~feeddrive.plots.analysis`), and layout checks of a figure
(:mod:`~feeddrive.plots.layout`)."""
