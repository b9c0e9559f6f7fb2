/* Hybrid simulation loop: adaptive DOP853 with dense output, guard location on the dense
 * output, resets, step counting and terminal outcomes — all in compiled code, one call per
 * simulation.
 *
 * This file is included at the end of a generated translation unit, which defines:
 *   NMODES, NXMAX, NTR, NPOINTS, NPARAM
 *   MODE_NX[NMODES], MODE_NTR[NMODES], MODE_TR0[NMODES]
 *   TR_DIR[NTR] (-1 falling, +1 rising, 0 both), TR_TERMINAL[NTR] (1 = ends the run),
 *   TR_STEP[NTR] (1 = counts as a walking step)
 *   int rhs(int mode, double t, const double *x, const double *p, double *dx);
 *   void guards(int mode, double t, const double *x, const double *p, double *g);
 *   void guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g);
 *   int enabled(int tr, double t, const double *x, const double *p);
 *   int reset(int tr, double t, const double *x, const double *p, double *xout, int *target);
 *   void dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G);
 *   void energy(int mode, double t, const double *x, const double *p, double *out);
 *   void kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel);
 *
 * The integrator follows Hairer's DOP853 as implemented in SciPy (same tableau, error norm,
 * step-size control and 7th-order dense output), so results can be compared step for step.
 */
#include "dop853_tableau.h"

#define ST_BUFFER_FULL 0
#define ST_END_TIME 1
#define ST_STEPS_DONE 2
#define ST_TERMINAL 3
#define ST_STEP_TIMEOUT 4
#define ST_ZENO 5
#define ST_STEP_TOO_SMALL 6
#define ST_NONFINITE 7
#define ST_MAX_EVENTS 8
#define ST_SINGULAR_MASS 9
#define ST_RESET_FAILED 10

/* ctx layout (doubles): the resumable state of a run */
#define CX_T 0
#define CX_MODE 1
#define CX_H 2
#define CX_STEPS 3
#define CX_EVENTS 4
#define CX_TLAST_STEP 5
#define CX_TPREV_EVENT 6
#define CX_ZENO 7
#define CX_GRID_K 8
#define CX_GRID_T0 9
#define CX_INFO 10
#define CX_FRESH 11
#define CX_X 16

/* opt layout (doubles) */
#define OP_TEND 0
#define OP_RTOL 1
#define OP_ATOL 2
#define OP_MAXSTEP 3
#define OP_MAXSTEPTIME 4
#define OP_SAMPLEDT 5
#define OP_ZENODT 6
/* iopt layout (longs) */
#define IO_MAXSTEPS 0
#define IO_MAXEVENTS 1
#define IO_OUTCAP 2
#define IO_EVCAP 3
#define IO_ZENON 4
#define IO_NSUB 5

#define NSUB_MAX 16

typedef struct {
    int n;
    double t_old, h;
    double y_old[NXMAX], y[NXMAX], f_old[NXMAX], f[NXMAX];
    double K[DOP_STAGES_EXT][NXMAX];
    double F[DOP_INTERP][NXMAX];
    int dense_ready;
} Dop;

static int all_finite(int n, const double *x) {
    for (int i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

static double rms_norm(int n, const double *v) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += v[i] * v[i];
    return sqrt(s / n);
}

/* Initial step size as in Hairer's / SciPy's select_initial_step. */
static double initial_step(int mode, double t, const double *y, const double *f, const double *p,
                           double t_bound, double max_step, double rtol, double atol, int n) {
    double sc[NXMAX], tmp[NXMAX], y1[NXMAX], f1[NXMAX];
    double interval = fabs(t_bound - t);
    if (interval == 0.0) return 0.0;
    for (int i = 0; i < n; ++i) sc[i] = atol + fabs(y[i]) * rtol;
    for (int i = 0; i < n; ++i) tmp[i] = y[i] / sc[i];
    double d0 = rms_norm(n, tmp);
    for (int i = 0; i < n; ++i) tmp[i] = f[i] / sc[i];
    double d1 = rms_norm(n, tmp);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > interval) h0 = interval;
    for (int i = 0; i < n; ++i) y1[i] = y[i] + h0 * f[i];
    if (rhs(mode, t + h0, y1, p, f1)) return 1e-6;
    for (int i = 0; i < n; ++i) tmp[i] = (f1[i] - f[i]) / sc[i];
    double d2 = rms_norm(n, tmp) / h0;
    double h1;
    if (d1 <= 1e-15 && d2 <= 1e-15) h1 = fmax(1e-6, h0 * 1e-3);
    else h1 = pow(0.01 / fmax(d1, d2), 1.0 / 8.0);
    double h = fmin(100 * h0, h1);
    h = fmin(h, interval);
    return fmin(h, max_step);
}

/* One accepted DOP853 step from (t_old, y_old) with f_old known. Returns 0, or a status. */
static int dop_step(Dop *s, int mode, const double *p, double t_bound, double rtol, double atol,
                    double max_step, double *h_abs) {
    const int n = s->n;
    const double t = s->t_old;
    double min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
    double ha = *h_abs;
    if (ha > max_step) ha = max_step;
    if (ha < min_step) ha = min_step;
    int rejected = 0, saw_nan = 0;
    double ytmp[NXMAX];
    for (;;) {
        if (ha < min_step) return saw_nan ? ST_NONFINITE : ST_STEP_TOO_SMALL;
        double t_new = t + ha;
        if (t_new > t_bound) t_new = t_bound;
        double h = t_new - t;
        ha = fabs(h);
        for (int i = 0; i < n; ++i) s->K[0][i] = s->f_old[i];
        int err = 0;
        for (int st = 1; st < DOP_STAGES && !err; ++st) {
            const double *a = DOP_A + st * DOP_STAGES_EXT;
            for (int i = 0; i < n; ++i) {
                double acc = 0.0;
                for (int j = 0; j < st; ++j) acc += a[j] * s->K[j][i];
                ytmp[i] = s->y_old[i] + h * acc;
            }
            err = rhs(mode, t + DOP_C[st] * h, ytmp, p, s->K[st]);
        }
        if (err) return ST_SINGULAR_MASS;
        for (int i = 0; i < n; ++i) {
            double acc = 0.0;
            for (int j = 0; j < DOP_STAGES; ++j) acc += DOP_B[j] * s->K[j][i];
            s->y[i] = s->y_old[i] + h * acc;
        }
        if (rhs(mode, t + h, s->y, p, s->K[DOP_STAGES])) return ST_SINGULAR_MASS;
        double e5 = 0.0, e3 = 0.0;
        for (int i = 0; i < n; ++i) {
            double sc = atol + fmax(fabs(s->y_old[i]), fabs(s->y[i])) * rtol;
            double a5 = 0.0, a3 = 0.0;
            for (int j = 0; j <= DOP_STAGES; ++j) {
                a5 += DOP_E5[j] * s->K[j][i];
                a3 += DOP_E3[j] * s->K[j][i];
            }
            a5 /= sc;
            a3 /= sc;
            e5 += a5 * a5;
            e3 += a3 * a3;
        }
        double error_norm;
        if (e5 == 0.0 && e3 == 0.0) error_norm = 0.0;
        else error_norm = ha * e5 / sqrt((e5 + 0.01 * e3) * n);
        if (!isfinite(error_norm) || !all_finite(n, s->y)) {
            saw_nan = 1;
            ha *= 0.2;
            rejected = 1;
            continue;
        }
        if (error_norm < 1.0) {
            double factor = error_norm == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(error_norm, -1.0 / 8.0));
            if (rejected && factor > 1.0) factor = 1.0;
            *h_abs = ha * factor;
            s->h = h;
            for (int i = 0; i < n; ++i) s->f[i] = s->K[DOP_STAGES][i];
            s->dense_ready = 0;
            return 0;
        }
        ha *= fmax(0.2, 0.9 * pow(error_norm, -1.0 / 8.0));
        rejected = 1;
    }
}

/* 7th-order continuous extension of the last step (three extra stages). */
static int dop_dense_prepare(Dop *s, int mode, const double *p) {
    if (s->dense_ready) return 0;
    const int n = s->n;
    const double h = s->h;
    double ytmp[NXMAX];
    for (int st = DOP_STAGES + 1; st < DOP_STAGES_EXT; ++st) {
        const double *a = DOP_A + st * DOP_STAGES_EXT;
        for (int i = 0; i < n; ++i) {
            double acc = 0.0;
            for (int j = 0; j < st; ++j) acc += a[j] * s->K[j][i];
            ytmp[i] = s->y_old[i] + h * acc;
        }
        if (rhs(mode, s->t_old + DOP_C[st] * h, ytmp, p, s->K[st])) return ST_SINGULAR_MASS;
    }
    for (int i = 0; i < n; ++i) {
        double dy = s->y[i] - s->y_old[i];
        s->F[0][i] = dy;
        s->F[1][i] = h * s->f_old[i] - dy;
        s->F[2][i] = 2.0 * dy - h * (s->f[i] + s->f_old[i]);
        for (int r = 0; r < 4; ++r) {
            double acc = 0.0;
            for (int j = 0; j < DOP_STAGES_EXT; ++j) acc += DOP_D[r * DOP_STAGES_EXT + j] * s->K[j][i];
            s->F[3 + r][i] = h * acc;
        }
    }
    s->dense_ready = 1;
    return 0;
}

static void dop_dense_eval(const Dop *s, double t, double *out) {
    const int n = s->n;
    double x = (t - s->t_old) / s->h;
    for (int i = 0; i < n; ++i) {
        double y = 0.0;
        for (int k = DOP_INTERP - 1, c = 0; k >= 0; --k, ++c) {
            y += s->F[k][i];
            y *= (c % 2 == 0) ? x : (1.0 - x);
        }
        out[i] = y + s->y_old[i];
    }
}

/* Cubic Hermite through both step ends: cheap, for spotting sign changes inside a step. */
static void hermite_eval(const Dop *s, double theta, double *out) {
    const double h = s->h;
    double t2 = theta * theta, t3 = t2 * theta;
    double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + theta, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
    for (int i = 0; i < s->n; ++i)
        out[i] = h00 * s->y_old[i] + h10 * h * s->f_old[i] + h01 * s->y[i] + h11 * h * s->f[i];
}

static int crosses(int dir, double ga, double gb) {
    if (dir < 0) return ga > 0.0 && gb <= 0.0;
    if (dir > 0) return ga < 0.0 && gb >= 0.0;
    return (ga > 0.0 && gb <= 0.0) || (ga < 0.0 && gb >= 0.0);
}

/* Guard k of `mode` along the dense output at time t. */
static double guard_at(const Dop *s, int mode, int k, double t, const double *p, double *xbuf) {
    double g[NTR > 0 ? NTR : 1];
    dop_dense_eval(s, t, xbuf);
    guards(mode, t, xbuf, p, g);
    return g[k];
}

/* Root of guard k in [ta, tb] (crossing in direction dir) by the Illinois method on the dense
 * output; returns a time on the far side of the crossing, within ~1e-14 relative. */
static double locate(const Dop *s, int mode, int k, int dir, double ta, double ga, double tb,
                     double gb, const double *p) {
    double xbuf[NXMAX];
    int side = 0;
    double tol = 4e-16 * fmax(1.0, fmax(fabs(ta), fabs(tb)));
    for (int it = 0; it < 200 && (tb - ta) > tol; ++it) {
        double tm = (ga * tb - gb * ta) / (ga - gb);
        if (!(tm > ta && tm < tb)) tm = 0.5 * (ta + tb);
        double gm = guard_at(s, mode, k, tm, p, xbuf);
        if (crosses(dir, ga, gm)) {
            tb = tm; gb = gm;
            if (side == -1) ga *= 0.5;
            side = -1;
        } else {
            ta = tm; ga = gm;
            if (side == 1) gb *= 0.5;
            side = 1;
        }
    }
    return tb;
}

typedef struct {
    double *out_t, *out_x, *ev_t, *ev_xpre, *ev_xpost;
    int *out_mode, *ev_tr;
    long *n_out, *n_ev;
    long out_cap, ev_cap;
} Rec;

static void put_row(Rec *r, double t, int mode, int n, const double *x) {
    long k = (*r->n_out)++;
    r->out_t[k] = t;
    r->out_mode[k] = mode;
    double *row = r->out_x + k * NXMAX;
    for (int i = 0; i < NXMAX; ++i) row[i] = i < n ? x[i] : NAN;
}

/* Simulate from the state in ctx until an end condition; see the CX_, OP_, IO_ layouts.
 * Returns a status ST_*; ST_BUFFER_FULL means "grow the buffers and call again". */
int amble_simulate(const double *p, double *ctx, const double *opt, const long *iopt,
                   double *out_t, int *out_mode, double *out_x, long *n_out,
                   double *ev_t, int *ev_tr, double *ev_xpre, double *ev_xpost, long *n_ev) {
    Rec rec = {out_t, out_x, ev_t, ev_xpre, ev_xpost, out_mode, ev_tr, n_out, n_ev, iopt[IO_OUTCAP], iopt[IO_EVCAP]};
    const int recording = rec.out_cap > 0, ev_recording = rec.ev_cap > 0;
    const double t_end = opt[OP_TEND], rtol = opt[OP_RTOL], atol = opt[OP_ATOL];
    const double max_step_time = opt[OP_MAXSTEPTIME], sample_dt = opt[OP_SAMPLEDT];
    const double zeno_dt = opt[OP_ZENODT];
    const long max_steps = iopt[IO_MAXSTEPS], max_events = iopt[IO_MAXEVENTS], zeno_n = iopt[IO_ZENON];
    int nsub = (int)iopt[IO_NSUB];
    if (nsub < 1) nsub = 1;
    if (nsub > NSUB_MAX) nsub = NSUB_MAX;

    Dop s;
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
    double g_old[NTR > 0 ? NTR : 1], gd_old[NTR > 0 ? NTR : 1], gd_new[NTR > 0 ? NTR : 1];
    guards(mode, t, s.y_old, p, g_old);
    guards_dot(mode, t, s.y_old, s.f_old, p, gd_old);
    int status = -1;

    while (status < 0) {
        if (t >= t_end) { status = ST_END_TIME; break; }
        if (max_step_time > 0.0 && t - ctx[CX_TLAST_STEP] >= max_step_time) { status = ST_STEP_TIMEOUT; break; }
        double t_bound = t_end;
        if (max_step_time > 0.0 && ctx[CX_TLAST_STEP] + max_step_time < t_bound) t_bound = ctx[CX_TLAST_STEP] + max_step_time;
        s.t_old = t;
        double h_try = h_abs;
        int st = dop_step(&s, mode, p, t_bound, rtol, atol, max_step, &h_try);
        if (st) { status = st; break; }
        const double t_new = t + s.h;
        /* --- event detection: guard samples along the step (Hermite), then exact roots --- */
        const int ntr = MODE_NTR[mode], tr0 = MODE_TR0[mode];
        double g_new[NTR > 0 ? NTR : 1];
        guards(mode, t_new, s.y, p, g_new);
        int ev_k = -1;
        double t_ev = INFINITY;
        double x_ev[NXMAX];
        if (ntr > 0) {
            /* Sample times inside the step: a uniform grid, plus for each guard the extremum of
             * the cubic through g and ġ at both ends — so a guard that dips below zero and comes
             * back within one step (two crossings) is still seen. */
            double th[NSUB_MAX + 1 + 2 * NTR];
            int ns = 0;
            for (int j = 0; j <= nsub; ++j) th[ns++] = (double)j / nsub;
            const double *gd0 = gd_old, *gd1 = gd_new;
            guards_dot(mode, t_new, s.y, s.f, p, gd_new);
            for (int k = 0; k < ntr; ++k) {
                double a0 = g_old[k], a1 = s.h * gd0[k], b0 = g_new[k], b1 = s.h * gd1[k];
                /* cubic c(θ) = a0 + a1 θ + c2 θ² + c3 θ³ matching values and slopes */
                double c2 = 3 * (b0 - a0) - 2 * a1 - b1, c3 = 2 * (a0 - b0) + a1 + b1;
                double A = 3 * c3, B = 2 * c2, C = a1;
                double r[2];
                int nr = 0;
                double disc = B * B - 4 * A * C;
                if (disc >= 0) { /* stable roots of A θ² + B θ + C (A may be ~0: a quadratic guard) */
                    double qq = -0.5 * (B + copysign(sqrt(disc), B));
                    if (qq != 0.0) r[nr++] = C / qq;
                    if (A != 0.0) r[nr++] = qq / A;
                }
                for (int q = 0; q < nr; ++q)
                    if (r[q] > 0.0 && r[q] < 1.0 && ns < NSUB_MAX + 1 + 2 * NTR) th[ns++] = r[q];
            }
            for (int a = 1; a < ns; ++a) /* insertion sort: a handful of values */
                for (int b = a; b > 0 && th[b - 1] > th[b]; --b) { double tmp = th[b]; th[b] = th[b - 1]; th[b - 1] = tmp; }
            double gs[NSUB_MAX + 1 + 2 * NTR][NTR > 0 ? NTR : 1];
            double xs[NXMAX];
            int any = 0;
            for (int k = 0; k < ntr; ++k) { gs[0][k] = g_old[k]; gs[ns - 1][k] = g_new[k]; }
            for (int j = 1; j < ns - 1; ++j) {
                hermite_eval(&s, th[j], xs);
                guards(mode, t + s.h * th[j], xs, p, gs[j]);
            }
            for (int k = 0; k < ntr && !any; ++k)
                for (int j = 0; j + 1 < ns; ++j)
                    if (crosses(TR_DIR[tr0 + k], gs[j][k], gs[j + 1][k])) { any = 1; break; }
            if (any) {
                if (dop_dense_prepare(&s, mode, p)) { status = ST_SINGULAR_MASS; break; }
                for (int j = 1; j < ns - 1; ++j) {
                    dop_dense_eval(&s, t + s.h * th[j], xs);
                    guards(mode, t + s.h * th[j], xs, p, gs[j]);
                }
                for (int k = 0; k < ntr; ++k) {
                    int dir = TR_DIR[tr0 + k];
                    for (int j = 0; j + 1 < ns; ++j) {
                        double ta = t + s.h * th[j], tb = (j + 2 == ns) ? t_new : t + s.h * th[j + 1];
                        if (ta >= t_ev) break;
                        if (tb <= ta || !crosses(dir, gs[j][k], gs[j + 1][k])) continue;
                        double tr = locate(&s, mode, k, dir, ta, gs[j][k], tb, gs[j + 1][k], p);
                        if (tr >= t_ev) break;
                        double xr[NXMAX];
                        if (tr >= t_new) { tr = t_new; for (int i = 0; i < s.n; ++i) xr[i] = s.y[i]; }
                        else dop_dense_eval(&s, tr, xr);
                        if (enabled(tr0 + k, tr, xr, p)) {
                            t_ev = tr;
                            ev_k = k;
                            for (int i = 0; i < s.n; ++i) x_ev[i] = xr[i];
                            break;
                        }
                    }
                }
            }
        }
        const double t_stop = ev_k >= 0 ? t_ev : t_new;
        /* --- how many rows this step writes; if they do not fit, return and resume here --- */
        long k0 = (long)ctx[CX_GRID_K], k1 = k0;
        if (recording && sample_dt > 0.0) {
            while (ctx[CX_GRID_T0] + k1 * sample_dt <= t_stop) ++k1;
        }
        long need = (k1 - k0) + (ev_k >= 0 ? 2 : 0) + ((sample_dt > 0.0) ? 0 : 1);
        if ((recording && *n_out + need > rec.out_cap) || (ev_k >= 0 && ev_recording && *n_ev + 1 > rec.ev_cap)) {
            status = ST_BUFFER_FULL;
            break;
        }
        if (recording) {
            if (sample_dt > 0.0 && k1 > k0) {
                if (dop_dense_prepare(&s, mode, p)) { status = ST_SINGULAR_MASS; break; }
                double xs[NXMAX];
                for (long k = k0; k < k1; ++k) {
                    double tk = ctx[CX_GRID_T0] + k * sample_dt;
                    if (tk <= t) continue;
                    dop_dense_eval(&s, tk, xs);
                    put_row(&rec, tk, mode, s.n, xs);
                }
            } else if (sample_dt <= 0.0 && ev_k < 0) {
                put_row(&rec, t_new, mode, s.n, s.y);
            }
            ctx[CX_GRID_K] = (double)k1;
        }
        h_abs = h_try;
        if (ev_k < 0) {
            t = t_new;
            for (int i = 0; i < s.n; ++i) { s.y_old[i] = s.y[i]; s.f_old[i] = s.f[i]; }
            for (int k = 0; k < ntr; ++k) { g_old[k] = g_new[k]; gd_old[k] = gd_new[k]; }
            continue;
        }
        /* --- an event: record, then terminate or reset --- */
        const int tr = tr0 + ev_k;
        if (recording) put_row(&rec, t_ev, mode, s.n, x_ev);
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
        if (ev_recording) {
            long e = (*n_ev)++;
            ev_t[e] = t_ev;
            ev_tr[e] = tr;
            for (int i = 0; i < NXMAX; ++i) {
                ev_xpre[e * NXMAX + i] = i < s.n ? x_ev[i] : NAN;
                ev_xpost[e * NXMAX + i] = i < MODE_NX[target] ? xpost[i] : NAN;
            }
        }
        ctx[CX_EVENTS] += 1;
        if (TR_TERMINAL[tr]) {
            t = t_ev;
            for (int i = 0; i < s.n; ++i) s.y_old[i] = x_ev[i];
            ctx[CX_INFO] = tr;
            status = ST_TERMINAL;
            break;
        }
        if (t_ev - ctx[CX_TPREV_EVENT] < zeno_dt) ctx[CX_ZENO] += 1; else ctx[CX_ZENO] = 0;
        ctx[CX_TPREV_EVENT] = t_ev;
        mode = target;
        s.n = MODE_NX[mode];
        t = t_ev;
        for (int i = 0; i < s.n; ++i) s.y_old[i] = xpost[i];
        if (recording) put_row(&rec, t, mode, s.n, s.y_old);
        if (TR_STEP[tr]) { ctx[CX_STEPS] += 1; ctx[CX_TLAST_STEP] = t_ev; }
        if (rhs(mode, t, s.y_old, p, s.f_old)) { status = ST_SINGULAR_MASS; break; }
        guards(mode, t, s.y_old, p, g_old);
        guards_dot(mode, t, s.y_old, s.f_old, p, gd_old);
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
    return rhs(mode, t, x, p, dx);
}

void amble_guards(int mode, double t, const double *x, const double *p, double *g) {
    guards(mode, t, x, p, g);
}

int amble_reset(int tr, double t, const double *x, const double *p, double *xout, int *target) {
    return reset(tr, t, x, p, xout, target);
}

void amble_dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G) {
    dynamics(mode, t, x, p, M, h, G);
}

void amble_rows_energy(long nrows, const double *t, const int *mode, const double *x, const double *p, double *out) {
    for (long r = 0; r < nrows; ++r) energy(mode[r], t[r], x + r * NXMAX, p, out + 2 * r);
}

void amble_rows_kinematics(long nrows, const double *t, const int *mode, const double *x, const double *p,
                           double *pos, double *vel) {
    for (long r = 0; r < nrows; ++r)
        kinematics(mode[r], t[r], x + r * NXMAX, p, pos + r * NPOINTS * 3, vel + r * NPOINTS * 3);
}

void amble_info(long *out) {
    out[0] = NMODES;
    out[1] = NXMAX;
    out[2] = NTR;
    out[3] = NPOINTS;
    out[4] = NPARAM;
    out[5] = CX_X;
}
