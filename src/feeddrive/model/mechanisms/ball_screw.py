"""The ball-screw drives of Wang2021: CDFS and DDFS.  Eqs. (2)–(8).

Screw (θ_s, ω_s), nut (θ_n, ω_n) and table (x_t, v_t), with the screw–nut–table axial
stiffness K_eq(a) of Eqs. (2)–(5) and damping c_ax:

    F_d     = K_eq(a)·[H(θ_s − θ_n) − x_t] + c_ax·[H(ω_s − ω_n) − v_t]
    J_s ω̇_s = K_t i_s − H·F_screw − H·F_d
    J_n ω̇_n = K_t i_n − H·F_nut + H·F_d
    m_t v̇_t = F_d − F_guide
    L i̇     = u − R i − K_e ω

The CDFS is this mechanism with the hollow motor held (Sect. 2.1): the nut's states are frozen
(``nut_hold = "locked"``) or kept on its servo at zero command (``"servo"``).  With a lead
error δ(θ) the stretch is H·θ_rel + δ(θ_rel) − x_t and the lever (H + δ').  With a ball–nut
share f the screw-shaft friction is split between ground (1 − f) and the ball–nut contact at
the relative speed (f), whose reaction acts on the nut.

A gap at the coupling (``[backlash] location = "coupling"``,
:mod:`feeddrive.model.parts.backlash`) makes the screw shaft a body of its own beyond the
rotor, with states (θ_sh, ω_sh), only when that part is present:

    F_c       = gap_force(H(θ_s − θ_sh), H(ω_s − ω_sh); η·K_c/H², c_c, b/2)
    J_m ω̇_s   = K_t i_s − H·F_c
    J_sh ω̇_sh = H·F_c − H·F_screw − H·F_d

with F_d, the screw-shaft and ball–nut friction at ω_sh and the coupling out of the torsion
term of K_eq (Eq. 5 keeps the screw's own torsion).  η·K_c/H² is Eq. (5)'s reflection of the
coupling's torsion, so with b = 0 the series chain is the lumped model's K_eq.  The
friction-dominated hold acts on the table while the coupling gap is open.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import kernel
from ...parameters import DriveParameters, ParameterError
from ..codegen import Builder
from ..loops import ENC_Q, GRAT_Q, H_AX, V_FEEDBACK, Axis, Channel, axis_parameters
from .ball_screw_stiffness import axial_stiffness, equivalent_stiffness, torsional_stiffness
from .base import Body, DriveMotor, Mechanics, Mechanism, Site, register_mechanism

# stiffness block ``stiffness.<name>``: fixed K_eq (0 = from the chain), c0, EA, length,
# support (0 fixed–fixed, 1 fixed–free), x0; the kernel reads it through the named offsets
STIFFNESS_SLOTS = ("k_fixed", "c0", "ea", "length", "support", "x0")
K_FIXED, C0, EA, LENGTH, SUPPORT, X0 = range(len(STIFFNESS_SLOTS))


@kernel
def equivalent_stiffness_kernel(x_t: float, P: np.ndarray, o: int) -> float:
    """Screw–nut–table equivalent axial stiffness K_eq at the current table displacement.

    1/K_eq = c0 + c_screw(a), c0 the position-independent compliances (bearings, nut, optional
    torsion; Wang2021 Eqs. (2), (3), (5)) and c_screw the screw's axial compliance at nut position
    a = x0 + x_t, Wang2021 Eq. (4): a(l − a)/(EA·l) between fixed–fixed supports, a/(EA) for
    fixed–free.  a is kept 1e-3·l inside the supports, where Eq. (4) diverges.  A fixed K_eq in
    the block (> 0) is returned as is.

    Parameters
    ----------
    x_t : float
        Table displacement from its start position [m].
    P : numpy.ndarray
        The packed parameter vector [SI, per slot].
    o : int
        Offset of the stiffness block (:data:`STIFFNESS_SLOTS`: K_fixed, c0, EA, l, support,
        x0) in ``P``.

    Returns
    -------
    float
        K_eq [N/m].

    References
    ----------
    .. [1] Wang2021 Eqs. (2)–(5).
    """
    if P[o + K_FIXED] > 0.0:
        return P[o + K_FIXED]
    a = P[o + X0] + x_t
    length = P[o + LENGTH]
    # keep the nut strictly between the supports (Eq. 4 diverges at the supports)
    lo = 1e-3 * length
    if a < lo:
        a = lo
    elif a > length - lo:
        a = length - lo
    if P[o + SUPPORT] < 0.5:
        c_screw = a * (length - a) / (P[o + EA] * length)
    else:
        c_screw = a / P[o + EA]
    return 1.0 / (P[o + C0] + c_screw)


@register_mechanism
class BallScrewDrive(Mechanism):
    """CDFS / DDFS ball-screw mechanism (see the module docstring for its equations).

    Parameters
    ----------
    params : DriveParameters
        The parameter set (SI).
    drive : {"cdfs", "ddfs"}
        Which drive: the hollow motor held (CDFS) or driving the nut (DDFS).
    table_position : float
        Table position a along the screw [m] (sets K_eq(a), Wang2021 Eqs. (2)–(5)).
    nut_hold : {"locked", "servo"}
        How the CDFS holds the nut.

    References
    ----------
    .. [1] Z. Wang, X. Feng, H. Yang, H. Jin, "Research on low-speed characteristics of
       differential double-drive feed system", Mech. Sci. 12 (2021) 791–800, Eqs. (1)–(8).
    """

    drives = ("cdfs", "ddfs")
    drive_motors = (DriveMotor("screw", "screw_angle", "screw", "screw_motor_ripple",
                               "screw motor"),
                    DriveMotor("nut", "nut_angle", "nut", "hollow_motor_ripple",
                               "hollow motor"))
    has_lead_screw = True
    travel_length = "screw.length"
    travel_ends = "the screw supports"
    uses_table_position = True
    table_axis = "screw"
    #: the hollow motor's axis follows the nut reference (a profile's nut speed)
    reference_axes = {"nut": "nut"}
    part_name = "ball screw"
    own_sections = ("screw", "coupling", "stiffness", "screw_motor", "hollow_motor",
                    "hollow_controller")

    def __init__(self, params: DriveParameters, drive: str, table_position: float,
                 nut_hold: str) -> None:
        super().__init__(params, drive, table_position, nut_hold)
        # the DDFS drives its nut; the CDFS holds it (holds_nut), locked or on its servo
        self.nut_active = self.follows("nut") or nut_hold == "servo"
        gap = params.section("backlash")
        #: a gap at the coupling: the screw shaft is a body of its own (θ_sh, ω_sh)
        self.coupling_gap = gap is not None and gap.location == "coupling"

    @classmethod
    def check(cls, params: DriveParameters, drive: str, table_position: float) -> None:
        """Parameters
        ----------
        params : DriveParameters
            The parameter set [SI].
        drive : str
            The drive name.
        table_position : float
            Table position at the start [m].

        Raises
        ------
        ParameterError
            When the table position is not strictly between the screw's supports.
        """
        length = params.screw.length
        a = table_position
        if not (math.isfinite(a) and 0.0 < a < length):
            raise ParameterError("table_position", a,
                                 f"expected 0 < a < {length:g} [m] (between the supports)")

    @classmethod
    def drive_label(cls, drive: str) -> str:
        """Parameters
        ----------
        drive : str
            ``"cdfs"`` or ``"ddfs"``.

        Returns
        -------
        str
            ``"the CDFS"``, ``"the DDFS"``.
        """
        return f"the {drive.upper()}"

    def held_parameters(self) -> tuple[tuple[str, ...], str]:
        """The CDFS with its nut locked: the hollow motor, its loops, the nut's inertia and
        friction and the ball–nut share do not act.

        Returns
        -------
        paths : tuple of str
            Parameter paths or section prefixes.
        reason : str
            Why, for messages.
        """
        if self.nut_active:
            return (), ""
        return (("hollow_motor", "hollow_controller", "screw.nut_inertia", "friction.nut",
                 "friction.ball_nut_share"), "the CDFS holds the nut (hollow motor locked)")

    @classmethod
    def followed_references(cls, drive: str) -> tuple[str, ...]:
        """The DDFS follows a commanded nut speed; the CDFS holds its nut (locked, or on its
        servo at zero command).

        Parameters
        ----------
        drive : str
            ``"cdfs"`` or ``"ddfs"``.

        Returns
        -------
        tuple of str
            ``("nut",)`` for the DDFS, ``()`` for the CDFS.
        """
        return ("nut",) if drive == "ddfs" else ()

    @classmethod
    def held_part(cls, drive: str) -> str:
        """The CDFS holds its nut (``nut_hold``: locked or on its servo); the DDFS drives it.

        Parameters
        ----------
        drive : str
            ``"cdfs"`` or ``"ddfs"``.

        Returns
        -------
        str
            ``"nut"`` for the CDFS, ``""`` for the DDFS.
        """
        return "" if "nut" in cls.followed_references(drive) else "nut"

    def unfollowed(self, signal: str) -> str:
        return ("the CDFS holds the hollow motor; expected 0 (a moving nut is the DDFS: use "
                "drive 'ddfs', --drive ddfs)")

    def declare(self, b: Builder) -> None:
        H = self.params.screw.transmission_ratio
        b.state("screw_angle", "rad", "screw motor / shaft angle θ_s", "angle", H)
        b.state("screw_speed", "rad/s", "screw motor speed", "rotary_speed", H)
        b.state("nut_angle", "rad", "hollow motor / nut angle θ_n", "angle", H)
        b.state("nut_speed", "rad/s", "hollow motor speed", "rotary_speed", H)
        b.state("table_position", "m", "table displacement from its start x_t", "position")
        b.state("table_speed", "m/s", "table speed", "speed")
        if self.coupling_gap:
            b.state("shaft_angle", "rad", "screw shaft angle θ_sh beyond the coupling gap",
                    "angle", H)
            b.state("shaft_speed", "rad/s", "screw shaft speed beyond the coupling gap",
                    "rotary_speed", H)

    def parameters(self, b: Builder) -> None:
        p = self.params
        s, m = p.screw, p.stiffness
        H = s.transmission_ratio
        b.param("screw.H", H)
        j_motor, j_shaft = self._inertias()
        b.param("screw.J", j_motor if self.coupling_gap else j_motor + j_shaft)
        b.param("nut.J", p.hollow_motor.inertia + s.nut_inertia)
        b.param("table.mass", p.table.mass)
        b.param("stiffness.axial_damping", m.axial_damping)
        c0 = float(1.0 / axial_stiffness(np.inf, s, m.support_bearing_count))
        if m.include_torsion:  # a coupling gap takes the coupling out of the chain (its own)
            k_torsion = (s.torsional_stiffness if self.coupling_gap
                         else torsional_stiffness(p.coupling, s))
            c0 += H**2 / s.efficiency / k_torsion
        k_fixed = 0.0
        if m.equivalent_stiffness > 0:
            k_fixed = m.equivalent_stiffness
        elif not m.position_dependent and not self.coupling_gap:
            k_fixed = equivalent_stiffness(p, self.table_position)
        values = [k_fixed, c0, math.pi * s.diameter**2 / 4.0 * s.youngs_modulus, s.length,
                  0.0 if m.screw_support == "fixed-fixed" else 1.0, self.table_position]
        if self.coupling_gap and k_fixed == 0.0 and not m.position_dependent:
            values[K_FIXED] = equivalent_stiffness_kernel(0.0, np.array(values), 0)
        b.named_params("stiffness", STIFFNESS_SLOTS, np.array(values))
        b.param("nut.active", 1.0 if self.nut_active else 0.0)
        for key, motor in (("screw", p.screw_motor), ("nut", p.hollow_motor)):
            b.param(f"{key}_motor.torque_constant", motor.torque_constant)
            b.param(f"{key}_motor.back_emf_constant", motor.back_emf_constant)
            b.param(f"{key}_motor.inductance", motor.inductance)
            b.param(f"{key}_motor.resistance", motor.resistance)
        if self.coupling_gap:
            part = p.section("backlash")
            k_c = s.efficiency * p.coupling.torsional_stiffness / H**2  # Eq. (5)'s reflection
            m_red = j_motor * j_shaft / (j_motor + j_shaft) / H**2
            b.param("shaft.J", j_shaft)
            b.param("coupling.stiffness", k_c)
            b.param("coupling.contact_damping",
                    2.0 * part.contact_damping_ratio * math.sqrt(k_c * m_red))

    def _inertias(self) -> tuple[float, float]:
        """The screw motor's side and the screw shaft's side of the shaft line [kg m^2].

        Without a coupling gap the two turn as one (their sum is ``screw.J``).  With one, the
        part's ``motor_side_share`` s of ``screw.shaft_inertia`` turns with the rotor.

        Raises
        ------
        ParameterError
            When a coupling gap leaves the shaft no inertia.
        """
        p = self.params
        j_motor, j_shaft = p.screw_motor.inertia, p.screw.shaft_inertia
        if not self.coupling_gap:
            return j_motor, j_shaft
        share = p.section("backlash").motor_side_share
        if not j_shaft > 0.0:
            raise ParameterError("screw.shaft_inertia", j_shaft,
                                 "expected > 0 [kg m^2] with a gap at the coupling (the "
                                 "screw shaft beyond it is a body of its own)")
        return j_motor + share * j_shaft, (1.0 - share) * j_shaft

    def motors(self, b: Builder) -> None:
        b.state("screw_current", "A", "screw motor current", "current")
        b.state("nut_current", "A", "hollow motor current", "current")

    def sites(self, b: Builder) -> list[Site]:
        H = b.p("screw.H")
        nut_on = f"{b.p('nut.active')} > 0.5"
        share = self.params.friction.ball_nut_share
        out = []
        # beyond a coupling gap the shaft is its own body: its friction acts there
        w, shaft = ("{w_sh}", "shaft") if self.coupling_gap else ("{w_s}", "screw")
        if share < 1.0:
            out.append(Site("screw", "screw", f"{H} * {w}", ((shaft, H),), 1.0 - share,
                            rotary=True))
        out.append(Site("nut", "nut", f"{H} * {{w_n}}", (("nut", H),), 1.0, nut_on,
                        rotary=True))
        out.append(Site("guide", "guide", "{v_t}", (("table", "1.0"),)))
        if share > 0.0:
            out.append(Site("ball_nut", "screw", f"{H} * ({w} - {{w_n}})",
                            ((shaft, H), ("nut", f"(-{H})")), share, rotary=True))
        return out

    def axes(self, b: Builder) -> tuple[list[Axis], list[Channel]]:
        c = self.params.controller
        H = self.params.screw.transmission_ratio
        o_s = axis_parameters(b, "screw", c, H, speed_mode=False)
        cn = self.params.hollow_controller or c  # per-axis loops: the hollow motor's own
        if cn is not c and cn.position_feedback != "table":
            raise ParameterError("hollow_controller.position_feedback", cn.position_feedback,
                                 "the hollow motor's loop always reads its own encoder; "
                                 "expected 'table' (the option is the table axis', "
                                 "[controller])")
        o_n = axis_parameters(b, "nut", cn, H, speed_mode=cn.nut_loop == "speed")
        Hp = f"P[{o_s + H_AX}]"
        channels = [
            Channel("screw_angle", b.y("screw_angle"), b.y("screw_speed"), f"P[{o_s + ENC_Q}]"),
            Channel("nut_angle", b.y("nut_angle"), b.y("nut_speed"), f"P[{o_s + ENC_Q}]"),
            Channel("table", b.y("table_position"), b.y("table_speed"), f"P[{o_s + GRAT_Q}]"),
        ]
        fb = f"int(P[{o_s + V_FEEDBACK}]) == 1"
        position, position_q = "{table_position}", "q_table"
        if c.position_feedback == "motor":  # semi-closed loop: the encoders through the lead
            position = f"{Hp} * ({{screw_angle}} - {{nut_angle}})"
            position_q = f"{Hp} * (q_screw_angle - q_nut_angle)"
        # the DDFS follows a nut reference (followed_references); the CDFS holds its nut at 0
        nut_ref = self.follows("nut")
        screw = Axis(
            name="screw", param_offset=o_s, reference="{ref_x}",
            feedforward="({ref_v} + {ref_v_nut})" if nut_ref else "{ref_v}",
            position=position, position_q=position_q,
            speed=(f"(({{table_speed}} + {Hp} * {{nut_speed}}) / {Hp} if {fb} "
                   "else {screw_speed})"),
            speed_q=f"((s_table + {Hp} * s_nut_angle) / {Hp} if {fb} else s_screw_angle)",
            current_state="{screw_current}")
        nut = Axis(
            name="nut", param_offset=o_n, reference="{ref_x_nut}" if nut_ref else "0.0",
            feedforward="{ref_v_nut}" if nut_ref else "0.0",
            position=f"{Hp} * {{nut_angle}}", position_q=f"{Hp} * q_nut_angle",
            speed="{nut_speed}", speed_q="s_nut_angle", current_state="{nut_current}",
            active=f"{b.p('nut.active')} > 0.5", speed_law="speed")
        return [screw, nut], channels

    def compensation(self, b: Builder
                     ) -> tuple[list[tuple[str, str, str]], str]:
        H = b.p("screw.H")
        screw = "({ref_v} + {ref_v_nut})" if self.follows("nut") else "{ref_v}"
        return ([("screw", screw, f"{H} * {{screw_speed}}"),
                 ("guide", "{ref_v}", "{table_speed}")],
                f"{H} / {b.p('screw_motor.torque_constant')}")

    def steady_motion(self, table_speed: float, nut_speed: float
                      ) -> dict[str, tuple[str, float]]:
        """Screw (and a shaft beyond a coupling gap) at (v_t + v_n)/H, nut at v_n/H (0 when
        held), table at v_t (Eq. 8).

        Parameters
        ----------
        table_speed : float
            Commanded table speed [m/s].
        nut_speed : float
            Commanded nut speed [m/s].

        Returns
        -------
        dict
            Angle/position state → (rate state, steady rate [rad/s or m/s]).
        """
        H = self.params.screw.transmission_ratio
        v_n = nut_speed if self.nut_active else 0.0
        out = {"screw_angle": ("screw_speed", (table_speed + v_n) / H),
               "nut_angle": ("nut_speed", v_n / H),
               "table_position": ("table_speed", table_speed)}
        if self.coupling_gap:
            out["shaft_angle"] = ("shaft_speed", (table_speed + v_n) / H)
        return out

    def held(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The CDFS with its nut locked: the nut's states and the hollow motor's axis.

        Returns
        -------
        tuple of (tuple of str, tuple of str)
            Frozen state-name prefixes and idle axes.
        """
        if self.nut_active:
            return (), ()
        return ("nut_", "ball_nut_z"), ("nut",)

    def site_masses(self) -> dict[str, float]:
        """screw: (J_screw-motor + J_screw-shaft)/H²; nut: (J_hollow-motor + J_nut)/H²;
        guide: the table mass (Wang2021 Table 2; H = lead/2π, Eq. 8).

        Returns
        -------
        dict
            Site parameters key → effective mass [kg].

        References
        ----------
        .. [1] Wang2021 Table 2, Eq. (8).
        """
        p = self.params
        h = p.screw.transmission_ratio
        return {"screw": (p.screw_motor.inertia + p.screw.shaft_inertia) / h**2,
                "nut": (p.hollow_motor.inertia + p.screw.nut_inertia) / h**2,
                "guide": p.table.mass}

    def signals(self, b: Builder) -> None:
        b.add_aux("equivalent_stiffness", "N/m", "K_eq at the table position")
        b.add_aux("nut_position_reference", "m", "commanded nut position (linear)")
        b.add_aux("nut_speed_reference", "m/s", "commanded nut speed (linear)")
        H = self.params.screw.transmission_ratio
        b.add_derived("screw_linear_speed", "m/s", "screw speed × H", "screw_speed", H)
        b.add_derived("nut_linear_speed", "m/s", "nut speed × H", "nut_speed", H)

    def emit(self, b: Builder, m: Mechanics) -> None:
        from ..disturbances import harmonics

        H = b.p("screw.H")
        nut_ref = self.follows("nut")  # the CDFS commands its held nut 0
        b.emit(f"{{nut_position_reference}} = {'{ref_x_nut}' if nut_ref else '0.0'}")
        b.emit(f"{{nut_speed_reference}} = {'{ref_v_nut}' if nut_ref else '0.0'}")
        b.emit("{w_s} = {screw_speed}")
        b.emit("{w_n} = {nut_speed}")
        b.emit("{v_t} = {table_speed}")
        if self.coupling_gap:
            b.emit("{w_sh} = {shaft_speed}")
        for ln in m.always:
            b.emit(ln)
        k_eq = b.use(equivalent_stiffness_kernel)
        o_stiff = b.param_index[b.q(f"stiffness.{STIFFNESS_SLOTS[0]}")]  # the block's first slot
        b.emit(f"{{k_eq}} = {k_eq}({{table_position}}, P, {o_stiff})")
        c_ax = b.p("stiffness.axial_damping")
        cg = self.coupling_gap
        w = "{w_sh}" if cg else "{w_s}"  # the shaft the nut turns on
        th_rel = "({shaft_angle} - {nut_angle})" if cg else "({screw_angle} - {nut_angle})"
        gap = self.params.section("backlash")
        if gap is not None and not cg:  # a dead-zone spring at the nut (model/parts/backlash)
            if m.lead is not None:
                raise ParameterError("backlash.gap", gap.gap,
                                     "a backlash at the nut with a lead error is not "
                                     "modelled; remove [disturbances.lead_error] or the "
                                     "[backlash] section")
            self._emit_gap(b, "gap_e", f"{H} * {th_rel} - {{table_position}}",
                           f"{H} * ({{w_s}} - {{w_n}}) - {{v_t}}", "{k_eq}", c_ax, "f_d",
                           [("f_hold", "{v_t}", b.p("table.mass"))])
            lever = H
        elif m.lead is None:
            b.emit(f"{{f_d}} = ({{k_eq}} * ({H} * {th_rel} - {{table_position}}) "
                   f"+ {c_ax} * ({H} * ({w} - {{w_n}}) - {{v_t}}))")
            lever = H
        else:
            hh = b.use(harmonics)
            b.emit(f"{{lead_dev}}, {{lead_slope}} = {hh}({th_rel}, P, {m.lead[0]}, "
                   f"{m.lead[1]})")
            b.emit(f"{{f_d}} = ({{k_eq}} * ({H} * {th_rel} + {{lead_dev}} - {{table_position}}) "
                   f"+ {c_ax} * (({H} + {{lead_slope}}) * ({w} - {{w_n}}) - {{v_t}}))")
            lever = f"({H} + {{lead_slope}})"
        if cg:  # the same dead-zone spring between rotor and shaft, written at the table; the
            # friction-dominated hold stops the table (the light shaft rests on it via K_eq)
            self._emit_gap(b, "coupling_gap_e", f"{H} * ({{screw_angle}} - {{shaft_angle}})",
                           f"{H} * ({{w_s}} - {{w_sh}})", b.p("coupling.stiffness"),
                           b.p("coupling.contact_damping"), "f_c",
                           [("f_hold", "{v_t}", b.p("table.mass"))])
            screw = self._shaft(b, "screw", m, f"- {H} * {{f_c}}")
            shaft = Body(drive=[f"{H} * {{f_c}}"], external=list(m.forces.get("shaft", [])),
                         reaction=[f"- {lever} * {{f_d}}"])
        else:
            screw = self._shaft(b, "screw", m, f"- {lever} * {{f_d}}")
        table = Body(drive=["{f_d}"], external=list(m.forces.get("table", [])))
        if m.load is not None:
            table.external.append(f"- {m.load}")
        if gap is not None:
            table.external.append("+ {f_hold}")
        b.emit("{der(screw_angle)} = {w_s}")
        b.emit(f"{{der(screw_speed)}} = ({screw.expression()}) / {b.p('screw.J')}")
        if cg:
            b.emit("{der(shaft_angle)} = {w_sh}")
            b.emit(f"{{der(shaft_speed)}} = ({shaft.expression()}) / {b.p('shaft.J')}")
        b.emit("{der(table_position)} = {v_t}")
        b.emit(f"{{der(table_speed)}} = ({table.expression()}) / {b.p('table.mass')}")
        self._current(b, "screw", "{w_s}", m.torque_off)
        # the hollow motor and nut: live in the DDFS (or with the CDFS nut on its servo)
        b.emit(f"if {b.p('nut.active')} > 0.5:")
        for ln in m.gated:
            b.emit(ln.indented("    "))
        nut = self._shaft(b, "nut", m, f"+ {lever} * {{f_d}}")
        b.emit("    {der(nut_angle)} = {w_n}")
        b.emit(f"    {{der(nut_speed)}} = ({nut.expression()}) / {b.p('nut.J')}")
        self._current(b, "nut", "{w_n}", m.torque_off, indent="    ")
        b.emit("else:")
        for text in m.frozen:
            b.emit("    " + text)
        for name in ("nut_angle", "nut_speed", "nut_current"):
            b.emit(f"    {{der({name})}} = 0.0")
        b.emit("{equivalent_stiffness} = {k_eq}")

    def _emit_gap(self, b: Builder, stretch_name: str, stretch: str, rate: str, k: str,
                  c: str, force: str, held: list[tuple[str, str, str]]) -> None:
        """A gap of the backlash part (:mod:`feeddrive.model.parts.backlash`) at one site:
        the force ``force`` through its dead-zone spring (:func:`gap_force`) and the
        friction-dominated hold (:func:`gap_hold`) on each body of the driven side.

        Parameters
        ----------
        b : Builder
            The model being assembled.
        stretch_name : str
            The signal of the stretch across spring and gap.
        stretch, rate : str
            Code of the stretch [m] and its rate [m/s] at the table.
        k, c : str
            Code of the stiffness [N/m] and the contact damping [N s/m] at the table.
        force : str
            The signal of the transmitted force [N].
        held : list of (str, str, str)
            (hold force signal, driven speed code [m/s], driven mass code [kg]) per body.
        """
        from ..parts.backlash import gap_force, gap_hold

        half, hold = b.p("backlash.half_gap"), b.p("backlash.hold_time")
        b.emit(f"{{{stretch_name}}} = ({stretch})")
        b.emit(f"{{{force}}} = {b.use(gap_force)}({{{stretch_name}}}, {rate}, {k}, {c}, "
               f"{half})")
        for signal, speed, mass in held:
            b.emit(f"{{{signal}}} = {b.use(gap_hold)}({{{stretch_name}}}, {speed}, {half}, "
                   f"{mass}, {hold})")

    def _shaft(self, b: Builder, key: str, m: Mechanics, reaction: str) -> Body:
        shaft = Body(drive=[] if m.torque_off else
                     [f"{b.p(key + '_motor.torque_constant')} * {{{key}_current}}"])
        if key in m.ripple:
            shaft.drive.append(f"+ {m.ripple[key]}")
        shaft.external = list(m.forces.get(key, []))
        shaft.reaction = [reaction]
        return shaft

    def _current(self, b: Builder, key: str, speed: str, torque_off: bool,
                 indent: str = "") -> None:
        i = f"{key}_current"
        if torque_off:
            b.emit(f"{indent}{{der({i})}} = 0.0")
            return
        mot = f"{key}_motor"
        b.emit(f"{indent}{{der({i})}} = ({{{key}_voltage}} - {b.p(mot + '.resistance')} * "
               f"{{{i}}} - {b.p(mot + '.back_emf_constant')} * {speed}) / "
               f"{b.p(mot + '.inductance')}")
