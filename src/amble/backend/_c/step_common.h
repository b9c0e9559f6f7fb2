/* The pieces of a step every method shares (stepper.h), compiled in the model's unit: the
 * right-hand side is inlined into them and, with NX_FIXED, their loops over the state have
 * constant trip counts (the Hermite screen runs at every sample of every step).
 *
 * Needs from the including unit: the model's rhs, NXMAX, and NX_FIXED if its modes share a length.
 */
#ifndef AMBLE_STEP_COMMON_H
#define AMBLE_STEP_COMMON_H
#include "stepper.h"

/* The state length of a step. A unit whose modes all have one length defines NX_FIXED to it, so
 * every loop over the state has a constant trip count and is unrolled by the compiler (measured:
 * the stage sums are a third of the compass gait's integrator time with a run-time length). */
#ifdef NX_FIXED
#define STEP_N(s) NX_FIXED
#else
#define STEP_N(s) ((s)->n)
#endif

static double rms_norm(int n, const double *v) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += v[i] * v[i];
    return sqrt(s / n);
}

/* Initial step size as in Hairer's / SciPy's select_initial_step. */
AMBLE_HIDDEN double initial_step(int mode, double t, const double *y, const double *f, const double *p,
                                 double t_bound, double max_step, double rtol, double atol, int n, int error_order) {
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
    else h1 = pow(0.01 / fmax(d1, d2), 1.0 / (error_order + 1));
    double h = fmin(100 * h0, h1);
    h = fmin(h, interval);
    return fmin(h, max_step);
}

/* Cubic Hermite through both step ends: cheap, for spotting sign changes inside a step. */
AMBLE_HIDDEN void hermite_eval(const Step *s, double theta, double *out) {
    const double h = s->h;
    double t2 = theta * theta, t3 = t2 * theta;
    double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + theta, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
    for (int i = 0; i < STEP_N(s); ++i)
        out[i] = h00 * s->y_old[i] + h10 * h * s->f_old[i] + h01 * s->y[i] + h11 * h * s->f[i];
}

#endif
