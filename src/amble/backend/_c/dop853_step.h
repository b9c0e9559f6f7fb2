/* DOP853 (Hairer, Norsett & Wanner) as implemented in SciPy: same tableau, error norm, step-size
 * control and 7th-order dense output, so results can be compared step for step.
 *
 * The step itself is compiled in the model's own translation unit (this file is included by
 * model_tail.h), with the right-hand side inlined into it: the stage sums and the right-hand side
 * are nearly all of a small model's integrator time. The runtime (runtime.c, compiled once)
 * reaches it through the hidden stepper dop853_stepper (stepper.h) inside the model's library.
 *
 * Needs from the including unit: the ST_* codes (generated from abi.py), NXMAX, MODE_NTR, MODE_NSW and
 *   int rhs(int mode, double t, const double *x, const double *p, double *dx);
 *   int rhs_surfaces(int mode, double t, const double *x, const double *p, double *dx, double *g, double *gd);
 *   and the kernels switches, guards_dot, switches_dot.
 */
#ifndef AMBLE_DOP853_STEP_H
#define AMBLE_DOP853_STEP_H
#include "dop853.h"
#include "step_common.h"

/* Aiming at a switching surface estimated at a fraction θ of a rejected trial: if θ > AIM_NEAR the
 * retry ends AIM_SHORT (relative) short of it, a step with every stage on the near side; the
 * surface then lies just ahead of the next step, which crosses it in a step barely longer than
 * the gap, its overshoot cut for an error of AIM_ERR (the error there is about linear in it).
 * Measured on the library's walkers with switches and a kinked pendulum (tests/events): crossing
 * in one step aimed just past the surface takes fewer steps, but the crossing is located on the
 * dense output of that step, whose stages beyond the surface spoil it — final states at 1e-10 up
 * to 35× less accurate than SciPy's DOP853 switching branches exactly. */
#define AIM_NEAR 0.05
#define AIM_SHORT 0.02
#define AIM_ERR 0.01

/* Earliest crossing of a switching surface of `mode` inside a trial step of size h from the values
 * sw0 and slopes swd0 (d/dt) at its start to the values at its end state y: the smallest root in
 * (0, 1) of the quadratic in θ through g(0), h ġ(0) and g(1), of the first surface that changes
 * sign. Returns it times h (s), or −1 if no surface changes sign. */
static double switch_crossing(int mode, double t, double h, const double *y, const double *p, const double *sw0,
                              const double *swd0) {
    const int nsw = MODE_NSW[mode];
    double g1[nsw > 0 ? nsw : 1], best = INFINITY;
    switches(mode, t + h, y, p, g1);
    for (int k = 0; k < nsw; ++k) {
        const double g0 = sw0[k];
        if (g0 == 0.0 || !(g0 > 0.0 ? g1[k] <= 0.0 : g1[k] >= 0.0)) continue;
        const double a = h * swd0[k], c = g1[k] - g0 - a;
        double th = g0 / (g0 - g1[k]); /* the secant: the fallback of a degenerate quadratic */
        const double disc = a * a - 4.0 * c * g0;
        if (c != 0.0 && disc >= 0.0) { /* stable roots of c θ² + a θ + g0; q(0), q(1) differ in sign */
            const double q = -0.5 * (a + copysign(sqrt(disc), a));
            double r1 = q / c, r2 = q != 0.0 ? g0 / q : INFINITY, r = INFINITY;
            if (r1 > 0.0 && r1 <= 1.0) r = r1;
            if (r2 > 0.0 && r2 <= 1.0 && r2 < r) r = r2;
            if (r <= 1.0) th = r;
        }
        if (th < best) best = th;
    }
    return best <= 1.0 ? best * h : -1.0;
}

/* The step's last right-hand side, f(y) at its end, is outside its error estimate (DOP_E3 and
 * DOP_E5 vanish on it) but inside its dense output (F[2] and the stages 13–15 read it). A switching
 * surface that passes between the end y and the state of the stage before it at the same time
 * t + h (ytmp, c = 1) — the step's error-controlled stages all on the near side, its end across by
 * no more than their difference — is seen by that last evaluation alone: its branch jumps, f
 * with it, and the dense output carries the jump times h (a pendulum resting on a switch whose
 * force vanishes on one side: a step of 0.9 s ending 1e-18 rad across, a dense output 1 rad off
 * mid-step, an event located there). The stage at c = 1 then stands in for it: f of the near
 * side's branch, at a state within the step's error of y, so that the crossing, seen at the
 * step's end (g_new across), is located on the near side's flow. Returns 1 where it should. */
static int near_side_end(int mode, double t, const double *ytmp, const double *p, const double *sw0,
                         const double *sw_new) {
    const int nsw = MODE_NSW[mode];
    int across = 0;
    /* signs compared, not products: a surface placed at ±DBL_MIN times a small g underflows */
#define DOP_ACROSS(a, b) ((a) != 0.0 && ((b) == 0.0 || ((a) > 0.0) != ((b) > 0.0)))
    for (int k = 0; k < nsw; ++k) across |= DOP_ACROSS(sw0[k], sw_new[k]);
    if (!across) return 0; /* every step but those that end across a switch */
    double g1[nsw];
    switches(mode, t, ytmp, p, g1);
    for (int k = 0; k < nsw; ++k)
        if (DOP_ACROSS(sw0[k], sw_new[k]) && !DOP_ACROSS(sw0[k], g1[k])) return 1;
#undef DOP_ACROSS
    return 0;
}

/* The step's sums written out over the tableau's non-zero terms (the X-macro lists of
 * dop853_tableau.h), the coefficients as constants, as the dense output's below: per component the
 * additions are those of the plain sum over all stages, in its order (from 0.0, zeros skipped), so
 * the results are bitwise those of the loop over the tableau with a zero test per coefficient. */
#define DOP_ADD_TERM(j, c) a += (c) * d->K[j][i];
#define DOP_ADD_E(j, c5, c3) { const double k = d->K[j][i]; a5 += (c5) * k; a3 += (c3) * k; }
#define DOP_STEP_STAGE(st)                                                                     \
    if (!err) {                                                                                \
        for (int i = 0; i < n; ++i) {                                                          \
            double a = 0.0;                                                                    \
            DOP_A##st##_TERMS(DOP_ADD_TERM)                                                    \
            ytmp[i] = s->y_old[i] + h * a;                                                     \
        }                                                                                      \
        err = rhs(mode, t + DOP_C[st] * h, ytmp, p, d->K[st]);                                 \
    }

/* One accepted DOP853 step from (t_old, y_old) with f_old known. Returns 0, or a status.
 *
 * A kink or jump of the right-hand side at a switching surface inside a trial step spoils its
 * error estimate in proportion to the part of the step beyond the surface (the stages there see
 * the other branch): shrinking the step from its start, as the plain control does, keeps the
 * surface inside it for many rejections. So when a rejected trial ends on the far side of a
 * switching surface (values sw0 and slopes swd0 at the step's start, the mode's switching part of
 * the surfaces; NULL: no aiming), the retry is aimed at the estimated crossing (AIM_*): short of
 * it, or, with the surface just ahead, barely past it; the crossing is then located by the event
 * logic in the accepted step, which restarts the integrator on the far side. A retry aimed past
 * the surface whose error does not fall with its overshoot is limited by the smooth part: the
 * plain control takes over for the rest of the step.
 * *h_kink: the step size proposed before a switch spoiled the step (the size to resume with
 * after its crossing), or 0 if none did. g_new, gd_new (or NULL): the mode's surfaces and their
 * rates at the accepted step's end, computed with its last stage (rhs_surfaces). */
static int dop_step(Step *s, int mode, const double *p, double t_bound, double rtol, double atol, double max_step,
                    double *h_abs, const double *sw0, const double *swd0, double *h_kink, double *g_new, double *gd_new) {
    Dop *d = (Dop *)s;
    const int n = STEP_N(s);
    const double t = s->t_old;
    double min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
    double ha = *h_abs;
    if (ha > max_step) ha = max_step;
    if (ha < min_step) ha = min_step;
    int rejected = 0, saw_nan = 0, saw_singular = 0, aiming = sw0 != NULL && MODE_NSW[mode] > 0;
    double ytmp[NXMAX], err_aimed = INFINITY; /* the error of the last aimed trial */
    const double ha0 = ha;
    *h_kink = 0.0;
    for (;;) {
        if (ha < min_step) return saw_singular ? ST_SINGULAR_MASS : saw_nan ? ST_NONFINITE : ST_STEP_TOO_SMALL;
        double t_new = t + ha;
        if (t_new > t_bound) t_new = t_bound;
        double h = t_new - t;
        ha = fabs(h);
        for (int i = 0; i < n; ++i) d->K[0][i] = s->f_old[i];
        int err = 0;
        DOP_STEP_STAGE(1) DOP_STEP_STAGE(2) DOP_STEP_STAGE(3) DOP_STEP_STAGE(4) DOP_STEP_STAGE(5)
        DOP_STEP_STAGE(6) DOP_STEP_STAGE(7) DOP_STEP_STAGE(8) DOP_STEP_STAGE(9) DOP_STEP_STAGE(10)
        DOP_STEP_STAGE(11)
        if (!err) {
            for (int i = 0; i < n; ++i) {
                double a = 0.0;
                DOP_B_TERMS(DOP_ADD_TERM)
                s->y[i] = s->y_old[i] + h * a;
            }
            /* the last stage, at the step's end: with the surfaces the event screening reads there */
            err = g_new ? rhs_surfaces(mode, t + h, s->y, p, d->K[DOP_STAGES], g_new, gd_new)
                        : rhs(mode, t + h, s->y, p, d->K[DOP_STAGES]);
        }
        /* a trial stage outside the region where the mass matrix is positive definite (a stage
         * extrapolates past the state the flow reaches) says the step is too long, not that the
         * run must end: reject it as a non-finite one; only a singularity that persists down to
         * the smallest step ends the run (ST_SINGULAR_MASS) */
        if (err) {
            saw_singular = 1;
            ha *= 0.2;
            rejected = 1;
            continue;
        }
        double e5 = 0.0, e3 = 0.0;
        for (int i = 0; i < n; ++i) {
            double a5 = 0.0, a3 = 0.0; /* the 5th- and the 3rd-order error estimates */
            DOP_E_TERMS(DOP_ADD_E)
            const double ya = fabs(s->y_old[i]), yb = fabs(s->y[i]);
            const double sc = atol + (ya > yb ? ya : yb) * rtol; /* fmax is a library call at -O2 */
            const double b5 = a5 / sc, b3 = a3 / sc;
            e5 += b5 * b5;
            e3 += b3 * b3;
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
            if (g_new && sw0 && MODE_NSW[mode] > 0 && near_side_end(mode, t + h, ytmp, p, sw0, g_new + MODE_NTR[mode])) {
                for (int i = 0; i < n; ++i) d->K[DOP_STAGES][i] = d->K[DOP_STAGES - 1][i];
                guards_dot(mode, t + h, s->y, d->K[DOP_STAGES], p, gd_new);
                switches_dot(mode, t + h, s->y, d->K[DOP_STAGES], p, gd_new + MODE_NTR[mode]);
            }
            for (int i = 0; i < n; ++i) s->f[i] = d->K[DOP_STAGES][i];
            d->dense_ready = 0;
            return 0;
        }
        rejected = 1;
        if (aiming && error_norm > 0.25 * err_aimed) aiming = 0; /* not the switch's doing */
        const double tc = aiming ? switch_crossing(mode, t, h, s->y, p, sw0, swd0) : -1.0;
        if (tc > 0.0) {
            *h_kink = ha0;
            if (tc > AIM_NEAR * ha) { /* end the step short of the surface: no stage beyond it */
                err_aimed = INFINITY;
                ha = (1.0 - AIM_SHORT) * tc;
            } else { /* the surface just ahead: cross it in a step barely longer than the gap */
                err_aimed = error_norm;
                ha = tc + (ha - tc) * fmin(0.05, AIM_ERR / error_norm);
            }
            continue;
        }
        ha *= fmax(0.2, 0.9 * pow(error_norm, -1.0 / 8.0));
    }
}

/* 7th-order continuous extension of the last step (three extra stages). Its sums are written out
 * over the tableau's non-zero terms (the X-macro lists of dop853_tableau.h), the coefficients as
 * constants: the run-time loop over the stages with a zero test per coefficient took 2.7 times the
 * instructions (callgrind, compass gait). Per component the additions are those of the plain
 * sum over all stages, in its order (from 0.0, zeros skipped), so the result is bitwise the same;
 * the four coefficient rows are summed in one pass, each K[j] read once for all four. */
#define DOP_ADD_D(j, c0, c1, c2, c3) { const double k = d->K[j][i]; d0 += (c0) * k; d1 += (c1) * k; \
                                       d2 += (c2) * k; d3 += (c3) * k; }
#define DOP_EXTRA_STAGE(st)                                                                    \
    for (int i = 0; i < n; ++i) {                                                              \
        double a = 0.0;                                                                        \
        DOP_A##st##_TERMS(DOP_ADD_TERM)                                                        \
        ytmp[i] = s->y_old[i] + h * a;                                                         \
    }                                                                                          \
    if (rhs(mode, s->t_old + DOP_C[st] * h, ytmp, p, d->K[st])) return ST_SINGULAR_MASS;

static int dop_dense_prepare(Step *s, int mode, const double *p) {
    Dop *d = (Dop *)s;
    if (d->dense_ready) return 0;
    const int n = STEP_N(s);
    const double h = s->h;
    double ytmp[NXMAX];
    DOP_EXTRA_STAGE(13)
    DOP_EXTRA_STAGE(14)
    DOP_EXTRA_STAGE(15)
    for (int i = 0; i < n; ++i) {
        const double dy = s->y[i] - s->y_old[i];
        d->F[0][i] = dy;
        d->F[1][i] = h * s->f_old[i] - dy;
        d->F[2][i] = 2.0 * dy - h * (s->f[i] + s->f_old[i]);
        double d0 = 0.0, d1 = 0.0, d2 = 0.0, d3 = 0.0;
        DOP_D_TERMS(DOP_ADD_D)
        d->F[3][i] = h * d0;
        d->F[4][i] = h * d1;
        d->F[5][i] = h * d2;
        d->F[6][i] = h * d3;
    }
    d->dense_ready = 1;
    return 0;
}
#undef DOP_EXTRA_STAGE
#undef DOP_ADD_D
#undef DOP_ADD_TERM

/* The dense output at θ = x of the last step: Horner in x and 1 − x alternately (x first, from
 * the highest of the DOP_INTERP coefficient rows), written out; all components side by side. */
typedef char dop_interp_rows_are_7[DOP_INTERP == 7 ? 1 : -1]; /* a compile error otherwise */
static inline void dense_at(const Dop *restrict d, double x, double *restrict out) {
    const Step *s = &d->b;
    const int n = STEP_N(s);
    const double y1 = 1.0 - x;
    for (int i = 0; i < n; ++i) {
        double y = (0.0 + d->F[6][i]) * x; /* 0.0 + keeps the sign of a zero as the loop had it */
        y = (y + d->F[5][i]) * y1;
        y = (y + d->F[4][i]) * x;
        y = (y + d->F[3][i]) * y1;
        y = (y + d->F[2][i]) * x;
        y = (y + d->F[1][i]) * y1;
        y = (y + d->F[0][i]) * x;
        out[i] = y + s->y_old[i];
    }
}

/* The dense output of the last step at t. */
static void dop_dense_eval(const Step *restrict s, double t, double *restrict out) {
    dense_at((const Dop *)s, (t - s->t_old) / s->h, out);
}

/* Rows of the dense output at the grid times t0 + k·dt, k = k0 … k1 − 1, that lie after t (those
 * at or before t were written by the previous step): the times into out_t, the states into rows
 * of out_x of NXMAX entries, padded with NaN. Returns the number of rows written. In the model's
 * unit, not the runtime, so that the interpolant is inlined and, with NXMAX and NX_FIXED
 * constants, a row is a few stores instead of a loop with a test per entry. */
static int64_t dop_dense_rows(const Step *restrict s, double t0, double dt, int64_t k0, int64_t k1, double t,
                              double *restrict out_t, double *restrict out_x) {
    const int n = STEP_N(s);
    int64_t r = 0;
    for (int64_t k = k0; k < k1; ++k) {
        const double tk = t0 + k * dt;
        if (tk <= t) continue;
        double *row = out_x + r * NXMAX;
        dense_at((const Dop *)s, (tk - s->t_old) / s->h, row);
        for (int i = n; i < NXMAX; ++i) row[i] = NAN;
        out_t[r++] = tk;
    }
    return r;
}

static size_t dop_size(void) { return sizeof(Dop); }
static void dop_init(Step *s) { ((Dop *)s)->dense_ready = 0; }
static void dop_restart(Step *s) { (void)s; } /* a one-step method: nothing outlives a step */

static const Tableau dop_tableau = {DOP_STAGES, DOP_STAGES_EXT, DOP_A, DOP_B, DOP_C};

AMBLE_HIDDEN const Stepper dop853_stepper = {dop_size, dop_init, dop_restart, dop_step, dop_dense_prepare,
                                             dop_dense_eval, dop_dense_rows, 7, &dop_tableau};

#endif
