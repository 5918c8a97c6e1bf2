"""Integration methods as data: Butcher tableaux of explicit embedded Runge–Kutta pairs and
coefficient sets of Rosenbrock methods.

A method here is only numbers; :mod:`feeddrive.solvers.steps` writes the one explicit
embedded Runge–Kutta step and the one Rosenbrock step for any of them, and the one driver
(:mod:`feeddrive.solvers.driver`, specialised for :mod:`feeddrive.solvers.dopri5`,
:mod:`feeddrive.solvers.switching` and :mod:`feeddrive.fmu.solver`) calls the step so written.
Adding a method is adding a tableau.  A tableau checks its order conditions when it is built
(:mod:`feeddrive.solvers.order_conditions`): a wrong coefficient raises
:class:`~feeddrive.solvers.order_conditions.OrderConditionError` at import.

* :data:`DOPRI5`: Dormand–Prince 5(4), J. R. Dormand and P. J. Prince, "A family of embedded
  Runge–Kutta formulae", J. Comput. Appl. Math. 6 (1980) 19–26; the coefficients and the
  continuous extension as in E. Hairer, S. P. Nørsett and G. Wanner, *Solving Ordinary
  Differential Equations I*, 2nd ed., Springer (1993), Table II.5.2 and Sect. II.6, and their
  code ``dopri5.f`` (``CONTD5``; the same numbers as scipy's RK45 ``P``).
* :data:`BS3`: Bogacki–Shampine 3(2), P. Bogacki and L. F. Shampine, "A 3(2) pair of
  Runge–Kutta formulas", Appl. Math. Lett. 2 (1989) 321–325 (scipy's RK23): a second tableau
  of the same step (used by the tests: the step is generic, its order is the tableau's).
* :data:`RODAS3`: A. Sandu, J. G. Verwer, J. G. Blom, E. J. Spee, G. R. Carmichael and
  F. A. Potra, "Benchmarking stiff ODE solvers for atmospheric chemistry problems II:
  Rosenbrock solvers", Atmos. Environ. 31 (1997) 3459–3472 (as in the KPP code's
  ``Rodas3``): a second Rosenbrock tableau of the same step, order 3(2), no dense output.
* :data:`RODAS4`: E. Hairer and G. Wanner, *Solving Ordinary Differential Equations II*, 2nd
  ed., Springer (1996), Sect. IV.7, as in their ``rodas.f`` (``ROCOE``, ``METH = 1``, with the
  dense-output coefficients ``D21 … D35``).
* :data:`RODAS5P`: G. Steinebach, "Construction of Rosenbrock–Wanner method Rodas5P and
  numerical benchmarks within the Julia Differential Equations package", BIT Numer. Math. 63
  (2023) 27: order 5(4), eight stages, stiffly accurate like RODAS4, with a continuous
  extension of order 4 (three rows over the eight increments); the numbers as in
  OrdinaryDiffEq.jl (``lib/OrdinaryDiffEqRosenbrock/src/rosenbrock_tableaus.jl``,
  ``Rodas5PTableau``: A, C, c, d and H in the same increment form).  The stiff method of
  ``modal`` and ``auto`` (:attr:`feeddrive.engine.options.SolverOptions.rosenbrock`,
  default RODAS5P since 2026-12-05; docs/model.md, "RODAS5P, the default Rosenbrock
  method").
"""

from __future__ import annotations

from dataclasses import dataclass

from .order_conditions import check_explicit, check_rosenbrock


@dataclass(frozen=True)
class ExplicitTableau:
    """An explicit embedded Runge–Kutta pair.

    Parameters
    ----------
    name : str
        Short name (the generated step is ``_<name>_step``).
    order : int
        Order of the propagated solution.
    embedded_order : int
        Order of the embedded solution (the error estimate's).
    c : tuple of float
        Nodes c_s of the stages s = 1 … S (c_1 = 0) [fraction of the step].
    a : tuple of tuple of float
        Row s holds a_s1 … a_s,s-1 (row 1 is empty) [-].
    b : tuple of float
        Weights of the propagated solution over the S stages [-].
    e : tuple of float
        Error weights b − b̂ over the S stages and, when ``fsal``, the stage at the new point
        [-].
    fsal : bool
        The derivative at the new point (t + h, y_new) is a stage of the next step ("first
        same as last"); the step evaluates it.
    dense : tuple of float, optional
        Coefficients of the 4th-order continuous extension over the same stages as ``e``
        (Hairer–Nørsett–Wanner, Sect. II.6); empty if the method has none [-].
    reference : str
        Where the numbers come from.
    """

    name: str
    order: int
    embedded_order: int
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    e: tuple[float, ...]
    fsal: bool
    dense: tuple[float, ...] = ()
    reference: str = ""

    def __post_init__(self) -> None:
        s = len(self.c)
        if len(self.a) != s or any(len(row) != k for k, row in enumerate(self.a)):
            raise ValueError(f"{self.name}: a must hold rows of lengths 0 … {s - 1}")
        if len(self.b) != s or len(self.e) != s + (1 if self.fsal else 0):
            raise ValueError(f"{self.name}: b over the {s} stages, e over those "
                             f"{'and the new point' if self.fsal else ''}")
        if self.dense and len(self.dense) != len(self.e):
            raise ValueError(f"{self.name}: dense coefficients over the stages of e")
        check_explicit(self)

    @property
    def stages(self) -> int:
        """Right-hand-side evaluations per step (the new-point one included when ``fsal``)."""
        return len(self.c) - 1 + (1 if self.fsal else 0)


@dataclass(frozen=True)
class RosenbrockTableau:
    """A Rosenbrock method in the increment form of Hairer & Wanner, Sect. IV.7 (7.25)::

        (I/(γh) − J) u_s = f(t + c_s h, y + Σ_{j<s} a_sj u_j) + Σ_{j<s} (c_sj/h) u_j + d_s h f_t

    Parameters
    ----------
    name : str
        Short name (the generated step is ``_<name>_step``).
    order, embedded_order : int
        Orders of the solution and of the embedded one.
    gamma : float
        The diagonal γ [-].
    c : tuple of float
        Nodes c_s (c_1 = 0) [fraction of the step].
    a : tuple of tuple of float
        Row s: a_s1 … a_s,s-1 (increment form) [-].
    cc : tuple of tuple of float
        Row s: c_s1 … c_s,s-1 (increment form) [-].
    d : tuple of float
        d_s, the weight of h·f_t in stage s (Hairer & Wanner's γ_s) [-].
    dense : tuple of tuple of float
        Two or three rows (empty: none) of the dense-output vectors q_r = Σ_j dense[r][j] u_j
        over the first S − 1 or all S increments:
        y(θ) = (1 − θ)·y_0 + θ·(y_1 + (1 − θ)·(q_1 + θ·(q_2 + θ·q_3))), q_3 = 0 with two rows;
        its order is :attr:`dense_order` [-].
    reference : str
        Where the numbers come from.

    Notes
    -----
    The generated step supports stiffly accurate methods whose last two stage arguments are
    y_1 and the embedded solution (a_S = a_{S−1} extended by a_{S,S−1} = 1): y_1 is the last
    stage argument plus u_S, and u_S is the error estimate (RODAS4 is one).
    """

    name: str
    order: int
    embedded_order: int
    gamma: float
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    cc: tuple[tuple[float, ...], ...]
    d: tuple[float, ...]
    dense: tuple[tuple[float, ...], ...]
    reference: str = ""

    def __post_init__(self) -> None:
        s = len(self.c)
        for rows, what in ((self.a, "a"), (self.cc, "cc")):
            if len(rows) != s or any(len(row) != k for k, row in enumerate(rows)):
                raise ValueError(f"{self.name}: {what} must hold rows of lengths 0 … {s - 1}")
        if len(self.d) != s:
            raise ValueError(f"{self.name}: d over the {s} stages")
        if tuple(self.a[-1]) != (*self.a[-2], 1.0):
            raise ValueError(f"{self.name}: the step supports stiffly accurate methods with "
                             "a_S = (a_{S-1}, 1) only")
        if self.dense and (len(self.dense) not in (2, 3) or len({len(r) for r in self.dense}) != 1
                           or len(self.dense[0]) not in (s - 1, s)):
            raise ValueError(f"{self.name}: dense holds two or three vectors q_r over the first "
                             f"{s - 1} or all {s} increments")
        check_rosenbrock(self)

    @property
    def stages(self) -> int:
        """Right-hand-side evaluations per step (the first stage's is the caller's f0)."""
        return len(self.c) - 1

    @property
    def dense_order(self) -> int:
        """Order of the continuous extension (one below the method's) [-]."""
        return self.order - 1

    @property
    def step_exponent(self) -> float:
        """The step-size controller's exponent 1/(q + 1), q the embedded order: the local
        error estimate u_S is O(h^(q+1)) (rodas.f: 0.25 for RODAS4) [-]."""
        return 1.0 / (self.embedded_order + 1)


DOPRI5 = ExplicitTableau(
    name="dp5", order=5, embedded_order=4,
    c=(0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0),
    a=((),
       (1 / 5,),
       (3 / 40, 9 / 40),
       (44 / 45, -56 / 15, 32 / 9),
       (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
       (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656)),
    b=(35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84),
    e=(71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40),
    fsal=True,
    dense=(-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
           -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
           -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0),
    reference="Dormand & Prince, J. Comput. Appl. Math. 6 (1980); Hairer, Nørsett & Wanner, "
              "Solving ODEs I, Table II.5.2, dopri5.f CONTD5")

BS3 = ExplicitTableau(
    name="bs3", order=3, embedded_order=2,
    c=(0.0, 1 / 2, 3 / 4),
    a=((), (1 / 2,), (0.0, 3 / 4)),
    b=(2 / 9, 1 / 3, 4 / 9),
    e=(2 / 9 - 7 / 24, 1 / 3 - 1 / 4, 4 / 9 - 1 / 3, -1 / 8),
    fsal=True,
    reference="Bogacki & Shampine, Appl. Math. Lett. 2 (1989) 321-325")

RODAS4 = RosenbrockTableau(
    name="rodas4", order=4, embedded_order=3, gamma=0.25,
    c=(0.0, 0.386, 0.21, 0.63, 1.0, 1.0),
    a=((),
       (0.1544000000000000e+01,),
       (0.9466785280815826e+00, 0.2557011698983284e+00),
       (0.3314825187068521e+01, 0.2896124015972201e+01, 0.9986419139977817e+00),
       (0.1221224509226641e+01, 0.6019134481288629e+01, 0.1253708332932087e+02,
        -0.6878860361058950e+00),
       (0.1221224509226641e+01, 0.6019134481288629e+01, 0.1253708332932087e+02,
        -0.6878860361058950e+00, 1.0)),
    cc=((),
        (-0.5668800000000000e+01,),
        (-0.2430093356833875e+01, -0.2063599157091915e+00),
        (-0.1073529058151375e+00, -0.9594562251023355e+01, -0.2047028614809616e+02),
        (0.7496443313967647e+01, -0.1024680431464352e+02, -0.3399990352819905e+02,
         0.1170890893206160e+02),
        (0.8083246795921522e+01, -0.7981132988064893e+01, -0.3152159432874371e+02,
         0.1631930543123136e+02, -0.6058818238834054e+01)),
    d=(0.25, -0.1043, 0.1035, -0.3620000000000023e-01, 0.0, 0.0),
    dense=((0.1012623508344586e+02, -0.7487995877610167e+01, -0.3480091861555747e+02,
            -0.7992771707568823e+01, 0.1025137723295662e+01),
           (-0.6762803392801253e+00, 0.6087714651680015e+01, 0.1643084320892478e+02,
            0.2476722511418386e+02, -0.6594389125716872e+01)),
    reference="Hairer & Wanner, Solving ODEs II, Sect. IV.7; rodas.f ROCOE METH = 1")

RODAS3 = RosenbrockTableau(
    name="rodas3", order=3, embedded_order=2, gamma=0.5,
    c=(0.0, 0.0, 1.0, 1.0),
    a=((), (0.0,), (2.0, 0.0), (2.0, 0.0, 1.0)),
    cc=((), (4.0,), (1.0, -1.0), (1.0, -1.0, -8.0 / 3.0)),
    d=(0.5, 1.5, 0.0, 0.0),
    dense=(),
    reference="Sandu et al., Atmos. Environ. 31 (1997) 3459-3472; KPP Rodas3")

# Steinebach (2023): the sixth row of a, shared by the last two (stiffly accurate)
_A6P = (-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
        0.030198172008377946)
RODAS5P = RosenbrockTableau(
    name="rodas5p", order=5, embedded_order=4, gamma=0.21193756319429014,
    c=(0.0, 0.6358126895828704, 0.4095798393397535, 0.9769306725060716, 0.4288403609558664,
       1.0, 1.0, 1.0),
    a=((),
       (3.0,),
       (2.849394379747939, 0.45842242204463923),
       (-6.954028509809101, 2.489845061869568, -10.358996098473584),
       (2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641),
       _A6P,
       (*_A6P, 1.0),
       (*_A6P, 1.0, 1.0)),
    cc=((),
        (-14.155112264123755,),
        (-17.97296035885952, -2.859693295451294),
        (147.12150275711716, -1.41221402718213, 71.68940251302358),
        (165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306),
        (24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125,
         -0.6610691825249471),
        (30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783,
         -19.097331116725623, -28.087943162872662),
        (37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047,
         -40.06618937091002, -54.66780262877968, -9.48861652309627)),
    d=(0.21193756319429014, -0.42387512638858027, -0.3384627126235924, 1.8046452872882734,
       2.325825639765069, 0.0, 0.0, 0.0),
    dense=((25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204,
            0.524948541321073, 1.1241088310450404, 0.4272876194431874, -0.17202221070155493),
           (-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796,
            20.176138334709044, 15.98066361424651, -6.789040303419874, -6.710236069923372),
           (11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643,
            -52.072871366152654, -59.78993625266729, -0.15582684282751913, 4.883087185713722)),
    reference="Steinebach, BIT Numer. Math. 63 (2023) 27; OrdinaryDiffEq.jl Rodas5PTableau")

EXPLICIT = {t.name: t for t in (DOPRI5, BS3)}
ROSENBROCK = {t.name: t for t in (RODAS4, RODAS3, RODAS5P)}
