/* feeddrive FMU wrapper: the FMI 2.0 / 3.0 functions around a generated drive model.
 *
 * Compiled after the generated parts in one translation unit (feeddrive.fmu.build):
 *   - the model (feeddrive.model.c_backend): FD_N_STATE, FD_N_AUX, FD_N_HELD, FD_N_PARAM,
 *     FD_N_TABLE, fd_rhs(), fd_sample_update();
 *   - the integrator (feeddrive.solvers.driver specialised COMM, translated): FD_ADVANCE();
 *   - the variable tables (feeddrive.fmu.description): VR_KIND/VR_A/VR_B, start values.
 * Nothing here is physics: the wrapper moves values between the importer and the arrays the
 * generated code reads (states y, held controller values, parameters P, data table T).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if FMU_FMI_VERSION == 2
#include "fmi2Functions.h"
#else
#include "fmi3Functions.h"
#endif

/* a change of time, state, input or parameter: the cached Jacobian is stale */
#if FMU_KIND_ME
#define FMU_TOUCH(m) ((m)->jac_valid = 0)
#else
#define FMU_TOUCH(m) ((void)(m))
#endif
/* one input block per drive or machine axis (BLOCK_*): its commanded positions and speeds,
   its load force, and two reference integrals (table, nut) */
#define N_REF_STATES (2 * N_BLOCK)
#define N_CSTATES (FD_N_STATE + N_REF_STATES)
#define N_WORK 10

typedef struct {
    double t, t0, stop_time;
    double y[N_CSTATES];
    double dy[N_CSTATES];
    double held[FD_N_HELD], held_prev[FD_N_HELD];
    double P[FD_N_PARAM];
    double T[FD_N_TABLE];
    double aux[FD_N_AUX];
    double u[N_INPUT], du[N_INPUT];
    double s[N_SETTING];
    double atol[FD_N_STATE], rel[FD_N_STATE];
    double work[N_WORK][FD_N_STATE];
    double memory[FD_MEMORY_SIZE];
    double base, next_event;
    long steps[FD_N_CLOCK], tick[FD_N_CLOCK], k_event;
    double evaluations[2];  /* fd_rhs and tangent evaluations (model exchange counters) */
#if FMU_KIND_ME
    /* directional derivatives: the tangent's seeds and results, the Jacobian of the
       derivatives by the states at the current point (valid while jac_valid) */
    double y_d[N_CSTATES], u_d[N_INPUT], dy_d[N_CSTATES], aux_d[FD_N_AUX];
    double P_d[FD_N_PARAM], T_d[FD_N_TABLE], dy_s[N_CSTATES], aux_s[FD_N_AUX];
    double jac[N_CSTATES][N_CSTATES];
    int jac_valid, warned_swap;
#endif
    int sampled, inputs_changed, dirty, initialized, terminated, logging, model_exchange;
    char name[256];
#if FMU_FMI_VERSION == 2
    fmi2CallbackFunctions cb;
#else
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
#endif
} Fmu;

enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 };

static void fmu_log(Fmu *m, int status, const char *message) {
#if FMU_FMI_VERSION == 2
    if (m->cb.logger)
        m->cb.logger(m->cb.componentEnvironment, m->name, (fmi2Status)status,
                     status >= ST_ERROR ? "logStatusError" : "logAll", "%s", message);
#else
    if (m->log)
        m->log(m->env, (fmi3Status)status,
               status >= ST_ERROR ? "logStatusError" : "logAll", message);
#endif
}

static Fmu *fmu_new(const char *name, int model_exchange) {
    Fmu *m = (Fmu *)calloc(1, sizeof(Fmu));
    if (!m) return NULL;
    strncpy(m->name, name ? name : "feeddrive", sizeof(m->name) - 1);
    m->model_exchange = model_exchange;
    return m;
}

/* start values: the state of an instance after instantiation or reset */
static void fmu_defaults(Fmu *m) {
    int i;
    memset(m->y, 0, sizeof(m->y));
    for (i = 0; i < FD_N_STATE; i++) m->y[i] = Y_START[i];
    memset(m->held, 0, sizeof(m->held));
    memcpy(m->P, P_START, sizeof(m->P));
    memcpy(m->T, T_START, sizeof(m->T));
    memcpy(m->u, U_START, sizeof(m->u));
    memset(m->du, 0, sizeof(m->du));
    memcpy(m->s, S_START, sizeof(m->s));
    m->evaluations[0] = m->evaluations[1] = 0.0;
    m->t = 0.0;
    m->t0 = 0.0;
    m->initialized = 0;
    m->terminated = 0;
    m->dirty = 1; FMU_TOUCH(m);
}

/* the reference block of T (feeddrive.model.reference.REF_INPUT) and the load slot, from the inputs;
   the commanded positions are the inputs or the integrals of the speed references */
static void fmu_write_inputs(Fmu *m, int with_rates) {
    int integrate = m->s[S_INTEGRATE] > 0.5, k;
    for (k = 0; k < N_BLOCK; k++) {
        const double *u = m->u + k * N_IN_BLOCK, *du = m->du + k * N_IN_BLOCK;
        const double *x = m->y + FD_N_STATE + 2 * k;
        double *T = m->T + BLOCK_TABLE[k];
        T[0] = integrate ? x[0] : u[IN_XT];
        T[2] = u[IN_VT];
        T[3] = with_rates ? du[IN_VT] : 0.0;
        T[4] = integrate ? x[1] : u[IN_XN];
        T[6] = u[IN_VN];
        T[7] = with_rates ? du[IN_VN] : 0.0;
        m->P[BLOCK_INSTANT[k]] = m->t;
        m->P[BLOCK_LOAD[k]] = u[IN_LOAD];
    }
}

/* the rates of the reference integrals: the speed inputs */
static void fmu_reference_rates(double *dy, const double *u) {
    int k;
    for (k = 0; k < N_BLOCK; k++) {
        dy[FD_N_STATE + 2 * k] = u[k * N_IN_BLOCK + IN_VT];
        dy[FD_N_STATE + 2 * k + 1] = u[k * N_IN_BLOCK + IN_VN];
    }
}

/* derivatives and signals at (t, y) (model exchange; co-simulation after a step) */
static void fmu_evaluate(Fmu *m) {
    if (!m->dirty) return;
    if (m->model_exchange) fmu_write_inputs(m, 0);
    fd_rhs(m->t, m->y, m->held, m->P, m->T, m->dy, m->aux);
    m->evaluations[0] += 1.0;
    fmu_reference_rates(m->dy, m->u);
    m->dirty = 0;
}

#if FMU_KIND_ME
/* ---- directional derivatives (model exchange): the model's tangent, generated from its
   kernels (feeddrive.backends.tangent), evaluated at the current point for the seeds
   m->y_d (continuous states) and m->u_d (inputs); the inputs reach the model through the
   reference block of T and the load slot of P, as fmu_write_inputs puts them there */
static void fmu_tangent(Fmu *m) {
    int integrate = m->s[S_INTEGRATE] > 0.5, k, load = 0;
    fmu_evaluate(m);  /* P and T hold the current inputs */
    memset(m->T_d, 0, sizeof(m->T_d));
    for (k = 0; k < N_BLOCK; k++) {
        const double *u_d = m->u_d + k * N_IN_BLOCK, *x_d = m->y_d + FD_N_STATE + 2 * k;
        double *T_d = m->T_d + BLOCK_TABLE[k];
        T_d[0] = integrate ? x_d[0] : u_d[IN_XT];
        T_d[2] = u_d[IN_VT];
        T_d[4] = integrate ? x_d[1] : u_d[IN_XN];
        T_d[6] = u_d[IN_VN];
        load |= u_d[IN_LOAD] != 0.0;
    }
    if (load) {  /* the load forces are parameter slots: P varies too */
        memset(m->P_d, 0, sizeof(m->P_d));
        for (k = 0; k < N_BLOCK; k++)
            m->P_d[BLOCK_LOAD[k]] = m->u_d[k * N_IN_BLOCK + IN_LOAD];
        fd_rhs_tangent_all(m->t, m->y, m->held, m->P, m->T, m->dy_s, m->aux_s, m->y_d,
                           m->P_d, m->T_d, m->dy_d, m->aux_d);
    } else {
        fd_rhs_tangent(m->t, m->y, m->held, m->P, m->T, m->dy_s, m->aux_s, m->y_d, m->T_d,
                       m->dy_d, m->aux_d);
    }
    fmu_reference_rates(m->dy_d, m->u_d);
    m->evaluations[1] += 1.0;
}

/* the Jacobian of the derivatives by the continuous states at the current point: one tangent
   evaluation per group of columns that share no row of the declared pattern (JAC_GROUP, the
   model's colouring), each entry taken from its column's group */
static void fmu_jacobian(Fmu *m) {
    int g, i, j, members;
    if (m->jac_valid) return;
    memset(m->u_d, 0, sizeof(m->u_d));
    for (g = 0; g < JAC_N_GROUPS; g++) {
        members = 0;
        for (j = 0; j < N_CSTATES; j++) {
            m->y_d[j] = JAC_GROUP[j] == g ? 1.0 : 0.0;
            members += JAC_GROUP[j] == g;
        }
        if (members == 0) continue;
        fmu_tangent(m);
        for (j = 0; j < N_CSTATES; j++) {
            if (JAC_GROUP[j] != g) continue;
            for (i = 0; i < N_CSTATES; i++) {
                int declared = members == 1 ||
                               (i < FD_N_STATE && j < FD_N_STATE && JAC_PATTERN[i * FD_N_STATE + j]);
                m->jac[i][j] = declared ? m->dy_d[i] : 0.0;
            }
        }
    }
    m->jac_valid = 1;
}

/* out = J·seed for the derivatives `rows` by the continuous states `columns` (with their
   seeds), from the cached Jacobian; a row or column is the state index VR_A of its value
   reference (a derivative's or a state's alike: fmu_swapped) */
static int fmu_jacobian_product(Fmu *m, const unsigned int *rows, size_t n_rows,
                                const unsigned int *columns, size_t n_columns,
                                const double *seed, double *out) {
    double seed_y[N_CSTATES];
    size_t k;
    int j;
    memset(seed_y, 0, sizeof(seed_y));
    for (k = 0; k < n_columns; k++) seed_y[VR_A[columns[k]]] += seed[k];
    fmu_jacobian(m);
    for (k = 0; k < n_rows; k++) {
        double sum = 0.0;
        int i = VR_A[rows[k]];
        for (j = 0; j < N_CSTATES; j++) sum += m->jac[i][j] * seed_y[j];
        out[k] = sum;
    }
    return ST_OK;
}

/* A request with every unknown a continuous state and every known a derivative has no FMI
   meaning (a state is not a function of its rate); pathsim-fmi 0.1.1 asks its state Jacobian
   so (it reads fmpy's `derivative` attribute the wrong way round).  The only sensible answer
   is the Jacobian of those states' derivatives by the states whose rates it names: given, with
   a warning once per instance, so that importer gets the Jacobian it means. */
static int fmu_swapped(Fmu *m, const unsigned int *unknowns, size_t n_unknown,
                       const unsigned int *knowns, size_t n_known) {
    size_t k;
    if (n_unknown == 0 || n_known == 0) return 0;
    for (k = 0; k < n_unknown; k++)
        if ((int)unknowns[k] >= N_VR || VR_KIND[unknowns[k]] != K_STATE) return 0;
    for (k = 0; k < n_known; k++)
        if ((int)knowns[k] >= N_VR || VR_KIND[knowns[k]] != K_DER) return 0;
    if (!m->warned_swap) {
        fmu_log(m, ST_WARNING, "directional derivative of continuous states by derivatives: "
                "answered as the derivatives' Jacobian by the states (unknowns and knowns "
                "swapped, as pathsim-fmi 0.1.1 asks)");
        m->warned_swap = 1;
    }
    return 1;
}

/* FMI directional derivative: unknowns (derivatives, states, signals, outputs) by knowns
   (continuous states, inputs) along seed */
static int fmu_directional(Fmu *m, const unsigned int *unknowns, size_t n_unknown,
                           const unsigned int *knowns, size_t n_known, const double *seed,
                           double *out) {
    size_t k;
    int only_derivatives = 1, only_states = 1;
    char msg[300];
    if (!m->initialized) {
        fmu_log(m, ST_ERROR, "directional derivatives are defined after initialisation");
        return ST_ERROR;
    }
    if (fmu_swapped(m, unknowns, n_unknown, knowns, n_known))
        return fmu_jacobian_product(m, unknowns, n_unknown, knowns, n_known, seed, out);
    memset(m->y_d, 0, sizeof(m->y_d));
    memset(m->u_d, 0, sizeof(m->u_d));
    for (k = 0; k < n_known; k++) {
        int vr = (int)knowns[k];
        if (vr < 0 || vr >= N_VR || (VR_KIND[vr] != K_STATE && VR_KIND[vr] != K_INPUT)) {
            snprintf(msg, sizeof msg, "directional derivative by value reference %d: expected "
                     "a continuous state or an input", vr);
            fmu_log(m, ST_ERROR, msg);
            return ST_ERROR;
        }
        if (VR_KIND[vr] == K_STATE) m->y_d[VR_A[vr]] += seed[k];
        else { m->u_d[VR_A[vr]] += seed[k]; only_states = 0; }
    }
    for (k = 0; k < n_unknown; k++) {
        int vr = (int)unknowns[k], kind = vr >= 0 && vr < N_VR ? VR_KIND[vr] : -1;
        if (kind != K_DER && kind != K_STATE && kind != K_AUX && kind != K_PRODUCT &&
            kind != K_ERROR) {
            snprintf(msg, sizeof msg, "directional derivative of value reference %d: expected "
                     "a derivative, state, signal or output", vr);
            fmu_log(m, ST_ERROR, msg);
            return ST_ERROR;
        }
        only_derivatives &= kind == K_DER;
    }
    if (only_derivatives && only_states)  /* the importer's Jacobian: from the cache */
        return fmu_jacobian_product(m, unknowns, n_unknown, knowns, n_known, seed, out);
    fmu_tangent(m);
    for (k = 0; k < n_unknown; k++) {
        int vr = (int)unknowns[k], a = VR_A[vr], b = VR_B[vr];
        switch (VR_KIND[vr]) {
        case K_DER: out[k] = m->dy_d[a]; break;
        case K_STATE: out[k] = m->y_d[a]; break;
        case K_AUX: out[k] = m->aux_d[a]; break;
        case K_PRODUCT: out[k] = m->P[a] * m->y_d[b]; break;
        default: out[k] = m->aux_d[a] - m->y_d[b]; break;  /* K_ERROR */
        }
    }
    return ST_OK;
}
#endif

/* the sample schedule (feeddrive.solvers.schedule): the loop periods of the settings go into
   their parameter slots, then every clock of the model (CLOCK_SLOT) is put on one grid */
static int fmu_sampling(Fmu *m) {
    double base = 0.0, period;
    int i;
    char msg[200];
    for (i = 0; i < N_PERIOD; i++) {  /* each loop's period setting (PERIOD_SETTING) */
        period = m->s[PERIOD_SETTING[i]];
        if (!(period >= 0.0) || !isfinite(period)) {
            snprintf(msg, sizeof msg, "%s = %g: expected a period >= 0 [s]", PERIOD_NAMES[i],
                     period);
            fmu_log(m, ST_ERROR, msg);
            return ST_ERROR;
        }
        m->P[PERIOD_SLOT[i]] = period;
    }
    for (i = 0; i < FD_N_CLOCK; i++) {
        period = m->P[CLOCK_SLOT[i]];
        if (period > 0.0 && (base == 0.0 || period < base)) base = period;
    }
    for (i = 0; i < FD_N_CLOCK; i++) {
        period = m->P[CLOCK_SLOT[i]];
        m->steps[i] = period > 0.0 ? (long)floor(period / base + 0.5) : 0;
        if (period > 0.0 && fabs(m->steps[i] * base - period) > 1e-9 * period) {
            snprintf(msg, sizeof msg, "%s = %g: must be an integer multiple of the fastest "
                     "controller period %g [s]", CLOCK_NAMES[i], period, base);
            fmu_log(m, ST_ERROR, msg);
            return ST_ERROR;
        }
    }
    /* each sampled part integrates over the spacing of its instants on the grid
       (feeddrive.engine.simulate.Sampling.parameters) */
    for (i = 0; i < FD_N_CLOCK; i++)
        if (m->steps[i] > 0) m->P[CLOCK_SLOT[i]] = m->steps[i] * base;
    m->base = base > 0.0 ? base : 1.0;
    m->sampled = base > 0.0;
    return ST_OK;
}

static int fmu_check_settings(Fmu *m) {
    int i;
    char msg[200];
    for (i = 0; i < N_SETTING; i++) {
        if (IS_PERIOD_SETTING[i] || i == S_INTEGRATE)
            continue;
        if (!(m->s[i] > 0.0) || !isfinite(m->s[i])) {
            snprintf(msg, sizeof msg, "%s = %g: expected a finite value > 0", SETTING_NAMES[i],
                     m->s[i]);
            fmu_log(m, ST_ERROR, msg);
            return ST_ERROR;
        }
    }
    for (i = 0; i < FD_N_STATE; i++) {
        m->atol[i] = ATOL_POSITION[i] * m->s[S_POSITION_TOL] + ATOL_SPEED[i] * m->s[S_SPEED_TOL]
                     + ATOL_CURRENT[i] * m->s[S_CURRENT_TOL];
        m->rel[i] = REL_MASK[i];
    }
    return ST_OK;
}

/* leave initialisation: sampling grid, the controller sampled at t0, the signals there */
static int fmu_initialize(Fmu *m) {
    int i;
    if (fmu_sampling(m) != ST_OK || fmu_check_settings(m) != ST_OK) return ST_ERROR;
    for (i = 0; i < FD_MEMORY_SIZE; i++) m->memory[i] = 0.0;
    m->memory[FD_MEM_H] = 1e-6;
    m->memory[FD_MEM_ERR] = 1e-4;
    for (i = 0; i < N_BLOCK; i++) {  /* the speed integrals start at the position inputs */
        m->y[FD_N_STATE + 2 * i] = m->u[i * N_IN_BLOCK + IN_XT];
        m->y[FD_N_STATE + 2 * i + 1] = m->u[i * N_IN_BLOCK + IN_XN];
    }
    m->t = m->t0;
    fmu_write_inputs(m, !m->model_exchange);
    memcpy(m->held_prev, m->held, sizeof(m->held));
    if (FD_DUE(0, m->steps, m->tick) > 0)
        fd_sample_update(m->t, m->y, m->held, m->P, m->T, m->tick);
    m->memory[FD_MEM_AT_SAMPLE] = 1.0;
    m->k_event = 0;
    m->next_event = m->t0 + (m->sampled ? FD_NEXT_INSTANT(0, m->steps) : 1) * m->base;
    m->inputs_changed = 0;
    m->dirty = 1; FMU_TOUCH(m);
    fmu_evaluate(m);
    m->initialized = 1;
    return ST_OK;
}

static int fmu_do_step(Fmu *m, double t, double h) {
    long status, max_steps = (long)m->s[S_MAX_STEPS];
    int redo, i;
    double t_end = t + h, instants;
    char msg[400];
    if (!m->initialized || m->terminated) return ST_ERROR;
    if (fabs(t - m->t) > 1e-9 * (fabs(t) + 1.0)) {
        snprintf(msg, sizeof msg, "doStep at t = %.17g s, but the FMU is at t = %.17g s", t, m->t);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    if (!(h >= 0.0) || !isfinite(h)) {
        snprintf(msg, sizeof msg, "communicationStepSize = %g: expected a finite step >= 0 [s]",
                 h);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    /* the sample instants in (t, t_end]: bounded before any work (solver.max_steps_per_call
       bounds the integrator's steps below, inside the integrator) */
    instants = m->sampled ? floor((t_end - m->t0) / m->base) - floor((t - m->t0) / m->base) : 0.0;
    if (instants > (double)max_steps) {
        snprintf(msg, sizeof msg, "solver.max_steps_per_call = %ld: the communication step "
                 "[%.9g, %.9g] s holds %.0f sample instants of the %g-s controller grid; take "
                 "shorter communication steps or raise solver.max_steps_per_call", max_steps,
                 t, t_end, instants, m->base);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    redo = m->inputs_changed;
    m->inputs_changed = 0;
    fmu_write_inputs(m, 1);
    /* the integrator stops after more than its limit: max_steps - 1 lets it take at most
       max_steps steps (accepted and rejected) */
    status = FD_ADVANCE(m->t, t_end, m->t0, (long)FD_N_STATE, m->y, m->held, m->held_prev, m->P,
                        m->T, m->steps, m->tick, m->base, m->s[S_RTOL], m->atol,
                        m->rel, m->s[S_MAX_STEP], max_steps - 1, (long)redo,
                        m->memory, m->work[0], m->work[1], m->work[2], m->work[3], m->work[4],
                        m->work[5], m->work[6], m->work[7], m->work[8], m->work[9], m->aux);
    if (status == 1) {
        /* the step cap alone asks for more steps than allowed: say so (a solver.max_step of
           1e-300 s read as a stiff drive) */
        double capped = (t_end - t) / m->s[S_MAX_STEP];
        char why[160];
        if (capped > (double)max_steps)
            snprintf(why, sizeof why, "solver.max_step = %.3g s alone asks for %.3g steps",
                     m->s[S_MAX_STEP], capped);
        else
            snprintf(why, sizeof why, "the parameters may make the drive too stiff or "
                     "unstable");
        snprintf(msg, sizeof msg, "solver.max_steps_per_call = %ld: the communication step "
                 "[%.9g, %.9g] s needs more integrator steps; take shorter communication steps "
                 "or raise solver.max_steps_per_call (%s)", max_steps, t, t_end, why);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    if (status != 0) {
        snprintf(msg, sizeof msg, "integration stopped near t = %.9g s: %s", m->t,
                 STATUS_MESSAGES[status < 0 || status > 3 ? 0 : status]);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    /* the speed integrals: exact for speeds held (and ramped at their input rates) */
    for (i = 0; i < N_REF_STATES; i++) {
        int v = (i / 2) * N_IN_BLOCK + (i % 2 == 0 ? IN_VT : IN_VN);
        m->y[FD_N_STATE + i] += m->u[v] * h + 0.5 * m->du[v] * h * h;
    }
    m->t = t_end;
    for (i = 0; i < FD_N_STATE; i++) m->dy[i] = m->work[0][i]; /* f at t_end */
    fmu_reference_rates(m->dy, m->u);
    m->dirty = 0;
    return ST_OK;
}

/* ---- model exchange: time events at the sample instants t0 + k·base */
static void fmu_event_update(Fmu *m, int *next_defined, double *next_time) {
    if (m->sampled) {
        while (m->t >= m->next_event - 1e-9 * m->base) {
            m->k_event = FD_NEXT_INSTANT(m->k_event, m->steps);
            fmu_write_inputs(m, 0);
            FD_DUE(m->k_event, m->steps, m->tick);
            fd_sample_update(m->t, m->y, m->held, m->P, m->T, m->tick);
            m->next_event = m->t0 + FD_NEXT_INSTANT(m->k_event, m->steps) * m->base;
            m->dirty = 1; FMU_TOUCH(m);
        }
        *next_defined = 1;
        *next_time = m->next_event;
    } else {
        *next_defined = 0;
        *next_time = 0.0;
    }
}

/* ---- value references */
static double fmu_get(Fmu *m, int vr) {
    int a = VR_A[vr], b = VR_B[vr];
    switch (VR_KIND[vr]) {
    case K_TIME: return m->t;
    case K_STATE: return m->y[a];
    case K_DER: fmu_evaluate(m); return m->dy[a];
    case K_AUX: fmu_evaluate(m); return m->aux[a];
    case K_PARAM: return m->P[a];
    case K_INPUT: return m->u[a];
    case K_SETTING: case K_BOOLEAN: case K_INTEGER: return m->s[a];
    case K_PRODUCT: return m->P[a] * m->y[b];
    case K_ERROR: fmu_evaluate(m); return m->aux[a] - m->y[b];
    case K_COUNTER: return m->memory[a];
    case K_EVALUATIONS: return m->evaluations[a];
    default: return 0.0;
    }
}

/* whether value lies in the variable's range (description.py: the parameter file's range of
   the field it comes from; VR_RANGE bits: 1 low end excluded, 2 zero allowed, 4 integers) */
static int fmu_in_range(int vr, double value) {
    int flags = VR_RANGE[vr];
    if (!isfinite(value)) return 0;
    if ((flags & 2) && value == 0.0) return 1;
    if ((flags & 4) && value != floor(value)) return 0;
    if ((flags & 1) ? !(value > VR_LOW[vr]) : !(value >= VR_LOW[vr])) return 0;
    return value <= VR_HIGH[vr];
}

/* the importer's relative tolerance (fmi2SetupExperiment, fmi3EnterInitializationMode):
   taken when it lies in solver.relative_tolerance's range (the command line's and the API's),
   else the FMU keeps its own and says so (a warning: the importer's tolerance is a request) */
static void fmu_importer_tolerance(Fmu *m, double tolerance) {
    char msg[300];
    if (fmu_in_range(VR_RTOL, tolerance)) {
        m->s[S_RTOL] = tolerance;
        return;
    }
    snprintf(msg, sizeof msg, "the importer's tolerance %.9g is outside %s %s; "
             "solver.relative_tolerance stays %.9g", tolerance, VR_NAME[VR_RTOL],
             VR_EXPECTED[VR_RTOL], m->s[S_RTOL]);
    fmu_log(m, ST_WARNING, msg);
}

/* set a variable: refused (Error, through the logger, naming it) when FMI does not let the
   importer set it now (VR_SET: 0 never, 1 until initialised, 2 always) or when the value lies
   outside its range */
static int fmu_set(Fmu *m, int vr, double value) {
    int a = VR_A[vr];
    char msg[400];
    if (VR_SET[vr] == 0 || (VR_SET[vr] == 1 && m->initialized)) {
        snprintf(msg, sizeof msg, "%s: %s", VR_NAME[vr], VR_SET[vr] == 0
                 ? "computed by the FMU (an output or local variable), not settable"
                 : "settable only before initialisation ends (a fixed parameter or a start "
                   "value)");
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    if (!fmu_in_range(vr, value)) {
        snprintf(msg, sizeof msg, "%s = %.9g: %s", VR_NAME[vr], value, VR_EXPECTED[vr]);
        fmu_log(m, ST_ERROR, msg);
        return ST_ERROR;
    }
    switch (VR_KIND[vr]) {
    case K_STATE: m->y[a] = value; m->dirty = 1; FMU_TOUCH(m); return ST_OK;
    case K_PARAM:
        m->P[a] = value;
        m->dirty = 1; FMU_TOUCH(m);
        return ST_OK;
    case K_INPUT:
        if (m->u[a] != value) m->inputs_changed = 1;
        m->u[a] = value;
        m->dirty = 1; FMU_TOUCH(m);
        return ST_OK;
    case K_SETTING: case K_BOOLEAN: case K_INTEGER:
        m->s[a] = value;
        return ST_OK;
    default: return ST_ERROR;
    }
}

static int fmu_check_vr(Fmu *m, int vr, int type) {
    static const char *const TYPE_NAMES[] = {"Real", "Boolean", "Integer"};
    char msg[300];
    if (vr < 0 || vr >= N_VR) {
        snprintf(msg, sizeof msg, "unknown value reference %d", vr);
        fmu_log(m, ST_ERROR, msg);
        return 0;
    }
    if (VR_TYPE[vr] != type) {
        snprintf(msg, sizeof msg, "value reference %d (%s) is a %s variable, not %s", vr,
                 VR_NAME[vr], TYPE_NAMES[VR_TYPE[vr]], TYPE_NAMES[type]);
        fmu_log(m, ST_ERROR, msg);
        return 0;
    }
    return 1;
}

#if FMU_FMI_VERSION == 2
/* ======================================================================== FMI 2.0 */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n,
                               const fmi2String categories[]) {
    (void)n; (void)categories;
    ((Fmu *)c)->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Fmu *m;
    (void)fmuResourceLocation; (void)visible;
    if ((fmuType == fmi2ModelExchange) != FMU_KIND_ME) return NULL;
    if (!fmuGUID || strcmp(fmuGUID, INSTANTIATION_TOKEN) != 0) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "GUID does not match this FMU's");
        return NULL;
    }
    m = fmu_new(instanceName, FMU_KIND_ME);
    if (!m) return NULL;
    if (functions) m->cb = *functions;
    m->logging = loggingOn;
    fmu_defaults(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Fmu *m = (Fmu *)c;
    if (toleranceDefined) fmu_importer_tolerance(m, tolerance);
    m->t0 = startTime;
    m->t = startTime;
    m->stop_time = stopTimeDefined ? stopTime : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return fmu_initialize((Fmu *)c) == ST_OK ? fmi2OK : fmi2Error;
}

fmi2Status fmi2Terminate(fmi2Component c) { ((Fmu *)c)->terminated = 1; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) { fmu_defaults((Fmu *)c); return fmi2OK; }

/* every typed get/set goes through fmu_get / fmu_set (checks, messages) */
#define FMU2_ACCESS(NAME, CTYPE, TYPE, TO_FMI, FROM_FMI)                                  \
    fmi2Status fmi2Get##NAME(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,  \
                             CTYPE value[]) {                                             \
        size_t i;                                                                         \
        for (i = 0; i < nvr; i++) {                                                       \
            double v;                                                                     \
            if (!fmu_check_vr((Fmu *)c, (int)vr[i], TYPE)) return fmi2Error;              \
            v = fmu_get((Fmu *)c, (int)vr[i]);                                            \
            value[i] = TO_FMI;                                                            \
        }                                                                                 \
        return fmi2OK;                                                                    \
    }                                                                                     \
    fmi2Status fmi2Set##NAME(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,  \
                             const CTYPE value[]) {                                       \
        size_t i;                                                                         \
        for (i = 0; i < nvr; i++) {                                                       \
            if (!fmu_check_vr((Fmu *)c, (int)vr[i], TYPE)) return fmi2Error;              \
            if (fmu_set((Fmu *)c, (int)vr[i], FROM_FMI) != ST_OK) return fmi2Error;       \
        }                                                                                 \
        return fmi2OK;                                                                    \
    }
FMU2_ACCESS(Real, fmi2Real, T_REAL, v, value[i])
FMU2_ACCESS(Boolean, fmi2Boolean, T_BOOLEAN, v > 0.5 ? fmi2True : fmi2False,
            value[i] ? 1.0 : 0.0)
FMU2_ACCESS(Integer, fmi2Integer, T_INTEGER, v > 2147483647.0 ? 2147483647 : (fmi2Integer)v,
            (double)value[i])
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    Fmu *copy = (Fmu *)malloc(sizeof(Fmu));
    if (!copy) return fmi2Error;
    memcpy(copy, c, sizeof(Fmu));
    if (*s) free(*s);
    *s = copy;
    return fmi2OK;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    if (!s) return fmi2Error;
    memcpy(c, s, sizeof(Fmu));
    return fmi2OK;
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)c;
    free(*s);
    *s = NULL;
    return fmi2OK;
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)c; (void)s;
    *size = sizeof(Fmu);
    return fmi2OK;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte data[],
                                 size_t size) {
    (void)c;
    if (size < sizeof(Fmu)) return fmi2Error;
    memcpy(data, s, sizeof(Fmu));
    return fmi2OK;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte data[], size_t size,
                                   fmi2FMUstate *s) {
    (void)c;
    if (size < sizeof(Fmu)) return fmi2Error;
    if (!*s) *s = malloc(sizeof(Fmu));
    if (!*s) return fmi2Error;
    memcpy(*s, data, sizeof(Fmu));
    return fmi2OK;
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
#if FMU_KIND_ME
    return fmu_directional((Fmu *)c, u, nu, z, nz, dv, dz) == ST_OK ? fmi2OK : fmi2Error;
#else
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    fmu_log((Fmu *)c, ST_ERROR, "directional derivatives: model exchange only");
    return fmi2Error;
#endif
}

/* model exchange */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    int defined;
    double next;
    fmu_event_update((Fmu *)c, &defined, &next);
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = defined ? fmi2True : fmi2False;
    info->nextEventTime = next;
    return fmi2OK;
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation) {
    (void)c; (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    ((Fmu *)c)->t = time;
    ((Fmu *)c)->dirty = 1; FMU_TOUCH((Fmu *)c);
    return fmi2OK;
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi2Error;
    for (i = 0; i < nx; i++) m->y[i] = x[i];
    m->dirty = 1; FMU_TOUCH(m);
    return fmi2OK;
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi2Error;
    fmu_evaluate(m);
    for (i = 0; i < nx; i++) dx[i] = m->dy[i];
    return fmi2OK;
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz) {
    (void)c; (void)z;
    return nz == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi2Error;
    for (i = 0; i < nx; i++) x[i] = m->y[i];
    return fmi2OK;
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    size_t i;
    (void)c;
    if (nx != N_CSTATES) return fmi2Error;
    for (i = 0; i < nx; i++) x_nominal[i] = NOMINAL[i];
    return fmi2OK;
}

/* co-simulation */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    Fmu *m = (Fmu *)c;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (!fmu_check_vr(m, (int)vr[i], T_REAL) || VR_KIND[vr[i]] != K_INPUT) return fmi2Error;
        if (order[i] == 1) {
            if (m->du[VR_A[vr[i]]] != value[i]) m->inputs_changed = 1;
            m->du[VR_A[vr[i]]] = value[i];
        } else if (order[i] > 1) {
            return fmi2Error;
        }
    }
    return fmi2OK;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)c; (void)vr; (void)order; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentCommunicationPoint) {
    (void)noSetFMUStatePriorToCurrentCommunicationPoint;
    return fmu_do_step((Fmu *)c, currentCommunicationPoint, communicationStepSize) == ST_OK
               ? fmi2OK : fmi2Error;
}
fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)c; (void)s;
    *value = fmi2OK;
    return fmi2OK;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s == fmi2LastSuccessfulTime) {
        *value = ((Fmu *)c)->t;
        return fmi2OK;
    }
    return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)c;
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fmi2Discard;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}

#else
/* ======================================================================== FMI 3.0 */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t n,
                               const fmi3String categories[]) {
    (void)n; (void)categories;
    ((Fmu *)c)->logging = loggingOn;
    return fmi3OK;
}

static fmi3Instance fmu3_instantiate(fmi3String instanceName, fmi3String token,
                                     fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                     fmi3LogMessageCallback logMessage, int model_exchange) {
    Fmu *m;
    if (model_exchange != FMU_KIND_ME) return NULL;
    if (!token || strcmp(token, INSTANTIATION_TOKEN) != 0) {
        if (logMessage)
            logMessage(env, fmi3Error, "logStatusError",
                       "instantiation token does not match this FMU's");
        return NULL;
    }
    m = fmu_new(instanceName, model_exchange);
    if (!m) return NULL;
    m->env = env;
    m->log = logMessage;
    m->logging = loggingOn;
    fmu_defaults(m);
    return m;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String token,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback logMessage) {
    (void)resourcePath; (void)visible;
    return fmu3_instantiate(instanceName, token, loggingOn, env, logMessage, 1);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String token,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath; (void)visible; (void)earlyReturnAllowed; (void)required;
    (void)nRequired; (void)intermediateUpdate;
    if (eventModeUsed) return NULL;  /* no clocks: hasEventMode="false" */
    return fmu3_instantiate(instanceName, token, loggingOn, env, logMessage, 0);
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String token, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)token; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)env; (void)logMessage; (void)clockUpdate; (void)lockPreemption;
    (void)unlockPreemption;
    return NULL;
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Fmu *m = (Fmu *)c;
    if (toleranceDefined) fmu_importer_tolerance(m, tolerance);
    m->t0 = startTime;
    m->t = startTime;
    m->stop_time = stopTimeDefined ? stopTime : 0.0;
    return fmi3OK;
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    return fmu_initialize((Fmu *)c) == ST_OK ? fmi3OK : fmi3Error;
}
fmi3Status fmi3EnterEventMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3Terminate(fmi3Instance c) { ((Fmu *)c)->terminated = 1; return fmi3OK; }
fmi3Status fmi3Reset(fmi3Instance c) { fmu_defaults((Fmu *)c); return fmi3OK; }

#define FMU3_ACCESS(NAME, CTYPE, TYPE, TO_FMI, FROM_FMI)                                  \
    fmi3Status fmi3Get##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,   \
                             CTYPE values[], size_t nValues) {                            \
        size_t i;                                                                         \
        if (nValues < nvr) return fmi3Error;                                              \
        for (i = 0; i < nvr; i++) {                                                       \
            double v;                                                                     \
            if (!fmu_check_vr((Fmu *)c, (int)vr[i], TYPE)) return fmi3Error;              \
            v = fmu_get((Fmu *)c, (int)vr[i]);                                            \
            values[i] = TO_FMI;                                                           \
        }                                                                                 \
        return fmi3OK;                                                                    \
    }                                                                                     \
    fmi3Status fmi3Set##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,   \
                             const CTYPE values[], size_t nValues) {                      \
        size_t i;                                                                         \
        if (nValues < nvr) return fmi3Error;                                              \
        for (i = 0; i < nvr; i++) {                                                       \
            if (!fmu_check_vr((Fmu *)c, (int)vr[i], TYPE)) return fmi3Error;              \
            if (fmu_set((Fmu *)c, (int)vr[i], FROM_FMI) != ST_OK) return fmi3Error;       \
        }                                                                                 \
        return fmi3OK;                                                                    \
    }
FMU3_ACCESS(Float64, fmi3Float64, T_REAL, v, values[i])
FMU3_ACCESS(Boolean, fmi3Boolean, T_BOOLEAN, v > 0.5, values[i] ? 1.0 : 0.0)
FMU3_ACCESS(Int64, fmi3Int64, T_INTEGER, (fmi3Int64)v, (double)values[i])

#define FMU3_NO_TYPE(NAME, CTYPE)                                                         \
    fmi3Status fmi3Get##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,   \
                             CTYPE values[], size_t nValues) {                            \
        (void)c; (void)vr; (void)values; (void)nValues;                                   \
        return nvr == 0 ? fmi3OK : fmi3Error;                                             \
    }                                                                                     \
    fmi3Status fmi3Set##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,   \
                             const CTYPE values[], size_t nValues) {                      \
        (void)c; (void)vr; (void)values; (void)nValues;                                   \
        return nvr == 0 ? fmi3OK : fmi3Error;                                             \
    }
FMU3_NO_TYPE(Float32, fmi3Float32)
FMU3_NO_TYPE(Int8, fmi3Int8)
FMU3_NO_TYPE(UInt8, fmi3UInt8)
FMU3_NO_TYPE(Int16, fmi3Int16)
FMU3_NO_TYPE(UInt16, fmi3UInt16)
FMU3_NO_TYPE(Int32, fmi3Int32)
FMU3_NO_TYPE(UInt32, fmi3UInt32)
FMU3_NO_TYPE(UInt64, fmi3UInt64)
FMU3_NO_TYPE(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)c; (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues) {
    (void)c; (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    (void)c; (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    (void)c; (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr,
                                               size_t *n) {
    (void)c; (void)vr; (void)n;
    return fmi3Error;
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)c; (void)dependent; (void)elementIndicesOfDependent; (void)independents;
    (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
    return fmi3Error;
}
fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) {
    Fmu *copy = (Fmu *)malloc(sizeof(Fmu));
    if (!copy) return fmi3Error;
    memcpy(copy, c, sizeof(Fmu));
    if (*s) free(*s);
    *s = copy;
    return fmi3OK;
}
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) {
    if (!s) return fmi3Error;
    memcpy(c, s, sizeof(Fmu));
    return fmi3OK;
}
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) {
    (void)c;
    free(*s);
    *s = NULL;
    return fmi3OK;
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *size) {
    (void)c; (void)s;
    *size = sizeof(Fmu);
    return fmi3OK;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte data[], size_t size) {
    (void)c;
    if (size < sizeof(Fmu)) return fmi3Error;
    memcpy(data, s, sizeof(Fmu));
    return fmi3OK;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte data[], size_t size,
                                   fmi3FMUState *s) {
    (void)c;
    if (size < sizeof(Fmu)) return fmi3Error;
    if (!*s) *s = malloc(sizeof(Fmu));
    if (!*s) return fmi3Error;
    memcpy(*s, data, sizeof(Fmu));
    return fmi3OK;
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    if (nSeed != nKnowns || nSensitivity != nUnknowns) return fmi3Error;
#if FMU_KIND_ME
    return fmu_directional((Fmu *)c, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity)
               == ST_OK ? fmi3OK : fmi3Error;
#else
    (void)unknowns; (void)knowns; (void)seed; (void)sensitivity;
    fmu_log((Fmu *)c, ST_ERROR, "directional derivatives: model exchange only");
    return fmi3Error;
#endif
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)c; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed;
    (void)nSeed; (void)sensitivity; (void)nSensitivity;
    return fmi3Error;
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }
fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier q[]) {
    (void)c; (void)vr; (void)nvr; (void)intervals; (void)q;
    return fmi3Error;
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier q[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)q;
    return fmi3Error;
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[]) {
    (void)c; (void)vr; (void)nvr; (void)shifts;
    return fmi3Error;
}
fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    (void)c; (void)vr; (void)nvr; (void)intervals;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
    (void)c; (void)vr; (void)nvr; (void)shifts;
    return fmi3Error;
}
fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    int defined = 0;
    double next = 0.0;
    if (((Fmu *)c)->model_exchange) fmu_event_update((Fmu *)c, &defined, &next);
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = defined ? fmi3True : fmi3False;
    *nextEventTime = next;
    return fmi3OK;
}
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    (void)c; (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = fmi3False;
    *terminateSimulation = fmi3False;
    return fmi3OK;
}
fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) {
    ((Fmu *)c)->t = time;
    ((Fmu *)c)->dirty = 1; FMU_TOUCH((Fmu *)c);
    return fmi3OK;
}
fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi3Error;
    for (i = 0; i < nx; i++) m->y[i] = x[i];
    m->dirty = 1; FMU_TOUCH(m);
    return fmi3OK;
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi3Error;
    fmu_evaluate(m);
    for (i = 0; i < nx; i++) dx[i] = m->dy[i];
    return fmi3OK;
}
fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t nz) {
    (void)c; (void)z;
    return nz == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx) {
    Fmu *m = (Fmu *)c;
    size_t i;
    if (nx != N_CSTATES) return fmi3Error;
    for (i = 0; i < nx; i++) x[i] = m->y[i];
    return fmi3OK;
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[],
                                             size_t nx) {
    size_t i;
    (void)c;
    if (nx != N_CSTATES) return fmi3Error;
    for (i = 0; i < nx; i++) nominals[i] = NOMINAL[i];
    return fmi3OK;
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) {
    (void)c;
    *n = 0;
    return fmi3OK;
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) {
    *n = ((Fmu *)c)->model_exchange ? N_CSTATES : 0;
    return fmi3OK;
}
fmi3Status fmi3EnterStepMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 order[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)c; (void)vr; (void)order; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    int status;
    (void)noSetFMUStatePriorToCurrentPoint;
    status = fmu_do_step((Fmu *)c, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = ((Fmu *)c)->t;
    return status == ST_OK ? fmi3OK : fmi3Error;
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)c; (void)clockReference; (void)activationTime;
    return fmi3Error;
}
#endif
