/* Hybrid simulation loop: integrate a mode, find the step's event, record, reset or end — all
 * in compiled code, one call per simulation. The pieces live in their own headers:
 *   dop853.h  the integrator's state (its step is compiled in the model's unit: dop853_step.h)
 *   radau.h   the implicit integrator for stiff runs (IO_METHOD = 1), same dense-output contract
 *   events.h  guard screening and crossing location inside a step
 *   record.h  sample and event rows in caller-owned buffers
 *   rest.h    a contact coming to rest instead of a zeno end (TR_REST)
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
#include <stdint.h>

#define NSUB_MAX 16

#include "dop853.h"
#include "events.h"
#include "radau.h"
#include "record.h"
#include "rest.h"
#include "sensitivity.h"

/* Simulate from the state in ctx until an end condition; see the CX_, OP_, IO_ layouts.
 * Returns a status ST_*; ST_BUFFER_FULL means "grow the buffers and call again", ST_YIELD (every
 * IO_YIELDN accepted steps) "call again" — the caller handles signals in between, the run resumes
 * exactly where it stopped. IO_MAXISTEPS and IO_MAXISTEPS_EV cap the accepted steps of the run and
 * between transitions (0: no cap). sens: NULL, or the sensitivity buffer of sensitivity.h, carried
 * along with the state. */
int amble_simulate(const double *p, double *ctx, const double *opt, const int64_t *iopt,
                   double *out_t, int *out_mode, double *out_x, int64_t *n_out,
                   double *ev_t, int *ev_tr, double *ev_xpre, double *ev_xpost, int64_t *n_ev, double *sens) {
    AMBLE_PARAMS(p); /* the parameters and their hoisted subexpressions (backend/hoist.py) */
    Rec rec = {out_t, out_x, ev_t, ev_xpre, ev_xpost, out_mode, ev_tr, n_out, n_ev, iopt[IO_OUTCAP], iopt[IO_EVCAP]};
    const int recording = rec.out_cap > 0, ev_recording = rec.ev_cap > 0;
    const double t_end = opt[OP_TEND], rtol = opt[OP_RTOL], atol = opt[OP_ATOL];
    const double max_step_time = opt[OP_MAXSTEPTIME], sample_dt = opt[OP_SAMPLEDT];
    const double zeno_dt = opt[OP_ZENODT];
    const int64_t max_steps = iopt[IO_MAXSTEPS], max_events = iopt[IO_MAXEVENTS], zeno_n = iopt[IO_ZENON];
    const int64_t max_isteps = iopt[IO_MAXISTEPS], max_isteps_ev = iopt[IO_MAXISTEPS_EV], yield_n = iopt[IO_YIELDN];
    int64_t isteps_call = 0;
    int nsub = (int)iopt[IO_NSUB];
    if (nsub < 1) nsub = 1;
    if (nsub > NSUB_MAX) nsub = NSUB_MAX;

    Dop s;
    s.radau = 0;
    const int implicit = iopt[IO_METHOD] == 1;
    Radau rad;
    /* the implicit integrator's matrices, for this model's size; none for an explicit run */
    double rad_w[implicit ? radau_doubles() : 1];
    int rad_iw[implicit ? radau_ints() : 1];
    radau_attach(&rad, rad_w, rad_iw);
    radau_reset(&rad);
    int mode = (int)ctx[CX_MODE];
    if (mode < 0 || mode >= NMODES) return ST_RESET_FAILED;
    s.n = MODE_NX[mode];
    double t = ctx[CX_T];
    for (int i = 0; i < s.n; ++i) s.y_old[i] = ctx[CX_X + i];
    if (!all_finite(s.n, s.y_old)) return ST_NONFINITE;
    if (ctx[CX_FRESH] != 0.0) {
        if (recording) {
            if (*n_out + 1 > rec.out_cap) return ST_BUFFER_FULL;
            put_row(&rec, t, mode, s.n, s.y_old);
        }
        ctx[CX_FRESH] = 0.0;
    }
    if (rhs(mode, t, s.y_old, p, s.f_old)) return ST_SINGULAR_MASS;
    double max_step = opt[OP_MAXSTEP] > 0 ? opt[OP_MAXSTEP] : INFINITY;
    double h_abs = ctx[CX_H];
    if (!(h_abs > 0.0)) h_abs = initial_step(mode, t, s.y_old, s.f_old, p, t_end, max_step, rtol, atol, s.n);
    double g_old[NTR1], gd_old[NTR1], gd_new[NTR1];
    surfaces(mode, t, s.y_old, p, g_old);
    surfaces_dot(mode, t, s.y_old, s.f_old, p, gd_old);
    arm_zero_guards(mode, t, s.y_old, s.f_old, p, s.n, g_old, gd_old, -1);
    int status = -1, zs;
    /* the step size before a switching surface spoiled a step: resumed once it is crossed */
    double h_resume = 0.0;
    if ((zs = resolve_zero_switches(mode, t, s.y_old, p, g_old, s.n, -1)) >= 0) {
        ctx[CX_INFO] = MODE_SW0[mode] + (zs - MODE_NTR[mode]);
        status = ST_SLIDING;
    }

    while (status < 0) {
        if (t >= t_end) { status = ST_END_TIME; break; }
        if (max_step_time > 0.0 && t - ctx[CX_TLAST_STEP] >= max_step_time) { status = ST_STEP_TIMEOUT; break; }
        if (max_isteps > 0 && ctx[CX_ISTEPS] >= (double)max_isteps) { status = ST_MAX_ISTEPS; break; }
        if (max_isteps_ev > 0 && ctx[CX_ISTEPS_EV] >= (double)max_isteps_ev) { status = ST_STALLED; break; }
        if (yield_n > 0 && isteps_call >= yield_n) { status = ST_YIELD; break; }
        double t_bound = t_end;
        if (max_step_time > 0.0 && ctx[CX_TLAST_STEP] + max_step_time < t_bound) t_bound = ctx[CX_TLAST_STEP] + max_step_time;
        s.t_old = t;
        double h_try = h_abs, h_kink = 0.0, g_new[NTR1];
        const double *sw0 = MODE_NSW[mode] > 0 ? g_old + MODE_NTR[mode] : NULL;
        int st = implicit ? radau_step(&s, &rad, mode, p, t_bound, rtol, atol, max_step, &h_try)
                          : dop_step(&s, mode, p, t_bound, rtol, atol, max_step, &h_try, sw0, sw0 ? gd_old + MODE_NTR[mode] : NULL,
                                     &h_kink, g_new, gd_new);
        if (st) { status = st; break; }
        if (h_kink > h_resume) h_resume = h_kink;
        const double t_new = t + s.h;
        const int ntr = MODE_NTR[mode], tr0 = MODE_TR0[mode], nsf = n_surf(mode);
        /* the explicit step evaluated the surfaces and their rates at its end with its last stage */
        if (implicit) {
            surfaces(mode, t_new, s.y, p, g_new);
            surfaces_dot(mode, t_new, s.y, s.f, p, gd_new);
        }
        int ev_k;
        double t_ev, x_ev[NXMAX], from = 0.0;
        if ((st = find_event(&s, mode, p, nsub, t, t_new, g_old, gd_old, g_new, gd_new, &ev_k, &t_ev, x_ev, &from, ctx[CX_TLAST_STEP],
                            8.0 * atol, 8.0 * rtol))) {
            status = st;
            break;
        }
        if (ev_k < 0 && nsf > ntr && (ev_k = stuck_at_switch(mode, t_new, s.y, p, s.n, g_old, g_new, gd_new, x_ev)) >= 0) {
            /* a kink within the rounding of the state, approached but out of reach of any step:
             * crossed at the step's end, as if located there */
            t_ev = t_new;
            from = g_new[ev_k];
            if (sens && dop_dense_prepare(&s, mode, p)) { status = ST_SINGULAR_MASS; break; }
        }
        const double t_stop = ev_k >= 0 ? t_ev : t_new;
        /* --- how many rows this step writes; if they do not fit, return and resume here --- */
        int64_t k0 = (int64_t)ctx[CX_GRID_K], k1 = k0;
        if (recording && sample_dt > 0.0) k1 = grid_end(ctx, sample_dt, k0, t_stop);
        const int rest_room = ev_k >= 0 && ev_k < ntr && TR_REST[tr0 + ev_k] >= 0; /* room to come to rest */
        int64_t need = (k1 - k0) + (ev_k >= 0 ? 2 : 0) + ((sample_dt > 0.0) ? 0 : 1) + rest_room;
        if ((recording && *n_out + need > rec.out_cap) || (ev_k >= 0 && ev_recording && *n_ev + 1 + rest_room > rec.ev_cap)) {
            status = ST_BUFFER_FULL;
            break;
        }
        if (recording) {
            if (sample_dt > 0.0 && k1 > k0) {
                if (put_grid_rows(&rec, &s, mode, p, ctx, sample_dt, k0, k1, t)) { status = ST_SINGULAR_MASS; break; }
            } else if (sample_dt <= 0.0 && ev_k < 0) {
                put_row(&rec, t_new, mode, s.n, s.y);
            }
            ctx[CX_GRID_K] = (double)k1;
        }
        h_abs = h_try;
        ++isteps_call;
        ctx[CX_ISTEPS] += 1;
        ctx[CX_ISTEPS_EV] += 1;
        if (ev_k < 0) {
            if (sens) {
                double y1[NXMAX];
                if ((st = sens_advance(mode, p, sens_cols(sens), t, s.h, s.y_old, sens + SENS_S, y1))) { status = st; break; }
            }
            t = t_new;
            for (int i = 0; i < s.n; ++i) { s.y_old[i] = s.y[i]; s.f_old[i] = s.f[i]; }
            for (int k = 0; k < nsf; ++k) { g_old[k] = g_new[k]; gd_old[k] = gd_new[k]; }
            if (nsf > ntr && (zs = approaching_slide(mode, t, s.y_old, p, s.n, g_old, gd_old, h_abs,
                                                           20.0 * (atol + rtol))) >= 0) {
                if (recording && sample_dt > 0.0) put_row(&rec, t, mode, s.n, s.y_old);
                ctx[CX_INFO] = MODE_SW0[mode] + (zs - ntr);
                status = ST_SLIDING;
                break;
            }
            continue;
        }
        radau_reset(&rad); /* the flow jumps here: the Newton matrix and the predictor are stale */
        if (ev_k >= ntr) {
            /* --- a switching surface: restart the integrator on its far side, or stop if the flow
             * there points back into it (sliding) --- */
            if (recording && sample_dt <= 0.0) put_row(&rec, t_ev, mode, s.n, x_ev);
            if (h_resume > h_abs) h_abs = h_resume;
            h_resume = 0.0;
            /* crossings accumulating (a switch chattering about a kink) count towards Zeno */
            if (t_ev - ctx[CX_TPREV_EVENT] < zeno_dt) ctx[CX_ZENO] += 1; else ctx[CX_ZENO] = 0;
            ctx[CX_TPREV_EVENT] = t_ev;
            double fm[NXMAX];
            if (sens && (st = sens_to_event(&s, mode, p, t, s.y_old, t_ev, x_ev, 1, sens, fm))) { status = st; break; }
            t = t_ev;
            onto_far_side(mode, ev_k, t, x_ev, p, s.n, from);
            for (int i = 0; i < s.n; ++i) s.y_old[i] = x_ev[i];
            if (rhs(mode, t, s.y_old, p, s.f_old)) { status = ST_SINGULAR_MASS; break; }
            if (sens && (st = sens_jump(mode, ev_k, -1, mode, t_ev, x_ev, p, fm, s.f_old, 0, sens))) { status = st; break; }
            surfaces(mode, t, s.y_old, p, g_old);
            surfaces_dot(mode, t, s.y_old, s.f_old, p, gd_old);
            if (slides_after_crossing(mode, ev_k, t, s.y_old, p, s.n, g_old[ev_k], gd_old[ev_k], from)) {
                if (recording && sample_dt > 0.0) put_row(&rec, t, mode, s.n, s.y_old); /* where it ends */
                ctx[CX_INFO] = MODE_SW0[mode] + (ev_k - ntr);
                status = ST_SLIDING;
                break;
            }
            if ((zs = resolve_zero_switches(mode, t, s.y_old, p, g_old, s.n, ev_k)) >= 0) {
                if (recording && sample_dt > 0.0) put_row(&rec, t, mode, s.n, s.y_old);
                ctx[CX_INFO] = MODE_SW0[mode] + (zs - ntr);
                status = ST_SLIDING;
                break;
            }
            if (zeno_n > 0 && ctx[CX_ZENO] >= zeno_n) {
                if (recording && sample_dt > 0.0) put_row(&rec, t, mode, s.n, s.y_old);
                status = ST_ZENO;
                break;
            }
            continue;
        }
        /* --- an event: record, then terminate or reset --- */
        const int tr = tr0 + ev_k;
        h_resume = 0.0;
        if (recording) put_row(&rec, t_ev, mode, s.n, x_ev);
        double fm[NXMAX];
        if (sens && (st = sens_to_event(&s, mode, p, t, s.y_old, t_ev, x_ev, 0, sens, fm))) { status = st; break; }
        double xpost[NXMAX];
        int target = mode;
        if (TR_TERMINAL[tr]) {
            for (int i = 0; i < s.n; ++i) xpost[i] = x_ev[i];
        } else {
            int err = reset(tr, t_ev, x_ev, p, xpost, &target);
            if (err || target < 0 || target >= NMODES || !all_finite(MODE_NX[target], xpost)) {
                t = t_ev;
                for (int i = 0; i < s.n; ++i) s.y_old[i] = x_ev[i];
                ctx[CX_INFO] = tr;
                status = err == AMBLE_ERR_SINGULAR_RESET || err == 0 ? ST_RESET_FAILED : ST_SINGULAR_MASS;
                break;
            }
        }
        if (ev_recording) put_event(&rec, t_ev, tr, s.n, x_ev, MODE_NX[target], xpost);
        ctx[CX_EVENTS] += 1;
        ctx[CX_ISTEPS_EV] = 0;
        if (TR_TERMINAL[tr]) {
            if (sens) sens_jump(mode, ev_k, tr, mode, t_ev, x_ev, p, fm, fm, 1, sens);
            t = t_ev;
            for (int i = 0; i < s.n; ++i) s.y_old[i] = x_ev[i];
            ctx[CX_INFO] = tr;
            status = ST_TERMINAL;
            break;
        }
        if (t_ev - ctx[CX_TPREV_EVENT] < zeno_dt) ctx[CX_ZENO] += 1; else ctx[CX_ZENO] = 0;
        ctx[CX_TPREV_EVENT] = t_ev;
        const int fired = target == mode ? ev_k : -1;
        const int source = mode;
        mode = target;
        s.n = MODE_NX[mode];
        t = t_ev;
        for (int i = 0; i < s.n; ++i) s.y_old[i] = xpost[i];
        if (recording) put_row(&rec, t, mode, s.n, s.y_old);
        if (TR_STEP[tr]) { ctx[CX_STEPS] += 1; ctx[CX_TLAST_STEP] = t_ev; }
        if (rhs(mode, t, s.y_old, p, s.f_old)) { status = ST_SINGULAR_MASS; break; }
        if (sens && (st = sens_jump(source, ev_k, tr, mode, t_ev, x_ev, p, fm, s.f_old, 0, sens))) { status = st; break; }
        surfaces(mode, t, s.y_old, p, g_old);
        surfaces_dot(mode, t, s.y_old, s.f_old, p, gd_old);
        arm_zero_guards(mode, t, s.y_old, s.f_old, p, s.n, g_old, gd_old, fired);
        if ((zs = resolve_zero_switches(mode, t, s.y_old, p, g_old, s.n, -1)) >= 0) {
            ctx[CX_INFO] = MODE_SW0[mode] + (zs - MODE_NTR[mode]);
            status = ST_SLIDING;
            break;
        }
        /* a contact whose impacts accumulate, or that leaves the impact without normal velocity,
         * comes to rest; sensitivities are not carried through that transition (zeno instead) */
        if (TR_REST[tr] >= 0 && !sens
            && ((zeno_n > 0 && ctx[CX_ZENO] >= zeno_n) || settled(fired, s.n, s.y_old, g_old, gd_old))) {
            if ((st = come_to_rest(tr, t, p, &s, &mode, ctx, &rec, recording, ev_recording, g_old, gd_old)) >= 0) {
                status = st;
                break;
            }
        }
        if (zeno_n > 0 && ctx[CX_ZENO] >= zeno_n) { status = ST_ZENO; break; }
        if (max_steps > 0 && ctx[CX_STEPS] >= max_steps) { status = ST_STEPS_DONE; break; }
        if (max_events > 0 && ctx[CX_EVENTS] >= max_events) { status = ST_MAX_EVENTS; break; }
    }
    ctx[CX_T] = t;
    ctx[CX_MODE] = mode;
    ctx[CX_H] = h_abs;
    for (int i = 0; i < NXMAX; ++i) ctx[CX_X + i] = i < s.n ? s.y_old[i] : 0.0;
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
