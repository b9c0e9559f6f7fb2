/* Tsitouras 5(4) (Ch. Tsitouras, "Runge–Kutta pairs of order 5(4) satisfying only the first
 * column simplifying assumption", Comput. Math. Appl. 62, 2011): an explicit pair of 7 stages,
 * the last at the step's end (first same as last: 6 right-hand sides per step), and a free
 * 4th-order dense output — its weights b_i(θ) are polynomials in θ over the same stages, so
 * locating an event costs no extra stage. The coefficients are those of the paper (as in
 * OrdinaryDiffEq.jl's Tsit5). The error norm and the step-size control are SciPy's RK45
 * (`integrate._ivp.rk`): RMS of h·Σ e_i K_i scaled by atol + max(|y_old|, |y|)·rtol, safety
 * 0.9, factors within [0.2, 10], no growth after a rejection, exponent −1/5.
 *
 * Compiled in the runtime; its stepper is tsit5_stepper (stepper.h). It does not aim its retries
 * at switching surfaces: a switch inside a step is located by the event logic after the plain
 * control has accepted the step.
 *
 * Needs from the including unit: stepper.h, events.h (the surfaces at a step's end), NXMAX, rhs.
 */
#ifndef AMBLE_TSIT5_H
#define AMBLE_TSIT5_H

#define TS_STAGES 7

static const double TS_C[TS_STAGES] = {0.0, 0.161, 0.327, 0.9, 0.9800255409045097, 1.0, 1.0};
/* row i: the stage i sum over stages j < i; row 6 is b (the solution's weights, b_6 = 0) */
static const double TS_A[TS_STAGES * TS_STAGES] = {
    0, 0, 0, 0, 0, 0, 0,
    0.161, 0, 0, 0, 0, 0, 0,
    -0.008480655492356989, 0.335480655492357, 0, 0, 0, 0, 0,
    2.897153057105493, -6.359448489975075, 4.3622954328695815, 0, 0, 0, 0,
    5.325864828439257, -11.748883564062828, 7.4955393428898365, -0.09249506636175525, 0, 0, 0,
    5.86145544294642, -12.92096931784711, 8.159367898576159, -0.071584973281401, -0.028269050394068383, 0, 0,
    0.09646076681806523, 0.01, 0.4798896504144996, 1.379008574103742, -3.290069515436081, 2.324710524099774, 0};
static const double *const TS_B = TS_A + 6 * TS_STAGES;
/* b − b̂: the difference of the 5th- and the 4th-order solutions */
static const double TS_E[TS_STAGES] = {-0.00178001105222577714, -0.0008164344596567469, 0.007880878010261995,
                                       -0.1447110071732629, 0.5823571654525552, -0.45808210592918697,
                                       0.015151515151515152};
/* the dense output's weights b_i(θ) = R[i][0] θ + R[i][1] θ² + R[i][2] θ³ + R[i][3] θ⁴ */
static const double TS_R[TS_STAGES][4] = {
    {1.0, -2.763706197274826, 2.9132554618219126, -1.0530884977290216},
    {0.0, 0.13169999999999998, -0.2234, 0.1017},
    {0.0, 3.9302962368947516, -5.941033872131505, 2.490627285651253},
    {0.0, -12.411077166933676, 30.33818863028232, -16.548102889244902},
    {0.0, 37.50931341651104, -88.1789048947664, 47.37952196281928},
    {0.0, -27.896526289197286, 65.09189467479366, -34.87065786149661},
    {0.0, 1.5, -4.0, 2.5}};

typedef struct {
    Step b; /* first: the state is reached from its Step */
    double K[TS_STAGES][AMBLE_NXCAP]; /* the last step's stages: K[0] = f_old, K[6] = f */
} Tsit5;

/* One accepted step (stepper.h); sw0, swd0 unread, *h_kink 0. */
static int tsit5_step(Step *s, int mode, const double *p, double t_bound, double rtol, double atol, double max_step,
                      double *h_abs, const double *sw0, const double *swd0, double *h_kink, double *g_new,
                      double *gd_new) {
    Tsit5 *ts = (Tsit5 *)s;
    const int n = s->n;
    const double t = s->t_old;
    const double min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
    double ha = *h_abs, ytmp[NXMAX];
    if (ha > max_step) ha = max_step;
    if (ha < min_step) ha = min_step;
    int rejected = 0, saw_nan = 0, saw_singular = 0;
    (void)sw0, (void)swd0;
    *h_kink = 0.0;
    for (;;) {
        if (ha < min_step) return saw_singular ? ST_SINGULAR_MASS : saw_nan ? ST_NONFINITE : ST_STEP_TOO_SMALL;
        double t_new = t + ha;
        if (t_new > t_bound) t_new = t_bound;
        const double h = t_new - t;
        ha = fabs(h);
        for (int i = 0; i < n; ++i) ts->K[0][i] = s->f_old[i];
        int bad = 0; /* a trial stage where M is singular: the step is too long (as in dop853_step.h) */
        for (int st = 1; st < TS_STAGES - 1 && !bad; ++st) {
            const double *a = TS_A + st * TS_STAGES;
            for (int i = 0; i < n; ++i) {
                double acc = 0.0;
                for (int j = 0; j < st; ++j) acc += a[j] * ts->K[j][i];
                ytmp[i] = s->y_old[i] + h * acc;
            }
            bad = rhs(mode, t + TS_C[st] * h, ytmp, p, ts->K[st]);
        }
        if (!bad) {
            for (int i = 0; i < n; ++i) {
                double acc = 0.0;
                for (int j = 0; j < TS_STAGES - 1; ++j) acc += TS_B[j] * ts->K[j][i];
                s->y[i] = s->y_old[i] + h * acc;
            }
            bad = rhs(mode, t + h, s->y, p, ts->K[TS_STAGES - 1]);
        }
        if (bad) {
            saw_singular = 1;
            ha *= 0.2;
            rejected = 1;
            continue;
        }
        double e2 = 0.0;
        for (int i = 0; i < n; ++i) {
            double acc = 0.0;
            for (int j = 0; j < TS_STAGES; ++j) acc += TS_E[j] * ts->K[j][i];
            const double sc = atol + fmax(fabs(s->y_old[i]), fabs(s->y[i])) * rtol, e = h * acc / sc;
            e2 += e * e;
        }
        const double err = sqrt(e2 / n);
        if (!isfinite(err) || !all_finite(n, s->y)) {
            saw_nan = 1;
            ha *= 0.2;
            rejected = 1;
            continue;
        }
        if (err < 1.0) {
            double factor = err == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -0.2));
            if (rejected && factor > 1.0) factor = 1.0;
            *h_abs = ha * factor;
            s->h = h;
            for (int i = 0; i < n; ++i) s->f[i] = ts->K[TS_STAGES - 1][i];
            surfaces(mode, t + h, s->y, p, g_new);
            surfaces_dot(mode, t + h, s->y, s->f, p, gd_new);
            return 0;
        }
        ha *= fmax(0.2, 0.9 * pow(err, -0.2));
        rejected = 1;
    }
}

static inline void tsit5_at(const Tsit5 *ts, double x, double *out) {
    const Step *s = &ts->b;
    double w[TS_STAGES];
    for (int j = 0; j < TS_STAGES; ++j) w[j] = x * (TS_R[j][0] + x * (TS_R[j][1] + x * (TS_R[j][2] + x * TS_R[j][3])));
    for (int i = 0; i < s->n; ++i) {
        double acc = 0.0;
        for (int j = 0; j < TS_STAGES; ++j) acc += w[j] * ts->K[j][i];
        out[i] = s->y_old[i] + s->h * acc;
    }
}

static void tsit5_dense_eval(const Step *s, double t, double *out) {
    tsit5_at((const Tsit5 *)s, (t - s->t_old) / s->h, out);
}

static int64_t tsit5_dense_rows(const Step *s, double t0, double dt, int64_t k0, int64_t k1, double t, double *out_t,
                                double *out_x) {
    int64_t r = 0;
    for (int64_t k = k0; k < k1; ++k) {
        const double tk = t0 + k * dt;
        if (tk <= t) continue;
        double *row = out_x + r * NXMAX;
        tsit5_at((const Tsit5 *)s, (tk - s->t_old) / s->h, row);
        for (int i = s->n; i < NXMAX; ++i) row[i] = NAN;
        out_t[r++] = tk;
    }
    return r;
}

/* the dense output is free: the step's own stages */
static int tsit5_dense_prepare(Step *s, int mode, const double *p) { (void)s, (void)mode, (void)p; return 0; }
static size_t tsit5_size(void) { return sizeof(Tsit5); }
static void tsit5_nothing(Step *s) { (void)s; } /* a one-step method: nothing outlives a step */

/* the sensitivities ride on the six stages the solution sums (b_6 = 0) */
static const Tableau tsit5_tableau = {TS_STAGES - 1, TS_STAGES, TS_A, TS_A + 6 * TS_STAGES, TS_C};

static const Stepper tsit5_stepper = {tsit5_size, tsit5_nothing, tsit5_nothing, tsit5_step, tsit5_dense_prepare,
                                      tsit5_dense_eval, tsit5_dense_rows, 4, &tsit5_tableau};

#endif
