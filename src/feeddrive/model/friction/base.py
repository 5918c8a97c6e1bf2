"""The friction-law interface and its registry.

A friction law is a small object (the python-control ``descfcn`` idea: a nonlinearity that
carries its own analytic description):

* ``kernel(v, y, k, P, o, dy) -> force`` — a ``@kernel`` (translated to C for the engine;
  numba-compiled where numba is installed, plain Python otherwise).  ``v`` [m/s] is the
  sliding speed (linear-equivalent; rotary sites are in Table 1's ÷H form), the law's
  internal states are ``y[k : k + len(state_names)]`` and it writes their rates to ``dy`` at
  the same places; its parameters are ``P[o : o + n]`` as packed by
  :meth:`FrictionLaw.pack`.  Returns the friction force [N] with the sign of the sliding
  speed.
* ``pack(site)`` — the parameter vector from a site's
  :class:`~feeddrive.model.friction.lugre_parameters.LuGreParameters` (every law reads the
  same cited fields: F_c, F_s, v_s, σ2 per direction, σ0, σ1).
* ``steady_force(v, site)`` — the steady curve [N] (constant sliding at ``v``);
* ``steady_state(v, site)`` — the internal states at steady sliding;
* ``linearise(v, site)`` — (A, B, C, D) of δẋ = A δx + B δv, δF = C δx + D δv at steady
  sliding; the default uses central differences of ``kernel``; laws may override it with an
  analytic form (checked against the default in the tests).

Laws are found by name (``[friction.screw] law = "lugre"``) in a registry; a user registers a
new one with :func:`register_friction_law` without editing the package.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ... import registry
from .lugre_parameters import LuGreParameters as _LuGreParameters

if TYPE_CHECKING:
    from .lugre_parameters import LuGreParameters


#: Names of a site's packed parameters
#: (:meth:`~feeddrive.model.friction.lugre_parameters.LuGreParameters.as_array`, the default
#: :meth:`FrictionLaw.pack`), in ``P`` order: their paths below ``friction.<site>``.
SITE_SLOTS = tuple(f"{d}.{f}" for d in ("positive", "negative")
                   for f in ("coulomb_force", "static_force", "stribeck_velocity",
                             "viscous_coefficient")) + ("bristle_stiffness", "bristle_damping")


@dataclass(frozen=True)
class LinearFriction:
    """Friction linearised at steady sliding: δẋ = A δx + B δv, δF = C δx + D δv.

    The small-signal model of a law around constant sliding at speed v (x the law's internal
    states); :mod:`feeddrive.analysis.linear` puts it into the drive's state-space model.

    Parameters
    ----------
    A : numpy.ndarray
        (n, n) state matrix of the internal states [1/s].
    B : numpy.ndarray
        (n,) input vector, rate of each state per unit of sliding speed [state unit/m].
    C : numpy.ndarray
        (n,) output vector, friction force per unit of each state [N/state unit].
    D : float
        Direct feed-through, the force per unit of sliding speed [N s/m].
    """

    A: np.ndarray  # (n, n) [1/s]
    B: np.ndarray  # (n,)  [1/m] per state unit
    C: np.ndarray  # (n,)  [N per state unit]
    D: float  # [N s/m]


#: the speed at which a law's states take their size (:meth:`FrictionLaw.deflection_scales`):
#: far below any Stribeck speed, the onset of sliding [m/s]
ONSET_SPEED = 1e-9
#: the size of a state without a steady size at the onset of sliding [m]
DEFAULT_DEFLECTION = 1e-6


class FrictionLaw:
    """Base class of friction laws; subclasses set ``name``, ``kernel``, ``state_names``."""

    name: str = ""
    state_names: tuple[str, ...] = ()
    state_unit: str = "m"
    citation: str = ""
    #: names of the packed parameters (:meth:`pack`), paths below ``friction.<site>``
    slots: tuple[str, ...] = SITE_SLOTS
    #: the class of a site's parameters under this law (:class:`SiteParameters` subclass)
    parameters_class: type = _LuGreParameters
    published: bool = True  # a published model: its docstring has a References section
    kernel: Any = None
    #: the law has a kink at zero sliding speed (|v|, the direction branch, GMS's stick/slip
    #: switch) and its first state's rate is the sliding speed when its states are zero
    #: (ż = v − …·|v|·z; a sticking GMS element's dδ/dt = v): the dense-output integrator
    #: makes the speed's zero crossings step ends
    #: (:mod:`feeddrive.solvers.events`)
    kink_at_zero_speed: bool = False

    @property
    def first_state(self) -> str:
        """Name of the law's first internal state at any site, the one whose rate is the
        sliding speed when the states are zero (``kink_at_zero_speed``); "" for a stateless
        law.  ``state_names[0]`` by default; a law whose state count depends on its
        parameters (GMS) overrides it."""
        return self.state_names[0] if self.state_names else ""

    @property
    def compiled(self) -> Any:
        """The kernel as declared on the class (a numba dispatcher is a descriptor: reading
        ``self.kernel`` would bind it to the law instance)."""
        for cls in type(self).__mro__:
            if "kernel" in cls.__dict__:
                k = cls.__dict__["kernel"]
                return getattr(k, "__func__", k)
        return None

    def pack(self, site: LuGreParameters) -> np.ndarray:
        """The site's parameters packed for the kernel, in :meth:`site_slots` order.

        Parameters
        ----------
        site : LuGreParameters
            The friction site's parameters (the law's ``parameters_class``).

        Returns
        -------
        numpy.ndarray
            The values the kernel reads at ``P[o : o + n]`` [SI, per slot].
        """
        return site.as_array()

    def states(self, site: Any) -> tuple[str, ...]:
        """Names of the law's internal states at ``site``.

        A law whose state count depends on its parameters (GMS's N elements) overrides this.

        Parameters
        ----------
        site : SiteParameters
            The friction site's parameters.

        Returns
        -------
        tuple of str
            One name per state, in ``y`` order; ``state_names`` by default.
        """
        return self.state_names

    def site_slots(self, site: Any) -> tuple[str, ...]:
        """Names of the values :meth:`pack` returns at ``site``.

        Parameters
        ----------
        site : SiteParameters
            The friction site's parameters.

        Returns
        -------
        tuple of str
            Parameter paths below ``friction.<site>``, in ``P`` order; ``slots`` by default.
        """
        return self.slots

    def steady_state(self, v: float, site: LuGreParameters) -> np.ndarray:
        """The law's internal states in steady sliding.

        Parameters
        ----------
        v : float
            Constant sliding speed [m/s].
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            The states, in :meth:`states` order [state units]; zeros by default (a stateless law).
        """
        return np.zeros(len(self.states(site)))

    def deflection_scales(self, site: Any) -> np.ndarray:
        """The size of each internal state: its steady value at the onset of sliding, the
        larger of the two directions (F_s/σ0 for a LuGre bristle), which the integrator's
        default tolerance of the state follows (:mod:`feeddrive.engine.options`).

        Read from :meth:`steady_state` at ±``ONSET_SPEED``; a state with no steady size there
        (a zero-weight element, a zero stiffness) takes ``DEFAULT_DEFLECTION``.

        Parameters
        ----------
        site : SiteParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            One positive size per state, in :meth:`states` order [state units].
        """
        n = len(self.states(site))
        if n == 0:
            return np.zeros(0)
        with np.errstate(all="ignore"):
            up = np.abs(np.asarray(self.steady_state(ONSET_SPEED, site), dtype=float))
            down = np.abs(np.asarray(self.steady_state(-ONSET_SPEED, site), dtype=float))
            size = np.maximum(up, down)
        return np.where(np.isfinite(size) & (size > 0.0), size, DEFAULT_DEFLECTION)

    def evaluate(self, v: float, states: np.ndarray, site: LuGreParameters,
                 packed: np.ndarray | None = None) -> tuple[float, np.ndarray]:
        """Friction force and state rates at one instant, by a Python call of the compiled kernel.

        Parameters
        ----------
        v : float
            Sliding speed [m/s].
        states : numpy.ndarray
            The law's internal states, in :meth:`states` order [state units].
        site : LuGreParameters
            The friction site's parameters.
        packed : numpy.ndarray, optional
            The site packed by :meth:`pack` [SI, per slot]; packed on each call when omitted.

        Returns
        -------
        force : float
            Friction force with the sign of the sliding speed [N].
        rates : numpy.ndarray
            Time derivatives of ``states`` [state units/s].
        """
        n = len(self.states(site))
        y = np.zeros(max(n, 1))
        y[:n] = states
        dy = np.zeros(max(n, 1))
        P = self.pack(site) if packed is None else packed
        force = float(self.compiled(float(v), y, 0, P, 0, dy))
        return force, dy[:n].copy()

    def steady_force(self, v: object, site: LuGreParameters) -> np.ndarray:
        """The steady friction curve: the force after sliding long enough at constant speed.

        Parameters
        ----------
        v : array_like
            Sliding speed(s) [m/s].
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        numpy.ndarray
            Friction force at each speed, shaped like ``v`` [N].
        """
        speeds = np.asarray(v, dtype=float)
        P = self.pack(site)
        out = np.empty(speeds.size)
        for i, s in enumerate(speeds.ravel()):
            out[i] = self.evaluate(s, self.steady_state(s, site), site, P)[0]
        return out.reshape(speeds.shape)

    def linearise(self, v: float, site: LuGreParameters) -> LinearFriction:
        """Linearise the law at steady sliding by central differences of its kernel.

        Steps of 1e-6 relative in the speed and in each state; laws with a closed form (LuGre, GMS)
        override this, and the tests compare the two.

        Parameters
        ----------
        v : float
            Steady sliding speed of the operating point [m/s], v ≠ 0 for laws whose states have no
            steady value at rest.
        site : LuGreParameters
            The friction site's parameters.

        Returns
        -------
        LinearFriction
            (A, B, C, D) of the small-signal model at ``v``.
        """
        n = len(self.states(site))
        P = self.pack(site)
        x0 = self.steady_state(v, site)
        dv = 1e-6 * max(abs(v), 1e-9)
        f_p, r_p = self.evaluate(v + dv, x0, site, P)
        f_m, r_m = self.evaluate(v - dv, x0, site, P)
        B = (r_p - r_m) / (2 * dv)
        D = (f_p - f_m) / (2 * dv)
        A = np.zeros((n, n))
        C = np.zeros(n)
        for j in range(n):
            dx = 1e-6 * max(abs(x0[j]), 1e-12)
            e = np.zeros(n)
            e[j] = dx
            f_p, r_p = self.evaluate(v, x0 + e, site, P)
            f_m, r_m = self.evaluate(v, x0 - e, site, P)
            A[:, j] = (r_p - r_m) / (2 * dx)
            C[j] = (f_p - f_m) / (2 * dx)
        return LinearFriction(A=A, B=B, C=C, D=float(D))


def register_friction_law(law: FrictionLaw) -> FrictionLaw:
    """Make ``law`` available by ``law.name`` in parameter files and the API.

    Parameters
    ----------
    law : FrictionLaw
        An instance of a law class (``name``, ``kernel``, ``state_names`` set).

    Returns
    -------
    FrictionLaw
        ``law``, registered in :mod:`feeddrive.registry` (group ``feeddrive.friction_laws``).
    """
    if not law.name or not law.name.replace("-", "_").isidentifier():
        raise ValueError(f"friction law name {law.name!r}: expected a short identifier")
    if law.compiled is None:
        raise ValueError(f"friction law {law.name!r}: no kernel")
    registry.register(registry.FRICTION_LAWS, law.name, law)
    return law


def friction_law(name: str) -> FrictionLaw:
    """Look up a registered friction law by the name a parameter file uses.

    Parameters
    ----------
    name : str
        The law's name (``"lugre"``, ``"stribeck"``, ``"dahl"``, ``"gms"``, ``"none"`` or one a
        user registered).

    Returns
    -------
    FrictionLaw
        The registered law instance.

    Raises
    ------
    ParameterError
        When no law of that name is registered; the message lists the known names.
    """
    laws = registry.table(registry.FRICTION_LAWS)
    if name not in laws:
        from ...parameters import ParameterError

        raise ParameterError("law", name,
                             f"unknown friction law; expected one of {', '.join(laws)}")
    law: FrictionLaw = laws[name]
    return law


def law_names() -> tuple[str, ...]:
    """Names of the registered friction laws, in registration order.

    Returns
    -------
    tuple of str
        The names a ``[friction.<site>] law = ...`` line accepts.
    """
    return registry.names(registry.FRICTION_LAWS)
