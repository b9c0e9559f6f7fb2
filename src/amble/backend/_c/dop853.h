/* The state of the DOP853 integrator (dop853_step.h) and the calls the rest of the engine makes on
 * it. Shared by the model's unit, which compiles the step, and the runtime (runtime.c), compiled
 * once per capacity: the arrays hold AMBLE_NXCAP entries (the model's NXMAX rounded up to a
 * capacity bucket, backend/runtime.py), the same in both units.
 *
 * Needs from the including unit: AMBLE_NXCAP, AMBLE_HIDDEN (amble_core.h).
 */
#ifndef AMBLE_DOP853_H
#define AMBLE_DOP853_H
#include "dop853_tableau.h"

typedef struct {
    int n;
    double t_old, h;
    double y_old[AMBLE_NXCAP], y[AMBLE_NXCAP], f_old[AMBLE_NXCAP], f[AMBLE_NXCAP];
    double K[DOP_STAGES_EXT][AMBLE_NXCAP];
    double F[DOP_INTERP][AMBLE_NXCAP];
    int dense_ready;
    /* set by an implicit (Radau IIA) step: its dense output is the collocation cubic
     * y_old + Q0 θ + Q1 θ² + Q2 θ³ (θ = (t − t_old)/h), always ready */
    int radau;
    double Q[3][AMBLE_NXCAP];
} Dop;

static int all_finite(int n, const double *x) {
    for (int i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* Initial step size as in Hairer's / SciPy's select_initial_step. */
AMBLE_HIDDEN double initial_step(int mode, double t, const double *y, const double *f, const double *p,
                                 double t_bound, double max_step, double rtol, double atol, int n);
/* One accepted DOP853 step from (t_old, y_old) with f_old known. Returns 0, or a status. A
 * rejected trial that crosses a switching surface (sw0, swd0: the mode's switching values and
 * slopes at the start, or NULL) is retried aimed at it; *h_kink is then the step size
 * proposed before it, else 0. g_new, gd_new (or NULL): the mode's surfaces and their rates at the
 * step's end, evaluated with its last stage. */
AMBLE_HIDDEN int dop_step(Dop *s, int mode, const double *p, double t_bound, double rtol, double atol,
                          double max_step, double *h_abs, const double *sw0, const double *swd0, double *h_kink,
                          double *g_new, double *gd_new);
/* The 7th-order continuous extension of the last step (three extra stages); 0 or ST_SINGULAR_MASS. */
AMBLE_HIDDEN int dop_dense_prepare(Dop *s, int mode, const double *p);
/* The dense output of the last step at t. */
AMBLE_HIDDEN void dop_dense_eval(const Dop *restrict s, double t, double *restrict out);
/* Rows of the dense output at the grid times t0 + k·dt (k0 <= k < k1) after t: times into out_t,
 * states into rows of out_x (NXMAX entries, NaN-padded); returns the number of rows. */
AMBLE_HIDDEN int64_t dop_dense_rows(const Dop *restrict s, double t0, double dt, int64_t k0, int64_t k1, double t,
                                    double *restrict out_t, double *restrict out_x);
/* Cubic Hermite through both step ends at θ ∈ [0, 1]: cheap, for spotting sign changes. */
AMBLE_HIDDEN void hermite_eval(const Dop *s, double theta, double *out);

#endif
