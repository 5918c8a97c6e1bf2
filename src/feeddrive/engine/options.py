"""Integrator settings (:class:`SolverOptions`) and how their tolerances follow the run.

A feeddrive number is only as good as the integration under it.  The error of every method
follows its absolute tolerances as much as ``rtol`` (the weight of a state's error is
``atol + rtol·|y|``, and at the speeds of a feed drive at low speed the absolute part is the
larger one), so fixed absolute tolerances made a 0.01-mm/s run a hundred times less accurate,
relative to its signal, than a 1-mm/s run.  The defaults therefore scale with the run
(``feeddrive.engine.simulate.run_scales``):

* speeds: ``SPEED_FRACTION`` × the state's speed scale: for the table (linear states), V_t,
  the largest commanded table speed (or initial speed); for the motors (angles and rotary
  speeds, through the lead H), V, the largest commanded speed of any motor (table plus nut for
  a DDFS: the screw's); each at least ``SPEED_SCALE_FLOOR``.  Each state is held relative to
  its own signal: a DDFS table at 0.1 mm/s between motors at 16 mm/s is the difference of two
  large angles, and its own tolerance is what keeps it accurate;
* positions (the table; the motor angles and the loops' integrals through H):
  ``POSITION_TIME`` × the same speed scales.  Not the stroke: a position error of the
  screw–table pair is a spring force error (K_eq × error), and the stroke would loosen it with
  the run's length;
* friction deflections (LuGre bristles, GMS elements, an observer's state):
  ``DEFLECTION_FRACTION`` × the state's own scale, its steady deflection at the onset of
  sliding (F_s/σ0 for LuGre), declared by the friction law;
* currents: ``CURRENT_FRACTION`` × the current scale, the controller's current limit when the
  set gives one below ``NO_CURRENT_LIMIT`` (the drive's peak current), else 1 A;
* ``rtol``: ``DEFAULT_RTOL``.

``accuracy`` multiplies every tolerance left at its default; an explicit tolerance is used as
given.  The constants were chosen by measurement (docs/model.md, "Integration accuracy";
benchmarks/bench_accuracy.py): at ``accuracy = 1`` the frictionless step responses of the
CDFS and DDFS stay within 1e-5 of their peak speed, and every method's error falls at least
5× per decade of ``accuracy``.

Where the settings come from, in order of precedence: the command line, the API (a
:class:`SolverOptions` built in Python), a parameter file's ``[solver]`` table, the defaults
(:func:`layered`); :meth:`feeddrive.SolverOptions.describe` says which one set each.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, NamedTuple

from ..parameters import ParameterError
from ..parameters.validation import check_flag, did_you_mean, is_real
from ..solvers import driver, modes, switching
from ..solvers.tableaux import DOPRI5, RODAS4, RODAS5P, RosenbrockTableau

__all__ = ["CURRENT_FRACTION", "DEFAULT_RTOL", "DEFLECTION_FRACTION", "DENSE_OUTPUT_ORDER",
           "DOPRI5_STEP", "LEGACY_TOLERANCES", "METHODS", "POSITION_TIME", "REVERSAL_METHODS",
           "SPEED_FRACTION", "SPEED_SCALE_FLOOR", "RunScales", "SolverOptions", "Tolerances",
           "current", "file_settings", "floor", "layered", "using"]

#: the methods :class:`SolverOptions` takes
METHODS = ("modal", "dopri5", "auto", "rodas4", "dopri5-dense", "dopri5-fixed",
           "rodas4-fixed")
# method -> (driver mode, adaptive) of feeddrive.solvers.switching
DENSE_MODES = {"modal": (switching.MODE_MODAL, 1), "auto": (switching.MODE_AUTO, 1),
               "rodas4": (switching.MODE_RODAS4, 1),
               "dopri5-dense": (switching.MODE_DOPRI5, 1),
               "rodas4-fixed": (switching.MODE_RODAS4, 0)}
#: the methods that locate friction reversals (a site's sliding speed through zero, where its
#: law has a kink) on their steps' continuous extension and make them step ends
#: (:mod:`feeddrive.solvers.events`) unless ``locate_reversals`` is false: every method but
#: the fixed-step DOPRI5 of the order checks
REVERSAL_METHODS = (*DENSE_MODES, "dopri5")
class Rosenbrock(NamedTuple):
    """A Rosenbrock method ``modal`` and ``auto`` can take where the run is stiff.

    Parameters
    ----------
    label : str
        Its name in labels (``RODAS4``).
    mode : int
        What it adds to the driver's mode (:data:`feeddrive.solvers.driver.ROSENBROCK_5`).
    tableau : RosenbrockTableau
        Its coefficients (:mod:`feeddrive.solvers.tableaux`).
    """

    label: str
    mode: int
    tableau: RosenbrockTableau

    @property
    def cost(self) -> float:
        """One step counted in DOPRI5 steps by the switch back to DOPRI5, the driver's
        ``<LABEL>_COST`` as it stands (:data:`feeddrive.solvers.driver.RODAS4_COST`) [-]."""
        return float(getattr(switching, f"{self.label}_COST"))


#: the Rosenbrock methods of ``SolverOptions.rosenbrock``, by name
ROSENBROCKS = {"rodas4": Rosenbrock("RODAS4", 0, RODAS4),
               "rodas5p": Rosenbrock("RODAS5P", switching.ROSENBROCK_5, RODAS5P)}
DEFAULT_ROSENBROCK = "rodas5p"
#: the default largest step of ``dopri5`` at ``accuracy`` 1 [s], × accuracy^(1/5) otherwise
#: (:attr:`feeddrive.SolverOptions.largest_step`): where the cap binds, DOPRI5's global
#: error goes as h^5, so a cap that stayed put would leave the error there deaf to
#: ``accuracy``
DOPRI5_STEP = 1e-3
#: the order of each method's continuous extension (outputs between step ends): DOPRI5's
#: dense output (Hairer, Nørsett & Wanner I, Sect. II.6, ``contd5``) is of order 4, RODAS4's
#: (Hairer & Wanner II, Sect. IV.7, ``contro``) of order 3; ``dopri5`` has every output a
#: step end
DENSE_OUTPUT_ORDER = {"modal": "4 (DOPRI5 steps) / 3 (RODAS4 steps) or 4 (RODAS5P steps)",
                      "auto": "4 (DOPRI5 steps) / 3 (RODAS4 steps) or 4 (RODAS5P steps)",
                      "rodas4": "3",
                      "dopri5-dense": "4", "rodas4-fixed": "3",
                      "dopri5": "none (every output a step end)",
                      "dopri5-fixed": "none (every output a step end)"}

DEFAULT_METHOD = "modal"
#: rtol of a run that is not given one, × ``accuracy`` [-]
DEFAULT_RTOL = 1e-6
#: speed tolerance = SPEED_FRACTION × V [-]
SPEED_FRACTION = 1e-5
#: position tolerance = POSITION_TIME × V [s]
POSITION_TIME = 1e-10
#: deflection tolerance = DEFLECTION_FRACTION × the state's deflection scale [-]
DEFLECTION_FRACTION = 1e-5
#: current tolerance = CURRENT_FRACTION × the current scale [-]
CURRENT_FRACTION = 1e-6
#: the smallest speed scale V [m/s] (0.001 mm/s): a run commanded at rest
SPEED_SCALE_FLOOR = 1e-6
#: a current limit at or above this is "no limit" [A]; the current scale is then 1 A
NO_CURRENT_LIMIT = 1000.0
#: the smallest relative tolerance a setting may ask for (double precision's reach) [-]
MIN_RELATIVE = 1e-14
#: the largest relative tolerance and accuracy factor accepted [-]
MAX_RTOL = 0.1
MAX_ACCURACY = 1e4
#: the largest explicit absolute tolerances accepted [m, m/s, A]: what ``accuracy =
#: MAX_ACCURACY`` makes of the defaults on a run at 1 m/s with a 1000-A current scale (the
#: fastest, largest feed drive), 1e-6 m, 0.1 m/s and 10 A; a larger one would leave every step
#: of a feed drive's run uncontrolled by it
MAX_ABSOLUTE = {"position_tolerance": POSITION_TIME * 1.0 * MAX_ACCURACY,
                "speed_tolerance": SPEED_FRACTION * 1.0 * MAX_ACCURACY,
                "current_tolerance": CURRENT_FRACTION * NO_CURRENT_LIMIT * MAX_ACCURACY}
#: the smallest accuracy factor accepted: rtol's default × it is MIN_RELATIVE [-]
MIN_ACCURACY = MIN_RELATIVE / DEFAULT_RTOL
#: the smallest current scale the floor below assumes (a 1-mA current limit) [A]
SMALLEST_CURRENT_SCALE = 1e-3
#: the smallest explicit absolute tolerances accepted [m, m/s, A]: what ``accuracy =
#: MIN_ACCURACY`` makes of the defaults on the slowest run (speed scale SPEED_SCALE_FLOOR) with
#: a 1-mA current scale, 1e-24 m, 1e-19 m/s and 1e-17 A — the mirror of MAX_ABSOLUTE.  A
#: smaller one asks for what no accuracy setting does (``--position-tolerance 1e-30`` ground
#: through 50 million steps, ``--current-tolerance 5e-324`` failed on a step-size underflow)
MIN_ABSOLUTE = {name: float(f"{value:.12g}") for name, value in (  # 1e-19, not 1.0…01e-19
    ("position_tolerance", POSITION_TIME * SPEED_SCALE_FLOOR * MIN_ACCURACY),
    ("speed_tolerance", SPEED_FRACTION * SPEED_SCALE_FLOOR * MIN_ACCURACY),
    ("current_tolerance", CURRENT_FRACTION * SMALLEST_CURRENT_SCALE * MIN_ACCURACY))}

#: the fixed tolerances every method ran with before they scaled with the run (engine v1 and
#: the defaults until 2026-12-04): ``SolverOptions(method="dopri5", locate_reversals=False,
#: **LEGACY_TOLERANCES)`` reproduces a v1 trace bit for bit
LEGACY_TOLERANCES = {"rtol": 1e-6, "position_tolerance": 1e-10, "speed_tolerance": 1e-8,
                     "current_tolerance": 1e-6}

#: the tolerance settings: (field, unit, what it bounds)
TOLERANCES = (("rtol", "-", "relative tolerance"),
              ("position_tolerance", "m", "absolute tolerance of positions"),
              ("speed_tolerance", "m/s", "absolute tolerance of speeds"),
              ("current_tolerance", "A", "absolute tolerance of currents"))
_TOLERANCE_NAMES = tuple(name for name, _, _ in TOLERANCES)
#: the settings a [solver] table or the command line may give
SETTINGS = ("method", *_TOLERANCE_NAMES, "accuracy", "output_interval", "max_step",
            "max_steps", "rosenbrock")
#: the defaults' source, as describe() names it
DEFAULT_SOURCE = "default"
API_SOURCE = "API"
#: the source :meth:`SolverOptions.from_record` gives ``accuracy``: a record holds settings
#: already merged (:func:`layered`, tightened), not one setting, so an accuracy factor under
#: explicit tolerances there is no ambiguity to refuse
RECORD_SOURCE = "record"
#: how a derived setting's source reads: ``"--rtol ÷ 100"``, the option's value tightened 100×
#: (:meth:`SolverOptions.tightened_source`)
_DIVIDED = " ÷ "
#: the command line's unit of each setting and the factor from its SI value to it (the command
#: line takes lengths in mm and speeds in mm/s: ``feeddrive.cli._solver.CLI_UNITS``; a file's
#: ``[solver]`` table and the API take SI)
CLI_UNITS = {"rtol": ("", 1.0), "position_tolerance": ("mm", 1e3),
             "speed_tolerance": ("mm/s", 1e3), "current_tolerance": ("A", 1.0),
             "accuracy": ("", 1.0)}
#: the settings in words, as :meth:`SolverOptions.setting_text` names them
_WORDS = {"rtol": "rtol", "position_tolerance": "position tolerance",
          "speed_tolerance": "speed tolerance", "current_tolerance": "current tolerance",
          "accuracy": "accuracy"}


def floor(name: str) -> float:
    """The smallest value a tolerance setting or ``accuracy`` takes: ``MIN_RELATIVE`` for
    ``rtol``, ``MIN_ABSOLUTE`` for an absolute tolerance, ``MIN_ACCURACY`` for ``accuracy``
    (double precision's reach).  :class:`SolverOptions` refuses a value below it, and
    :func:`feeddrive.engine.error_estimate.tightened` a tightening that would go below it.

    Parameters
    ----------
    name : str
        ``rtol``, ``position_tolerance``, ``speed_tolerance``, ``current_tolerance`` or
        ``accuracy``.

    Returns
    -------
    float
        The floor [-, m, m/s, A or -].
    """
    if name == "rtol":
        return MIN_RELATIVE
    if name == "accuracy":
        return MIN_ACCURACY
    return MIN_ABSOLUTE[name]


@dataclass(frozen=True)
class RunScales:
    """The sizes a run's default tolerances are scaled to.

    Parameters
    ----------
    speed : float
        Speed scale V of the motors: the largest commanded (or initial) speed of any motor,
        table plus nut for a DDFS's screw, at least :data:`SPEED_SCALE_FLOOR` [m/s].
    table_speed : float
        Speed scale V_t of the table: its largest commanded (or initial) speed, at least
        :data:`SPEED_SCALE_FLOOR` [m/s].
    current : float
        Current scale: the current limit, or 1 A [A].
    """

    speed: float
    table_speed: float
    current: float


@dataclass(frozen=True)
class Tolerances:
    """The tolerances a run integrates with, resolved from :class:`SolverOptions` and the run's
    :class:`RunScales`.

    Parameters
    ----------
    rtol : float
        Relative tolerance on speeds and currents [-].
    position : float
        Absolute tolerance of the table's (linear) positions [m].
    speed : float
        Absolute tolerance of the table's (linear) speeds [m/s].
    current : float
        Absolute tolerance of currents [A].
    deflection : float or None
        Fraction of each friction deflection state's own scale [-]; None: deflections take
        the position tolerance (an explicit ``position_tolerance``, as before scaled defaults).
    motor_position : float
        Absolute tolerance of the motors' angles and the loops' integrals, in table units
        [m] (÷ H per state).
    motor_speed : float
        Absolute tolerance of the motors' speeds, in table units [m/s] (÷ H per state).
    """

    rtol: float
    position: float
    speed: float
    current: float
    deflection: float | None
    motor_position: float
    motor_speed: float

    def as_dict(self) -> dict[str, float | None]:
        """The values by their option names (the Result's ``solver_stats`` and the JSON).

        Returns
        -------
        dict
            ``rtol``, ``position_tolerance`` [m], ``speed_tolerance`` [m/s],
            ``current_tolerance`` [A], ``deflection_fraction`` [-] (None: the position one),
            ``motor_position_tolerance`` [m], ``motor_speed_tolerance`` [m/s].
        """
        return {"rtol": self.rtol, "position_tolerance": self.position,
                "speed_tolerance": self.speed, "current_tolerance": self.current,
                "deflection_fraction": self.deflection,
                "motor_position_tolerance": self.motor_position,
                "motor_speed_tolerance": self.motor_speed}


def _mm(x: float) -> str:
    """A length [m] or speed [m/s] as a short label in mm or mm/s (the units at the edges:
    the command line's tolerances are given in them)."""
    return _num(x * 1e3)


def _num(x: float) -> str:
    """A number as a short label: 3 significant digits, the exponent without a leading zero
    (1e-5, not 1e-05)."""
    text = f"{x:.3g}"
    mantissa, _, exponent = text.partition("e")
    if not exponent:
        return text
    sign = "-" if exponent.startswith("-") else ""
    return f"{mantissa}e{sign}{exponent.lstrip('+-').lstrip('0') or '0'}"


def _check_positive(name: str, value: Any, unit: str, low: float = 0.0,
                    high: float = math.inf) -> float:
    span = (f"{low:g} … {high:g}" if low > 0.0 else f"> 0, ≤ {high:g}") \
        if math.isfinite(high) else f"≥ {low:g}" if low > 0.0 else "> 0"
    # NumPy's scalars are numbers: np.float32(1e-3) was "expected a finite value > 0 [s]"
    # (an API sweep of session 29)
    if not is_real(value) or not math.isfinite(value) or value <= 0.0 \
            or not low <= value <= high:
        raise ParameterError(f"options.{name}", value, f"expected a finite value {span} "
                             f"[{unit}]")
    return float(value)


def _check_origin(origin: object) -> tuple[tuple[str, str], ...]:
    """``SolverOptions.origin`` as a tuple of (setting, source) pairs of text, or a one-line
    refusal naming ``options.origin`` (``origin=3`` was "'int' object is not iterable", a
    dict's keys were read as pairs, a misspelt setting's source never asked for).

    Parameters
    ----------
    origin : object
        What was given: pairs (setting, source), e.g. ``(("accuracy", "API"),)``, or a
        mapping of setting to source.

    Returns
    -------
    tuple of (str, str)
        The pairs.

    Raises
    ------
    ParameterError
        For anything but pairs of text whose settings are SolverOptions' fields.
    """
    if origin == ():  # the default, and most options made inside
        return ()
    names = [f.name for f in fields(SolverOptions) if f.name != "origin"]
    expected = ("expected pairs (setting, source) of text, e.g. ((\"accuracy\", \"API\"),), "
                "or a mapping of setting to source")
    if isinstance(origin, Mapping):
        origin = tuple(origin.items())
    if isinstance(origin, str | bytes) or not isinstance(origin, Iterable):
        raise ParameterError("options.origin", origin, expected)
    pairs = []
    for k, pair in enumerate(origin):
        if isinstance(pair, str | bytes) or not isinstance(pair, Iterable):
            raise ParameterError(f"options.origin[{k}]", pair, expected)
        pair = tuple(pair)
        if len(pair) != 2 or not all(isinstance(p, str) for p in pair):
            raise ParameterError(f"options.origin[{k}]", pair, expected)
        if pair[0] not in names:
            raise ParameterError(f"options.origin[{k}]", pair, "expected a setting of "
                                 f"SolverOptions, one of {', '.join(names)}"
                                 + did_you_mean(pair[0], names))
        pairs.append((pair[0], pair[1]))
    return tuple(pairs)


@dataclass(frozen=True)
class SolverOptions:
    """Integrator settings, echoed in the result.

    The tolerances left at None scale with the run (module docstring,
    :mod:`feeddrive.engine.options`; docs/model.md, "Integration accuracy"), multiplied by
    ``accuracy``; an explicit tolerance is used as given.

    Parameters
    ----------
    method : str, default "modal"
        * ``"modal"`` (the default): DOPRI5 where the problem is not stiff, the Rosenbrock
          method ``rosenbrock`` where it is, with each Rosenbrock step capped so that every
          lightly damped, undamped or growing oscillatory mode of the Jacobian is resolved
          (h|λ| ≤ 0.35 for damping ratios below 0.02: :mod:`feeddrive.solvers.modes`), and
          no switch where that cap leaves the Rosenbrock method no longer a step than
          DOPRI5's; dense output.  A diverging run stops early (``divergence_bounds``);
        * ``"dopri5"``: adaptive Dormand–Prince 5(4), every output instant a step end (steps
          at most ``max_step``, default 1 ms × accuracy^(1/5), and the output interval;
          below ``accuracy`` 1 also ``stability_share`` × DOPRI5's stability bound),
          friction reversals located on each step's continuous extension and made step ends
          (``locate_reversals``); with ``locate_reversals=False`` at ``accuracy`` 1 the engine
          v1 behaviour, bit for bit;
        * ``"auto"``: DOPRI5 where the problem is not stiff, ``rosenbrock`` where it is, switched
          automatically on Hairer's stiffness test alone; dense output (steps not capped by
          the output interval);
        * ``"rodas4"``: the Rosenbrock method RODAS4 throughout, dense output;
        * ``"dopri5-dense"``: DOPRI5 throughout with dense output;
        * ``"dopri5-fixed"``, ``"rodas4-fixed"``: fixed step ``fixed_step`` (order checks).

        Outputs between step ends come from the method's own continuous extension
        (:data:`~feeddrive.engine.options.DENSE_OUTPUT_ORDER`).  See
        :mod:`feeddrive.solvers.switching`.
    rtol : float or None, default None
        Relative tolerance on speeds and currents [-]; None: ``DEFAULT_RTOL`` × accuracy.
    position_tolerance : float or None, default None
        Absolute error target of positions [m] (angles scaled by H); None: scaled with the
        run.  Given, it also holds for the friction deflections (as before scaled defaults).
    speed_tolerance : float or None, default None
        Absolute error target of speeds [m/s] (rotary speeds scaled by H); None: scaled.
    current_tolerance : float or None, default None
        Absolute error target of motor currents [A]; None: scaled.
    accuracy : float, default 1.0
        Factor on every tolerance left at its default (0.1: ten times tighter) [-].  Not
        together with an explicit tolerance in one setting (ambiguous: refused).
    output_interval : float, default 1e-3
        Spacing of the recorded samples [s] (for ``dopri5`` also the breakpoint spacing under
        continuous control).
    max_step : float or None, default None
        Largest step [s] (None: 1 ms × accuracy^(1/5) for ``dopri5``, unlimited for the
        dense-output methods).
    fixed_step : float, default 1e-5
        Step of the fixed-step methods [s].
    max_steps : int, default 50 000 000
        A run that would need more steps is refused before it starts.
    sample_steps : bool, default False
        Dense-output methods: every sample of a
        :class:`~feeddrive.model.reference.SampledSpeed` a step end, not only its kinks
        (``profile_breakpoints``), so that the steps always end on the profile's grid
        and a run's step sequence moves little with its parameters — what a fit's
        finite-difference Jacobian and its confidence intervals want (``feeddrive fit`` sets
        it); the steps are then no longer than the profile's interval.
    locate_reversals : bool, default True
        Friction reversals (a site's sliding speed through zero, where a LuGre or Dahl law has
        a kink) located on each step's continuous extension and made step ends
        (:mod:`feeddrive.solvers.events`), by every method of
        :data:`~feeddrive.engine.options.REVERSAL_METHODS`.
        False: the steps cross them, as the engine v1 did
        (``SolverOptions(method="dopri5", locate_reversals=False, **LEGACY_TOLERANCES)``
        reproduces a v1 trace bit for bit); its error then stops following the tolerances
        at the reversals.
    rosenbrock : str, default "rodas5p"
        The Rosenbrock method of ``modal`` and ``auto`` where the run is stiff
        (``DEFAULT_ROSENBROCK``, since 2026-12-05; RODAS4 before): ``"rodas4"`` (Hairer &
        Wanner, order 4(3), continuous extension of order 3) or ``"rodas5p"`` (Steinebach
        2023, order 5(4), eight stages, continuous extension of order 4:
        :data:`feeddrive.solvers.tableaux.RODAS5P`).  The ``rodas4`` methods are RODAS4
        whatever it says.
    origin : tuple of (str, str), default ()
        Where each setting came from (``("rtol", "--rtol")``, ``("accuracy", "[solver] in
        run.toml")``); a setting not listed was given in Python (API) or is a default.
        Not compared: two options with the same settings are equal.
    """

    method: str = DEFAULT_METHOD
    rtol: float | None = None
    position_tolerance: float | None = None
    speed_tolerance: float | None = None
    current_tolerance: float | None = None
    accuracy: float = 1.0
    output_interval: float = 1e-3
    max_step: float | None = None
    fixed_step: float = 1e-5
    max_steps: int = 50_000_000
    sample_steps: bool = False
    locate_reversals: bool = True
    rosenbrock: str = DEFAULT_ROSENBROCK
    origin: tuple[tuple[str, str], ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "origin", _check_origin(self.origin))
        if self.method not in METHODS:
            raise ParameterError("options.method", self.method,
                                 f"expected one of {', '.join(METHODS)}")
        # each number is kept as a float (a NumPy scalar given is echoed as the float it is)
        if self.rtol is not None:
            object.__setattr__(self, "rtol", _check_positive("rtol", self.rtol, "-",
                                                             floor("rtol"), MAX_RTOL))
        for name in ("position_tolerance", "speed_tolerance", "current_tolerance"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _check_positive(
                    name, value, dict((n, u) for n, u, _ in TOLERANCES)[name],
                    low=floor(name), high=MAX_ABSOLUTE[name]))
        object.__setattr__(self, "accuracy", _check_positive(
            "accuracy", self.accuracy, "-", floor("accuracy"), MAX_ACCURACY))
        for name, unit in (("output_interval", "s"), ("max_step", "s"), ("fixed_step", "s")):
            value = getattr(self, name)
            if name == "max_step" and value is None:
                continue
            object.__setattr__(self, name, _check_positive(name, value, unit))
        for name in ("sample_steps", "locate_reversals"):  # np.bool_ taken as a bool
            object.__setattr__(self, name, check_flag(f"options.{name}", getattr(self, name)))
        if self.rosenbrock not in ROSENBROCKS:
            raise ParameterError("options.rosenbrock", self.rosenbrock,
                                 f"expected one of {', '.join(ROSENBROCKS)}")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, numbers.Integral) \
                or self.max_steps < 1:
            raise ParameterError("options.max_steps", self.max_steps,
                                 "expected a whole number ≥ 1")
        object.__setattr__(self, "max_steps", int(self.max_steps))
        # an explicit tolerance and an accuracy factor given together, in one setting
        sources = dict(self.origin)
        if self.accuracy != 1.0:
            where = sources.get("accuracy", API_SOURCE)
            both = [n for n in _TOLERANCE_NAMES
                    if getattr(self, n) is not None and sources.get(n, API_SOURCE) == where]
            if both:
                raise ParameterError("options.accuracy", self.accuracy,
                                     f"given with {both[0]} in one setting ({where}): give "
                                     "either accuracy (a factor on every default tolerance) "
                                     "or explicit tolerances")

    # ---- where each setting came from
    def source(self, name: str) -> str:
        """Where setting ``name`` came from: a command-line option, a file's ``[solver]``
        table, ``"API"`` (given in Python) or ``"default"``.

        Parameters
        ----------
        name : str
            A field name.

        Returns
        -------
        str
            The source.
        """
        sources = dict(self.origin)
        if name in sources:
            return sources[name]
        value = getattr(self, name)
        default = next(f.default for f in fields(self) if f.name == name)
        return DEFAULT_SOURCE if value == default else API_SOURCE

    def _derived(self, name: str) -> tuple[str, float]:
        """The source setting ``name`` was derived from and the factor it was divided by
        (``("--rtol", 100.0)`` for ``"--rtol ÷ 100"``; 1 for a setting as given)."""
        source = self.source(name)
        base, sep, divisor = source.rpartition(_DIVIDED)
        if sep:
            try:
                return base, float(divisor)
            except ValueError:
                pass
        return source, 1.0

    def tightened_source(self, name: str, factor: float) -> str:
        """The source of setting ``name`` once it is ``factor`` times tighter: where it came
        from, divided (``"--rtol ÷ 10"``; tightened twice, ``"--rtol ÷ 100"``), so that a
        tightened setting still names the setting it came from and is not taken for it.

        Parameters
        ----------
        name : str
            A field name.
        factor : float
            How much tighter [-].

        Returns
        -------
        str
            The source.
        """
        base, divided = self._derived(name)
        return f"{base}{_DIVIDED}{divided * factor:g}"

    def setting_place(self, name: str) -> str:
        """Where setting ``name`` is given, as a refusal tells the user to change it: the
        command-line option (``--rtol``), the file's setting (``solver.accuracy ([solver] in
        run.toml)``), or the field's name (API, default).

        Parameters
        ----------
        name : str
            A field name.

        Returns
        -------
        str
            The place.
        """
        base, _ = self._derived(name)
        if base.startswith("--"):
            return base
        if base in (DEFAULT_SOURCE, API_SOURCE, RECORD_SOURCE):
            return name
        return f"solver.{name} ({base})"

    def setting_value(self, name: str, value: float | None = None) -> str:
        """A value of tolerance setting (or ``accuracy``) ``name`` in the units the setting
        was given in: the command line's (mm, mm/s, A) when an option gave it, SI otherwise.

        Parameters
        ----------
        name : str
            ``rtol``, an absolute tolerance's name or ``accuracy``.
        value : float or None, default None
            The value (a floor, a tightened value) [SI unit of the setting]; None: the
            setting's own.

        Returns
        -------
        str
            E.g. ``"1e-21 mm"``, ``"1e-8"``.
        """
        base, _ = self._derived(name)
        x = getattr(self, name) if value is None else value
        if base.startswith("--"):
            unit, per = CLI_UNITS[name]
        else:
            unit, per = dict((n, u) for n, u, _ in TOLERANCES).get(name, "-"), 1.0
        return f"{_num(x * per)}{'' if unit in ('', '-') else ' ' + unit}"

    def setting_text(self, name: str) -> str:
        """Tolerance setting (or ``accuracy``) ``name`` in words, its value in the units it
        was given in (:meth:`setting_value`); a tightened one with what it was tightened from
        (``"rtol 1e-8 (--rtol ÷ 100)"``).

        Parameters
        ----------
        name : str
            ``rtol``, an absolute tolerance's name or ``accuracy``.

        Returns
        -------
        str
            E.g. ``"position tolerance 1e-21 mm"``.
        """
        _, divided = self._derived(name)
        text = f"{_WORDS[name]} {self.setting_value(name)}"
        if divided != 1.0:
            text += f" ({self.setting_place(name)}{_DIVIDED}{divided:g})"
        return text

    @property
    def accuracy_acts(self) -> bool:
        """Whether ``accuracy`` changes the run: some tolerance is left at its default, or
        the method is ``dopri5`` (its step caps follow accuracy:
        :attr:`largest_step`, :attr:`stability_share`).  With every tolerance explicit under
        another method it changes nothing."""
        return self.method == "dopri5" or any(getattr(self, n) is None
                                              for n in _TOLERANCE_NAMES)

    def tolerances_label(self) -> str:
        """The tolerance settings in a few words, as the fit labels its attempts: each
        explicit tolerance (lengths in mm, speeds in mm/s, currents in A, the command line's
        units) and ``accuracy`` where it acts (:attr:`accuracy_acts`).

        Returns
        -------
        str
            E.g. ``"accuracy 0.1"``, ``"rtol 1e-7, accuracy 0.1"``, ``"rtol 1e-6, positions
            1e-9 mm, speeds 0.0001 mm/s, currents 0.0001 A"``.
        """
        parts = []
        if self.rtol is not None:
            parts.append(f"rtol {_num(self.rtol)}")
        if self.position_tolerance is not None:
            parts.append(f"positions {_mm(self.position_tolerance)} mm")
        if self.speed_tolerance is not None:
            parts.append(f"speeds {_mm(self.speed_tolerance)} mm/s")
        if self.current_tolerance is not None:
            parts.append(f"currents {_num(self.current_tolerance)} A")
        if self.accuracy_acts:
            parts.append(f"accuracy {_num(self.accuracy)}")
        return ", ".join(parts)

    @property
    def driver_mode(self) -> tuple[int, int]:
        """The dense driver's (mode, adaptive) of a method of ``DENSE_MODES``: ``modal``
        and ``auto`` with the Rosenbrock steps of ``rosenbrock``
        (:mod:`feeddrive.solvers.switching`)."""
        mode, adaptive = DENSE_MODES[self.method]
        if self.method in ("modal", "auto"):
            mode += ROSENBROCKS[self.rosenbrock].mode
        return mode, adaptive

    @property
    def explicit_positions(self) -> bool:
        """Whether ``position_tolerance`` was given (deflections then follow it)."""
        return self.position_tolerance is not None

    # ---- the tolerances of a run
    def resolve(self, scales: RunScales) -> Tolerances:
        """The tolerances of a run with ``scales``: each explicit one as given, each other the
        scaled default × ``accuracy``.

        Parameters
        ----------
        scales : RunScales
            The run's speed and current scales.

        Returns
        -------
        Tolerances
            rtol [-], position [m], speed [m/s], current [A], deflection fraction [-].
        """
        a = self.accuracy

        def given_or(value: float | None, default: float) -> float:
            return value if value is not None else default * a

        return Tolerances(
            rtol=given_or(self.rtol, DEFAULT_RTOL),
            position=given_or(self.position_tolerance, POSITION_TIME * scales.table_speed),
            speed=given_or(self.speed_tolerance, SPEED_FRACTION * scales.table_speed),
            current=given_or(self.current_tolerance, CURRENT_FRACTION * scales.current),
            deflection=None if self.explicit_positions else DEFLECTION_FRACTION * a,
            motor_position=given_or(self.position_tolerance, POSITION_TIME * scales.speed),
            motor_speed=given_or(self.speed_tolerance, SPEED_FRACTION * scales.speed))

    def describe(self, scales: RunScales | None = None) -> str:
        """The integrator in words, with the numbers it runs with: the method, its step cap
        (read from the solver's constants, :data:`feeddrive.solvers.modes.H_LAMBDA` and
        :data:`~feeddrive.solvers.modes.ZETA_LIGHT` for ``modal``), the tolerances (with the
        source of each setting that is not a default: the command line, a file's
        ``[solver]`` table, the API), the output and its continuous extension.  Reports
        print it beside the numbers that rest on it.

        Parameters
        ----------
        scales : RunScales or None, default None
            A run's scales: the tolerances are then given as numbers; None: as the rule.

        Returns
        -------
        str
            One sentence.
        """
        stiff = ROSENBROCKS[self.rosenbrock]
        rb = stiff.label
        methods = {
            "modal": f"DOPRI5/{rb} switched on stiffness and on the steps' cost (a {rb} "
                     f"step counted as {_num(stiff.cost)} DOPRI5 steps), every step "
                     f"capped at h·|λ| ≤ {_num(modes.H_LAMBDA)} on each oscillatory mode of "
                     f"the Jacobian with damping ratio < {_num(modes.ZETA_LIGHT)}",
            "dopri5": "adaptive Dormand–Prince 5(4)",
            "auto": f"DOPRI5/{rb} switched on Hairer's stiffness test and on the steps' "
                    "cost, no mode cap",
            "rodas4": "Rosenbrock RODAS4",
            "dopri5-dense": "adaptive Dormand–Prince 5(4), dense output",
            "dopri5-fixed": f"Dormand–Prince 5 at a fixed step of {_num(self.fixed_step)} s",
            "rodas4-fixed": f"RODAS4 at a fixed step of {_num(self.fixed_step)} s",
        }
        largest = self.largest_step
        caps = [f"≤ {_num(largest)} s"] if math.isfinite(largest) and \
            not self.method.endswith("-fixed") else []
        if self.stability_share < 1.0:
            caps.append(f"≤ {_num(self.stability_share)} × DOPRI5's stability bound "
                        f"{_num(driver.DOPRI5_STABILITY)}/ρ (ρ estimated on each step)")
        steps = f"steps {' and '.join(caps)}, " if caps else ""
        if self.sample_steps and self.method in DENSE_MODES:
            steps += "every sample of a sampled profile a step end, "
        if not self.locate_reversals and self.method in REVERSAL_METHODS:
            steps += "friction reversals stepped across (locate_reversals off), "
        return (f"{self.method} ({methods[self.method]}){self._from('method')}; {steps}"
                f"{self.describe_tolerances(scales)}; output every {_num(self.output_interval)} s"
                f"{self._from('output_interval')} ({self.output_text})")

    def describe_tolerances(self, scales: RunScales | None = None) -> str:
        """The tolerances in words (part of :meth:`describe`): lengths in mm, speeds in mm/s
        (the units the command line takes them in), currents in A.

        Parameters
        ----------
        scales : RunScales or None, default None
            A run's scales (numbers) or None (the rule).

        Returns
        -------
        str
            A clause.
        """
        a = self.accuracy
        acc = " × accuracy" if a != 1.0 else ""
        acc_from = f"; accuracy {_num(a)}{self._from('accuracy')}" if a != 1.0 else ""
        if scales is not None:
            tol = self.resolve(scales)
            deflection = ("deflections as positions" if tol.deflection is None else
                          f"deflections {_num(tol.deflection)} of their scale")
            motors = ("" if (tol.motor_position, tol.motor_speed) == (tol.position, tol.speed)
                      else f", motors {_mm(tol.motor_position)} mm and {_mm(tol.motor_speed)} "
                           "mm/s in table units")
            return (f"rtol {_num(tol.rtol)}{self._from('rtol')}, absolute tolerances "
                    f"{_mm(tol.position)} mm (positions){self._from('position_tolerance')}, "
                    f"{_mm(tol.speed)} mm/s (speeds){self._from('speed_tolerance')}{motors}, "
                    f"{_num(tol.current)} A (currents){self._from('current_tolerance')}, "
                    f"{deflection} (speed scales: table {_mm(scales.table_speed)} mm/s, motors "
                    f"{_mm(scales.speed)} mm/s; current scale {_num(scales.current)} A"
                    f"{acc_from})")
        parts = [
            f"rtol {_num(self.rtol)}{self._from('rtol')}" if self.rtol is not None
            else f"rtol {_num(DEFAULT_RTOL)}{acc}",
            f"positions {_mm(self.position_tolerance)} mm{self._from('position_tolerance')}"
            if self.position_tolerance is not None
            else f"positions {_num(POSITION_TIME)} s × V{acc}",
            f"speeds {_mm(self.speed_tolerance)} mm/s{self._from('speed_tolerance')}"
            if self.speed_tolerance is not None else f"speeds {_num(SPEED_FRACTION)} × V{acc}",
            f"currents {_num(self.current_tolerance)} A{self._from('current_tolerance')}"
            if self.current_tolerance is not None
            else f"currents {_num(CURRENT_FRACTION)} × the current limit (or 1 A){acc}",
            "friction deflections as positions" if self.position_tolerance is not None
            else f"friction deflections {_num(DEFLECTION_FRACTION)} × their onset deflection{acc}",
        ]
        return (f"{parts[0]}, absolute tolerances {', '.join(parts[1:])} (V: the state's speed "
                "scale, the table's largest command speed for the table, the largest motor "
                f"command speed for the motors, at least {_mm(SPEED_SCALE_FLOOR)} mm/s"
                f"{acc_from})")

    def _from(self, name: str) -> str:
        """Where a setting came from, when the command line or a file gave it (and how much
        it was tightened since: ``" (from --rtol ÷ 10)"``, ``" (÷ 10)"``)."""
        source = self.source(name)
        base, divided = self._derived(name)
        if divided != 1.0 and base in (DEFAULT_SOURCE, API_SOURCE):
            return f" ({_DIVIDED.strip()} {divided:g})"
        return "" if source in (DEFAULT_SOURCE, API_SOURCE) else f" (from {source})"

    @property
    def output_text(self) -> str:
        """How outputs between step ends are made: the continuous extension and its order
        (:data:`~feeddrive.engine.options.DENSE_OUTPUT_ORDER`), or every output a step end."""
        order = DENSE_OUTPUT_ORDER[self.method]
        if self.method in ("modal", "auto"):
            rb = ROSENBROCKS[self.rosenbrock]
            order = (f"{DOPRI5.order - 1} (DOPRI5 steps) / {rb.tableau.dense_order} "
                     f"({rb.label} steps)")
        if order.startswith("none"):
            return "every output a step end"
        return f"continuous extension of order {order}"

    @property
    def largest_step(self) -> float:
        """``max_step``, or its default: for ``dopri5``
        :data:`~feeddrive.engine.options.DOPRI5_STEP` (1 ms) × accuracy^(1/5) (the method's
        order: where the cap binds, the global error falls with ``accuracy`` as where the
        tolerances bind), 1 ms for ``dopri5-fixed``, unlimited for the dense-output methods
        [s].
        """
        if self.max_step is not None:
            return self.max_step
        if self.method in DENSE_MODES:
            return math.inf
        if self.method == "dopri5" and self.accuracy != 1.0:
            return DOPRI5_STEP * self.accuracy ** (1.0 / DOPRI5.order)
        return DOPRI5_STEP

    @property
    def stability_share(self) -> float:
        """For ``dopri5`` at ``accuracy`` < 1, accuracy^(1/5): each step is also capped at that
        share of DOPRI5's stability bound 3.3/ρ (ρ estimated on the step before, as dopri5.f
        detects stiffness).  Where a stiff mode holds the steps at that bound the tolerances
        do not shorten them, and the error of a lightly damped mode resolved there (the ring a
        friction reversal leaves in the DDFS) stays what the bound makes it; capped, it falls
        with ``accuracy`` as where the tolerances bind.  1 otherwise (no cap) [-].
        """
        if self.method == "dopri5" and self.accuracy < 1.0:
            return self.accuracy ** (1.0 / DOPRI5.order)
        return 1.0

    def record(self) -> dict[str, Any]:
        """The settings as plain values for cache and store keys and for a worker process:
        every field but ``origin``, and the scaling rule's constants (a change of the
        defaults changes the key).

        Returns
        -------
        dict
            Field values, and ``rule``: the default tolerances' constants.
        """
        out: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self)
                               if f.name != "origin"}
        out["rule"] = {"rtol": DEFAULT_RTOL, "speed": SPEED_FRACTION,
                       "position_time": POSITION_TIME, "deflection": DEFLECTION_FRACTION,
                       "current": CURRENT_FRACTION, "floor": SPEED_SCALE_FLOOR}
        return out

    @classmethod
    def from_record(cls, record: Mapping[str, Any],
                    origin: Iterable[tuple[str, str]] | None = None) -> SolverOptions:
        """The options a :meth:`record` holds, equal to those recorded (its ``rule`` is not
        read back: a worker runs its own code's rule, which the record's key already named).

        The record has no ``origin`` (it is a key of the settings alone): its settings were
        merged already (:func:`~feeddrive.engine.options.layered`, a fit's or an error
        estimate's tightening), so an ``accuracy`` under explicit tolerances is not the
        ambiguity of one setting that
        :class:`SolverOptions` refuses.  Without ``origin`` a recorded ``accuracy`` other than
        1 is given the source ``RECORD_SOURCE``.

        Parameters
        ----------
        record : mapping
            A :meth:`record`.
        origin : iterable of (str, str) or None, default None
            The recorded options' ``origin``, carried beside the record (a fit's tasks carry
            it): the options then name each setting's source as the recorded ones did.

        Returns
        -------
        SolverOptions
            The options.
        """
        names = {f.name for f in fields(cls)} - {"origin"}
        values = {k: v for k, v in record.items() if k in names}
        if origin is not None:
            sources = tuple(sorted((str(k), str(v)) for k, v in origin))
        else:
            sources = (("accuracy", RECORD_SOURCE),) if values.get("accuracy", 1.0) != 1.0 \
                else ()
        return cls(**values, origin=sources)


_CURRENT: ContextVar[SolverOptions | None] = ContextVar("feeddrive_solver_options",
                                                        default=None)


def check_given(options: object) -> None:
    """Refuse an ``options`` argument that is neither None nor :class:`SolverOptions` (a dict
    failed deep inside, e.g. "'dict' object has no attribute 'output_interval'"): the one
    wording of every function that takes integrator settings.

    Parameters
    ----------
    options : object
        What was given.

    Raises
    ------
    ParameterError
        Naming ``options`` and its type.
    """
    if options is not None and not isinstance(options, SolverOptions):
        raise ParameterError("options", type(options).__name__, "expected SolverOptions, "
                             "e.g. SolverOptions(rtol=1e-8)")


def current() -> SolverOptions:
    """The options a run takes when none are passed: those of the innermost :func:`using`,
    else the defaults.

    Returns
    -------
    SolverOptions
        The options in force.
    """
    return _CURRENT.get() or SolverOptions()


@contextmanager
def using(options: SolverOptions | None) -> Iterator[SolverOptions]:
    """Run the block with ``options`` as the options of every run that is not given its own
    (a command's ``--accuracy`` reaching the creep search, a fit's or a sweep's runs); None
    leaves the options in force.

    Parameters
    ----------
    options : SolverOptions or None
        The options.

    Yields
    ------
    SolverOptions
        The options in force inside the block.
    """
    token = _CURRENT.set(options) if options is not None else None
    try:
        yield current()
    finally:
        if token is not None:
            _CURRENT.reset(token)


def file_settings(path: str | Path) -> dict[str, Any]:
    """The ``[solver]`` table of a parameter (or sweep) file: the integrator settings stored
    with the set (``method``, ``rtol``, the absolute tolerances, ``accuracy``,
    ``output_interval``, ``max_step``, ``max_steps``, ``rosenbrock``), checked by name and
    kind as :func:`feeddrive.parameters.load` checks them
    (:func:`~feeddrive.parameters.components.solver_table`: the same refusals, in the same
    words, source ``"[solver] in PATH"``: the command line once had a check of its own, which
    named no close setting for a misspelt one and took a quoted number for a range error).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.

    Returns
    -------
    dict
        The table's settings (empty without a table); numbers as floats.

    Raises
    ------
    ParameterError
        For an unreadable file, a table that is not a table, an unknown setting, a value of
        the wrong kind, or ``accuracy`` with an explicit tolerance.
    """
    from ..parameters.components import solver_table
    from ..parameters.toml_io import read_toml_file

    table = read_toml_file(path).get("solver")
    if table is None:
        return {}
    return {name: value for name, value, _ in solver_table(table, f"[solver] in {path}")}


def layered(layers: Iterable[tuple[str, Mapping[str, Any]]],
            base: SolverOptions | None = None) -> SolverOptions:
    """Options from settings given in layers, each later layer over the earlier ones: e.g.
    ``[("[solver] in run.toml", file_settings), ("API", api), ("command line", cli)]``.

    A layer names its settings only (a setting it does not give is left to the layers
    below); within one layer, ``accuracy`` and an explicit tolerance together are refused.

    Parameters
    ----------
    layers : iterable of (str, mapping)
        (source, settings) pairs, lowest precedence first.  A value may be a pair
        ``(value, option)`` naming the command-line option it came from
        (``{"rtol": (1e-8, "--rtol")}``), which then is its source; None values are not
        given.
    base : SolverOptions or None, default None
        The options below every layer (None: the defaults).

    Returns
    -------
    SolverOptions
        The merged options, each setting's source in ``origin``.

    Raises
    ------
    ParameterError
        For an unknown setting, a refused value, or accuracy with a tolerance in one layer.
    """
    base = base or SolverOptions()
    values = {f.name: getattr(base, f.name) for f in fields(base) if f.name != "origin"}
    origin = dict(base.origin)
    for source, settings in layers:
        given: dict[str, Any] = {}
        names: dict[str, str] = {}
        for name, value in settings.items():
            if isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], str):
                value, where = value
            else:
                where = source
            if value is None:
                continue
            if name not in SETTINGS:
                raise ParameterError(f"{source}: {name}", value,
                                     f"expected one of {', '.join(SETTINGS)}")
            given[name] = value
            names[name] = where
        if "accuracy" in given:
            both = [n for n in _TOLERANCE_NAMES if n in given]
            if both:  # named by its option, or as a setting of the layer's table
                first, other = (names[n] if names[n] != source else f"solver.{n}"
                                for n in ("accuracy", both[0]))
                raise ParameterError(first, given["accuracy"],
                                     f"given with {other} ({source}): give either an "
                                     "accuracy factor or explicit tolerances")
            # a new accuracy factor replaces the explicit tolerances of the layers below
            for n in _TOLERANCE_NAMES:
                if values[n] is not None:
                    values[n] = None
                    origin.pop(n, None)
        values.update(given)
        origin.update(names)
    try:
        return SolverOptions(**values, origin=tuple(sorted(origin.items())))
    except ParameterError as err:  # name the option or file the value came from
        name = err.field.removeprefix("options.")
        if name in origin and origin[name].startswith("--"):
            raise ParameterError(origin[name], err.value, err.message) from None
        if name in origin:
            raise ParameterError(f"solver.{name}", err.value,
                                 f"{err.message} ({origin[name]})") from None
        raise
