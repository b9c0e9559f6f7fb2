/* Hybrid simulation loop: integrate a mode, find the step's event, record, reset or end — all
 * in compiled code, one call per simulation. The pieces live in their own headers:
 *   stepper.h      the integrator seam: a method's step, dense output and restart
 *   amble_steppers.h  the methods (dop853.h, radau.h, ...) at their codes (generated from abi.py)
 *   run.h          where a run stands, loaded from and saved to ctx
 *   flow.h         integrate a step, locate its event, record its rows
 *   transition.h   cross a switching surface, or apply a reset (or end the run)
 *   events.h       guard screening and crossing location inside a step
 *   switch_side.h  a state on a switching surface: the side the flow goes into, sliding
 *   record.h       sample and event rows in caller-owned buffers
 *   rest.h         a contact coming to rest instead of a zeno end (TR_REST)
 *   sensitivity.h  ∂x/∂(x0, p) through flows and events
 *
 * This file is the body of the runtime (runtime.c), compiled once and linked into every model's
 * library; what it knows of the model (model.h) is defined by the model's unit:
 *   the interface codes ST_*, CX_*, OP_*, IO_* and AMBLE_LAYOUT (amble_abi.h, from abi.py)
 *   NMODES, NXMAX, NTR, NPOINTS, NPARAM (run-time constants)
 *   MODE_NX[NMODES], MODE_NTR[NMODES], MODE_TR0[NMODES]
 *   TR_DIR[NTR] (-1 falling, +1 rising, 0 both), TR_TERMINAL[NTR] (1 = ends the run),
 *   TR_STEP[NTR] (1 = counts as a walking step), TR_REST[NTR] (rest transition instead of zeno, or -1)
 *   int rhs(int mode, double t, const double *x, const double *p, double *dx);
 *   void guards(int mode, double t, const double *x, const double *p, double *g);
 *   void guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g);
 *   int enabled(int tr, double t, const double *x, const double *p);
 *   int reset(int tr, double t, const double *x, const double *p, double *xout, int *target);
 *   void dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G);
 *   void energy(int mode, double t, const double *x, const double *p, double *out);
 *   void kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel);
 *   AMBLE_PARAMS(p): replaces the caller's NPARAM parameters p by the array of NPARAM + NHOIST
 *     values that every kernel reads (parameters, then their parameter-only subexpressions);
 *     each exported entry point that calls kernels starts with it (here and in batch.h)
 */
#include <stddef.h>
#include <stdint.h>

#define NSUB_MAX 16

#include "stepper.h"
#include "events.h"
#include "switch_side.h"
#include "record.h"
#include "rest.h"
#include "sensitivity.h"
#include "amble_steppers.h"
#include "run.h"
#include "flow.h"
#include "transition.h"

/* One turn of the loop: the ends checked, a step integrated, its event located, its rows
 * recorded; then on to its end, across a switch, or through a transition. */
static int loop_turn(Run *r) {
    int st;
    Hit e;
    double x_ev[NXMAX];
    if ((st = run_limits(r)) >= 0 || (st = integrate(r, &e)) >= 0 || (st = locate_event(r, &e, x_ev)) >= 0
        || (st = record_step(r, &e)) >= 0)
        return st;
    accept_step(r, &e);
    if (e.k < 0) return advance(r, &e);
    r->s->m->restart(r->s); /* the flow jumps here: what the method keeps of the trajectory is stale */
    return e.k >= MODE_NTR[r->mode] ? cross_switch(r, &e, x_ev) : apply_reset(r, &e, x_ev);
}

/* Simulate from the state in ctx until an end condition; see the CX_, OP_, IO_ layouts.
 * Returns a status ST_*; ST_BUFFER_FULL means "grow the buffers and call again", ST_YIELD (every
 * IO_YIELDN accepted steps) "call again" — the caller handles signals in between, the run resumes
 * exactly where it stopped. IO_MAXISTEPS and IO_MAXISTEPS_EV cap the accepted steps of the run and
 * between transitions (0: no cap). IO_METHOD is the integrator's code (MT_*). sens: NULL, or the
 * sensitivity buffer of sensitivity.h, carried along with the state (a method with a tableau). */
int amble_simulate(const double *p, double *ctx, const double *opt, const int64_t *iopt,
                   double *out_t, int *out_mode, double *out_x, int64_t *n_out,
                   double *ev_t, int *ev_tr, double *ev_xpre, double *ev_xpost, int64_t *n_ev, double *sens) {
    AMBLE_PARAMS(p); /* the parameters and their hoisted subexpressions (backend/hoist.py) */
    const int64_t method = iopt[IO_METHOD];
    if (method < 0 || method >= N_METHODS) return ST_STEP_TOO_SMALL; /* no such integrator: it fails */
    const Stepper *m = STEPPERS[method];
    double state[(m->size() + sizeof(double) - 1) / sizeof(double)]; /* the method's state, for this model */
    double g_old[NTR1], gd_old[NTR1], g_new[NTR1], gd_new[NTR1];
    Run r = {.p = p, .ctx = ctx, .sens = sens, .s = (Step *)state, .isteps_call = 0,
             .g_old = g_old, .gd_old = gd_old, .g_new = g_new, .gd_new = gd_new};
    r.rec = (Rec){out_t, out_x, ev_t, ev_xpre, ev_xpost, out_mode, ev_tr, n_out, n_ev, iopt[IO_OUTCAP], iopt[IO_EVCAP]};
    r.recording = r.rec.out_cap > 0, r.ev_recording = r.rec.ev_cap > 0;
    settings_read(&r.o, opt, iopt);
    r.s->m = m;
    m->init(r.s);
    int status = run_load(&r);
    if (status >= 0) return status;
    status = run_arm(&r);
    while (status < 0) status = loop_turn(&r);
    run_save(&r);
    return status;
}

/* ---- thin exported wrappers for analysis from Python (rows = many states at once) ---- */
int amble_rhs(int mode, double t, const double *x, const double *p, double *dx) {
    AMBLE_PARAMS(p);
    return rhs(mode, t, x, p, dx);
}

void amble_guards(int mode, double t, const double *x, const double *p, double *g) {
    AMBLE_PARAMS(p);
    guards(mode, t, x, p, g);
}

int amble_reset(int tr, double t, const double *x, const double *p, double *xout, int *target) {
    AMBLE_PARAMS(p);
    return reset(tr, t, x, p, xout, target);
}

int amble_rhs_jac(int mode, double t, const double *x, const double *p, double *dx, double *J) {
    AMBLE_PARAMS(p);
    return rhs_jac(mode, t, x, p, dx, J);
}

int amble_rhs_jacp(int mode, double t, const double *x, const double *p, double *J) {
    AMBLE_PARAMS(p);
    return rhs_jacp(mode, t, x, p, J);
}

/* dx and the whole Jacobian row block [∂f/∂x, ∂f/∂p] (nx rows of SC columns) in one call. */
int amble_rhs_jac_all(int mode, double t, const double *x, const double *p, double *dx, double *J) {
    AMBLE_PARAMS(p);
    return rhs_jac(mode, t, x, p, dx, J) || rhs_jacp(mode, t, x, p, J);
}

void amble_surfaces_grad(int mode, double t, const double *x, const double *p, double *G) {
    AMBLE_PARAMS(p);
    surfaces_grad(mode, t, x, p, G);
}

int amble_reset_jac(int tr, double t, const double *x, const double *p, double *D) {
    AMBLE_PARAMS(p);
    return reset_jac(tr, t, x, p, D);
}

void amble_dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G) {
    AMBLE_PARAMS(p);
    dynamics(mode, t, x, p, M, h, G);
}

void amble_rows_energy(int64_t nrows, const double *t, const int *mode, const double *x, const double *p, double *out) {
    AMBLE_PARAMS(p);
    for (int64_t r = 0; r < nrows; ++r) energy(mode[r], t[r], x + r * NXMAX, p, out + 2 * r);
}

void amble_rows_kinematics(int64_t nrows, const double *t, const int *mode, const double *x, const double *p,
                           double *pos, double *vel) {
    AMBLE_PARAMS(p);
    for (int64_t r = 0; r < nrows; ++r)
        kinematics(mode[r], t[r], x + r * NXMAX, p, pos + r * NPOINTS * 3, vel + r * NPOINTS * 3);
}

/* Many states per call: the operation op (ROP_*, abi.py) of mode `mode` at each of the n states
 * x + r * xs, times t[r * ts] and parameters p + r * ps (ps = 0: one vector for all), into
 * out + r * os. Returns the first row whose kernel failed (a singular mass matrix; the rows after
 * it are not evaluated), -1 if none, -2 for an unknown op. */
int64_t amble_rows(int64_t n, int op, int mode, const double *t, int64_t ts, const double *x, int64_t xs,
                   const double *p, int64_t ps, double *out, int64_t os) {
    if (op < ROP_RHS || op > ROP_CONSTRAINT_FORCES) return -2;
    const int nx = MODE_NX[mode], nq = nx / 2;
    double pf[NPFULL];
    for (int64_t r = 0; r < n; ++r) {
        if (r == 0 || ps) amble_k_params(p + r * ps, pf); /* hoisted once per parameter vector */
        const double *xr = x + r * xs, tr = t[r * ts];
        double *o = out + r * os;
        int err = 0;
        if (op == ROP_RHS) err = rhs(mode, tr, xr, pf, o);
        else if (op == ROP_DYNAMICS) dynamics(mode, tr, xr, pf, o, o + nq * nq, o + nq * nq + nq);
        else if (op == ROP_RHS_JAC) err = rhs_jac(mode, tr, xr, pf, o, o + nx) || rhs_jacp(mode, tr, xr, pf, o + nx);
        else err = constraint_forces(mode, tr, xr, pf, o);
        if (err) return r;
    }
    return -1;
}

void amble_info(int64_t *out) {
    out[0] = NMODES;
    out[1] = NXMAX;
    out[2] = NTR;
    out[3] = NPOINTS;
    out[4] = NPARAM;
    out[5] = CX_X;
    out[6] = AMBLE_LAYOUT;
    out[7] = SC;
    out[8] = AMBLE_CAT(amble_nxcap_, AMBLE_NXCAP); /* the integrator's capacity (model_tail.h) */
}

/* ---- many walks per call (basin maps, sweeps) ---- */
#include "batch.h"
