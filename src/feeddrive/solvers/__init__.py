"""The integrators of the assembled model.

DOPRI5 (Dormand & Prince 1980) with the sampled controller's breakpoints as exact step
ends, RODAS4 (Hairer & Wanner, *Solving Ordinary Differential Equations II*, Sect. IV.7) for
the stiff stretches, and the driver that switches between them.  Their source is placed in
every generated model module (:func:`feeddrive.model.assemble.solver_sources`) and compiled
there with the model's right-hand side.
"""
