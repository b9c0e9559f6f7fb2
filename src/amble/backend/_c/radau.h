/* Radau IIA of order 5 (Hairer & Wanner, "Solving ODEs II", IV.8) for stiff right-hand sides,
 * as in SciPy's `integrate._ivp.radau`: the same constants, simplified Newton iterations on the
 * collocation system in the eigenbasis of the Runge–Kutta matrix (one real and one complex
 * linear system per iteration), the same error estimate, step-size controller and cubic
 * collocation dense output. The Newton matrix uses the exact flow Jacobian ∂f/∂x of the model
 * (rhs_jac, generated from the symbolic equations), refreshed when Newton converges slowly.
 *
 * An accepted step fills the Step the event code reads (t_old, h, y_old, y, f_old, f) and the
 * collocation cubic, its dense output, so guards are screened and located exactly as for DOP853.
 * Compiled in the runtime; its stepper is radau_stepper (stepper.h).
 *
 * Needs from the including unit: stepper.h, events.h (the surfaces at a step's end),
 * amble_core.h's LU, NXMAX, SC, rhs, rhs_jac.
 */
#ifndef AMBLE_RADAU_H
#define AMBLE_RADAU_H

#define RADAU_NEWTON_MAXITER 6
#define RADAU_S6 2.449489742783178098197284

static const double RAD_C[3] = {(4.0 - RADAU_S6) / 10.0, (4.0 + RADAU_S6) / 10.0, 1.0};
static const double RAD_E[3] = {(-13.0 - 7.0 * RADAU_S6) / 3.0, (-13.0 + 7.0 * RADAU_S6) / 3.0, -1.0 / 3.0};
static const double RAD_T[3][3] = {{0.09443876248897524, -0.14125529502095421, 0.03002919410514742},
                                   {0.25021312296533332, 0.20412935229379994, -0.38294211275726192},
                                   {1.0, 1.0, 0.0}};
static const double RAD_TI[3][3] = {{4.17871859155190428, 0.32768282076106237, 0.52337644549944951},
                                    {-4.17871859155190428, -0.32768282076106237, 0.47662355450055044},
                                    {0.50287263494578682, -2.57192694985560522, 0.59603920482822492}};
static const double RAD_P[3][3] = {{13.0 / 3.0 + 7.0 * RADAU_S6 / 3.0, -23.0 / 3.0 - 22.0 * RADAU_S6 / 3.0, 10.0 / 3.0 + 5.0 * RADAU_S6},
                                   {13.0 / 3.0 - 7.0 * RADAU_S6 / 3.0, -23.0 / 3.0 + 22.0 * RADAU_S6 / 3.0, 10.0 / 3.0 - 5.0 * RADAU_S6},
                                   {1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0}};

/* The eigenvalues of the inverse Runge–Kutta matrix: one real, a complex pair (re − i·im). */
static double rad_mu_real(void) { return 3.0 + cbrt(9.0) - cbrt(3.0); }
static double rad_mu_re(void) { return 3.0 + 0.5 * (cbrt(3.0) - cbrt(9.0)); }
static double rad_mu_im(void) { return -0.5 * (pow(3.0, 5.0 / 6.0) + pow(3.0, 7.0 / 6.0)); }

typedef struct {
    double *J;                                     /* ∂f/∂x at the last Jacobian point (NXMAX rows of SC) */
    double *LUr, *LUc;                             /* NXMAX², 4 NXMAX² */
    int *pr, *pc;                                  /* NXMAX, 2 NXMAX */
    int have_jac, current_jac, have_lu, have_sol;
    double lu_h;                                   /* the step size the LU factors are for */
    double h_abs_old, err_old;                     /* for the predictive step-size controller */
} Radau;

/* The state of a run: the last step, its dense output y_old + Q0 θ + Q1 θ² + Q2 θ³
 * (θ = (t − t_old)/h), the Newton matrices; the workspace of radau_attach follows it. */
typedef struct {
    Step b; /* first: the state is reached from its Step */
    double Q[3][AMBLE_NXCAP];
    Radau r;
} RadauState;

/* The workspace of radau_attach, sized for the model. */
static int radau_doubles(void) { return NXMAX * SC + 5 * NXMAX * NXMAX; }
static int radau_ints(void) { return 3 * NXMAX; }

static void radau_attach(Radau *r, double *w, int *iw) {
    r->J = w;
    r->LUr = w + NXMAX * SC;
    r->LUc = r->LUr + NXMAX * NXMAX;
    r->pr = iw;
    r->pc = iw + NXMAX;
}

/* Forget everything tied to the current trajectory (after an event or a mode change). */
static void radau_reset(Radau *r) { r->have_jac = r->have_lu = r->have_sol = 0; r->h_abs_old = 0.0; r->err_old = 0.0; }

static double rad_norm(int n, const double *v) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += v[i] * v[i];
    return n > 0 ? sqrt(s / n) : 0.0;
}

/* LU factors of (μ/h) I − J: the real one n × n, the complex one as the real 2n × 2n block
 * [[re I − J, −im I], [im I, re I − J]]. */
static int radau_factor(Radau *r, int n, double h) {
    const double mr = rad_mu_real() / h, cr = rad_mu_re() / h, ci = rad_mu_im() / h;
    const int m = 2 * n;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double a = -r->J[i * SC + j], d = i == j;
            r->LUr[i * n + j] = mr * d + a;
            r->LUc[i * m + j] = cr * d + a;
            r->LUc[(n + i) * m + n + j] = cr * d + a;
            r->LUc[i * m + n + j] = -ci * d;
            r->LUc[(n + i) * m + j] = ci * d;
        }
    if (amble_lu_factor(n, r->LUr, r->pr) || amble_lu_factor(m, r->LUc, r->pc)) return 1;
    r->have_lu = 1;
    return 0;
}

static double rad_predict(double h_abs, double h_abs_old, double err, double err_old) {
    double mult = 1.0;
    if (err_old > 0.0 && h_abs_old > 0.0 && err > 0.0) mult = h_abs / h_abs_old * pow(err_old / err, 0.25);
    if (err == 0.0) return 10.0;
    return fmin(1.0, mult) * pow(err, -0.25);
}

/* Simplified Newton on the collocation system; Z (3 × n) holds the guess and the solution.
 * Returns 1 if it converged; *iters, *rate as in SciPy. */
static int radau_newton(Radau *r, int mode, const double *p, double t, const double *y, double h, int n,
                        const double *scale, double tol, double Z[3][NXMAX], int *iters, double *rate) {
    const double mr = rad_mu_real() / h, cr = rad_mu_re() / h, ci = rad_mu_im() / h;
    double W[3][NXMAX], F[3][NXMAX], yt[NXMAX], dW[3 * NXMAX], fc[2 * NXMAX];
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < n; ++i) W[k][i] = RAD_TI[k][0] * Z[0][i] + RAD_TI[k][1] * Z[1][i] + RAD_TI[k][2] * Z[2][i];
    double norm_old = -1.0;
    *rate = -1.0;
    for (int it = 0; it < RADAU_NEWTON_MAXITER; ++it) {
        *iters = it + 1;
        for (int k = 0; k < 3; ++k) {
            for (int i = 0; i < n; ++i) yt[i] = y[i] + Z[k][i];
            if (rhs(mode, t + RAD_C[k] * h, yt, p, F[k]) || !all_finite(n, F[k])) return 0;
        }
        for (int i = 0; i < n; ++i) {
            const double fr = RAD_TI[0][0] * F[0][i] + RAD_TI[0][1] * F[1][i] + RAD_TI[0][2] * F[2][i];
            const double fre = RAD_TI[1][0] * F[0][i] + RAD_TI[1][1] * F[1][i] + RAD_TI[1][2] * F[2][i];
            const double fim = RAD_TI[2][0] * F[0][i] + RAD_TI[2][1] * F[1][i] + RAD_TI[2][2] * F[2][i];
            dW[i] = fr - mr * W[0][i];
            /* (cr + i ci)(W1 + i W2) */
            fc[i] = fre - (cr * W[1][i] - ci * W[2][i]);
            fc[n + i] = fim - (cr * W[2][i] + ci * W[1][i]);
        }
        amble_lu_apply(n, r->LUr, r->pr, dW, 1);
        amble_lu_apply(2 * n, r->LUc, r->pc, fc, 1);
        for (int i = 0; i < n; ++i) { dW[n + i] = fc[i]; dW[2 * n + i] = fc[n + i]; }
        double nrm = 0.0;
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < n; ++i) { double v = dW[k * n + i] / scale[i]; nrm += v * v; }
        nrm = sqrt(nrm / (3 * n));
        if (norm_old >= 0.0) *rate = nrm / norm_old;
        if (*rate >= 0.0 && (*rate >= 1.0 || pow(*rate, RADAU_NEWTON_MAXITER - it) / (1.0 - *rate) * nrm > tol)) return 0;
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < n; ++i) W[k][i] += dW[k * n + i];
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < n; ++i) Z[k][i] = RAD_T[k][0] * W[0][i] + RAD_T[k][1] * W[1][i] + RAD_T[k][2] * W[2][i];
        if (nrm == 0.0 || (*rate >= 0.0 && *rate / (1.0 - *rate) * nrm < tol)) return 1;
        norm_old = nrm;
    }
    return 0;
}

/* One accepted Radau IIA step from (t_old, y_old) with f_old known (stepper.h); no aiming at
 * switches (sw0, swd0 unread, *h_kink 0). The surfaces at its end are evaluated afresh. */
static int radau_step(Step *s, int mode, const double *p, double t_bound, double rtol, double atol,
                      double max_step, double *h_abs_io, const double *sw0, const double *swd0, double *h_kink,
                      double *g_new, double *gd_new) {
    RadauState *rs = (RadauState *)s;
    Radau *r = &rs->r;
    (void)sw0, (void)swd0;
    *h_kink = 0.0;
    const int n = s->n;
    const double t = s->t_old;
    const double min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
    const double newton_tol = fmax(10.0 * DBL_EPSILON / rtol, fmin(0.03, sqrt(rtol)));
    double h_abs = *h_abs_io, h_abs_old = r->h_abs_old, err_old = r->err_old;
    if (h_abs > max_step) { h_abs = max_step; h_abs_old = 0.0; err_old = 0.0; }
    else if (h_abs < min_step) { h_abs = min_step; h_abs_old = 0.0; err_old = 0.0; }
    if (!r->have_jac) {
        double dx[NXMAX];
        if (rhs_jac(mode, t, s->y_old, p, dx, r->J)) return ST_SINGULAR_MASS;
        r->have_jac = r->current_jac = 1;
        r->have_lu = 0;
    }
    double Z[3][NXMAX], scale[NXMAX], err[NXMAX], tmp[NXMAX], ynew[NXMAX], fnew[NXMAX];
    int rejected = 0, iters = 0;
    double rate = -1.0, err_norm = 0.0, h = 0.0;
    for (;;) {
        if (h_abs < min_step) return ST_STEP_TOO_SMALL;
        double t_new = t + h_abs;
        if (t_new > t_bound) t_new = t_bound;
        h = t_new - t;
        h_abs = fabs(h);
        if (r->have_lu && r->lu_h != h) r->have_lu = 0;
        /* predictor: the previous step's collocation polynomial, extrapolated (s->h and s->Q still
         * describe it; it ends at the current state, θ = 1, where its value is y + ΣQ − ΣQ) */
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < n; ++i) {
                if (r->have_sol) {
                    const double th = 1.0 + RAD_C[k] * h / s->h;
                    Z[k][i] = th * (rs->Q[0][i] + th * (rs->Q[1][i] + th * rs->Q[2][i])) - (rs->Q[0][i] + rs->Q[1][i] + rs->Q[2][i]);
                } else {
                    Z[k][i] = 0.0;
                }
            }
        for (int i = 0; i < n; ++i) scale[i] = atol + fabs(s->y_old[i]) * rtol;
        int converged = 0;
        for (;;) {
            if (!r->have_lu) {
                if (radau_factor(r, n, h)) return ST_SINGULAR_MASS;
                r->lu_h = h;
            }
            converged = radau_newton(r, mode, p, t, s->y_old, h, n, scale, newton_tol, Z, &iters, &rate);
            if (converged || r->current_jac) break;
            double dx[NXMAX];
            if (rhs_jac(mode, t, s->y_old, p, dx, r->J)) return ST_SINGULAR_MASS;
            r->current_jac = 1;
            r->have_lu = 0;
        }
        if (!converged) { h_abs *= 0.5; r->have_lu = 0; continue; }
        for (int i = 0; i < n; ++i) ynew[i] = s->y_old[i] + Z[2][i];
        for (int i = 0; i < n; ++i) {
            const double ze = (RAD_E[0] * Z[0][i] + RAD_E[1] * Z[1][i] + RAD_E[2] * Z[2][i]) / h;
            err[i] = s->f_old[i] + ze;
            tmp[i] = ze;
        }
        amble_lu_apply(n, r->LUr, r->pr, err, 1);
        for (int i = 0; i < n; ++i) scale[i] = atol + fmax(fabs(s->y_old[i]), fabs(ynew[i])) * rtol;
        for (int i = 0; i < n; ++i) fnew[i] = err[i] / scale[i];
        err_norm = rad_norm(n, fnew);
        const double safety = 0.9 * (2 * RADAU_NEWTON_MAXITER + 1) / (2 * RADAU_NEWTON_MAXITER + iters);
        if (rejected && err_norm > 1.0) {
            double ye[NXMAX], fe[NXMAX];
            for (int i = 0; i < n; ++i) ye[i] = s->y_old[i] + err[i];
            if (rhs(mode, t, ye, p, fe)) return ST_SINGULAR_MASS;
            for (int i = 0; i < n; ++i) err[i] = fe[i] + tmp[i];
            amble_lu_apply(n, r->LUr, r->pr, err, 1);
            for (int i = 0; i < n; ++i) fnew[i] = err[i] / scale[i];
            err_norm = rad_norm(n, fnew);
        }
        if (!isfinite(err_norm) || err_norm > 1.0) {
            const double factor = rad_predict(h_abs, h_abs_old, err_norm, err_old);
            h_abs *= isfinite(err_norm) ? fmax(0.2, safety * factor) : 0.2;
            r->have_lu = 0;
            rejected = 1;
            continue;
        }
        /* accepted */
        const int recompute_jac = iters > 2 && rate > 1e-3;
        double factor = fmin(10.0, safety * rad_predict(h_abs, h_abs_old, err_norm, err_old));
        if (!recompute_jac && factor < 1.2) factor = 1.0;
        else r->have_lu = 0;
        if (rhs(mode, t + h, ynew, p, fnew)) return ST_SINGULAR_MASS;
        if (recompute_jac) {
            double dx[NXMAX];
            if (rhs_jac(mode, t + h, ynew, p, dx, r->J)) return ST_SINGULAR_MASS;
            r->current_jac = 1;
        } else {
            r->current_jac = 0;
        }
        r->h_abs_old = *h_abs_io;
        r->err_old = err_norm;
        *h_abs_io = h_abs * factor;
        s->h = h;
        for (int i = 0; i < n; ++i) {
            s->y[i] = ynew[i];
            s->f[i] = fnew[i];
            for (int k = 0; k < 3; ++k) rs->Q[k][i] = Z[0][i] * RAD_P[0][k] + Z[1][i] * RAD_P[1][k] + Z[2][i] * RAD_P[2][k];
        }
        r->have_sol = 1;
        surfaces(mode, t + h, s->y, p, g_new);
        surfaces_dot(mode, t + h, s->y, s->f, p, gd_new);
        return 0;
    }
}

static size_t radau_size(void) {
    return sizeof(RadauState) + (size_t)radau_doubles() * sizeof(double) + (size_t)radau_ints() * sizeof(int);
}

static void radau_init(Step *s) {
    RadauState *rs = (RadauState *)s;
    double *w = (double *)(rs + 1);
    radau_attach(&rs->r, w, (int *)(w + radau_doubles()));
    radau_reset(&rs->r);
}

static void radau_restart(Step *s) { radau_reset(&((RadauState *)s)->r); }

/* the collocation cubic is the dense output: always ready */
static int radau_dense_prepare(Step *s, int mode, const double *p) { (void)s, (void)mode, (void)p; return 0; }

static inline void radau_dense_at(const RadauState *rs, double x, double *out) {
    const Step *s = &rs->b;
    for (int i = 0; i < s->n; ++i) out[i] = s->y_old[i] + x * (rs->Q[0][i] + x * (rs->Q[1][i] + x * rs->Q[2][i]));
}

static void radau_dense_eval(const Step *s, double t, double *out) {
    radau_dense_at((const RadauState *)s, (t - s->t_old) / s->h, out);
}

static int64_t radau_dense_rows(const Step *s, double t0, double dt, int64_t k0, int64_t k1, double t, double *out_t,
                                double *out_x) {
    int64_t r = 0;
    for (int64_t k = k0; k < k1; ++k) {
        const double tk = t0 + k * dt;
        if (tk <= t) continue;
        double *row = out_x + r * NXMAX;
        radau_dense_at((const RadauState *)s, (tk - s->t_old) / s->h, row);
        for (int i = s->n; i < NXMAX; ++i) row[i] = NAN;
        out_t[r++] = tk;
    }
    return r;
}

/* the initial step's exponent as DOP853's (runs keep the steps they had) */
static const Stepper radau_stepper = {radau_size, radau_init, radau_restart, radau_step, radau_dense_prepare,
                                      radau_dense_eval, radau_dense_rows, 7, NULL};

#endif
