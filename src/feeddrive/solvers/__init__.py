"""The integrators of the assembled model: methods as data, generic steps, one driver.

* :mod:`~feeddrive.solvers.tableaux`: the methods as data — DOPRI5 (Dormand & Prince 1980),
  Bogacki–Shampine, RODAS4 (Hairer & Wanner, *Solving Ordinary Differential Equations II*,
  Sect. IV.7), RODAS3;
* :mod:`~feeddrive.solvers.steps`: one explicit embedded Runge–Kutta step and one Rosenbrock
  step, written out for any tableau, and the error norm and PI step-size controller;
* :mod:`~feeddrive.solvers.driver`: the one driver — step-size control, the event schedule
  (:mod:`~feeddrive.solvers.schedule`: the sampled parts' instants, merged, as exact step
  ends), output handling, divergence and stop checks — specialised per use by folding its flags:
  :mod:`~feeddrive.solvers.dopri5` (the ``dopri5`` method: every breakpoint a step end),
  :mod:`~feeddrive.solvers.switching` (the dense-output methods, DOPRI5 ⇄ RODAS4 with
  :mod:`~feeddrive.solvers.modes` and the Jacobian kernels of :mod:`~feeddrive.solvers.rodas4`)
  and :mod:`feeddrive.fmu.solver` (the FMU's integrator, also translated to C);
* :mod:`~feeddrive.solvers.placeholders`: the model names the templates call.

The driver and the steps are text, placed once in a generated module of their own
(:mod:`~feeddrive.solvers.shared`) and compiled once for every model: each function that calls
the model takes its right-hand side and sampled update as first-class functions.
"""
