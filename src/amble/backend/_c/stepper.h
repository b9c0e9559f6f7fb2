/* The integrator seam: what the hybrid loop (hybrid.c), the event location (events.h), the
 * recording (record.h) and the sensitivities (sensitivity.h) know of an integrator. The split is
 * SciPy's OdeSolver: a step (with its own error norm and step-size control, as _step_impl), a
 * dense output of the last step (_dense_output_impl), and a restart when the flow jumps.
 *
 * Every method keeps the last accepted step in a Step at the start of its own state (its struct
 * begins with a Step member, so a pointer to the state is a pointer to the Step and back), and
 * exposes one Stepper, `<name>_stepper`, in its file `<name>.h`. The table STEPPERS of the
 * generated amble_steppers.h (amble/backend/abi.py: METHODS) maps the method codes MT_* to them.
 *
 * Shared by the model's unit and the runtime: the arrays hold AMBLE_NXCAP entries.
 * Needs from the including unit: AMBLE_NXCAP, AMBLE_HIDDEN (amble_core.h).
 */
#ifndef AMBLE_STEPPER_H
#define AMBLE_STEPPER_H
#include <stddef.h>

struct Stepper;

/* The last accepted step, from (t_old, y_old, f_old = f(y_old)) to (t_old + h, y, f). */
typedef struct {
    const struct Stepper *m; /* the method that took it */
    int n;
    double t_old, h;
    double y_old[AMBLE_NXCAP], y[AMBLE_NXCAP], f_old[AMBLE_NXCAP], f[AMBLE_NXCAP];
} Step;

/* An explicit Runge–Kutta tableau: the stages b sums over (a row-major, row i at a + i·stride;
 * b, c of `stages` entries). The sensitivities take a step of the variational equations on it. */
typedef struct {
    int stages, stride;
    const double *a, *b, *c;
} Tableau;

typedef struct Stepper {
    /* bytes of the method's state (its struct and any workspace) for the model at hand */
    size_t (*size)(void);
    /* attach the state's workspace; once per call of the loop, before anything else */
    void (*init)(Step *s);
    /* the flow jumps (an event, a mode change): forget what is tied to the old trajectory */
    void (*restart)(Step *s);
    /* One accepted step from (t_old, y_old) with f_old known, of a size up to *h_abs (≤ max_step,
     * ending at t_bound at most); *h_abs then holds the proposed next size. Returns 0, or a status.
     * sw0, swd0: the mode's switching values and slopes at the start (NULL: none), for a method
     * that aims its retries at a switch; *h_kink: the size proposed before a switch spoiled the
     * step, else 0. g_new, gd_new: the mode's surfaces and their rates at the step's end. */
    int (*step)(Step *s, int mode, const double *p, double t_bound, double rtol, double atol, double max_step,
                double *h_abs, const double *sw0, const double *swd0, double *h_kink, double *g_new, double *gd_new);
    /* make the dense output of the last step ready (extra stages); 0 or ST_SINGULAR_MASS */
    int (*dense_prepare)(Step *s, int mode, const double *p);
    /* the dense output of the last step at t (dense_prepare done) */
    void (*dense_eval)(const Step *s, double t, double *out);
    /* rows of the dense output at t0 + k·dt (k0 ≤ k < k1) after t: times into out_t, states into
     * rows of out_x (NXMAX entries, NaN-padded); returns the number of rows */
    int64_t (*dense_rows)(const Step *s, double t0, double dt, int64_t k0, int64_t k1, double t, double *out_t,
                          double *out_x);
    /* the order of the error estimate, for the initial step size (h ∝ err^(1/(order+1))) */
    int error_order;
    /* the explicit tableau the sensitivities step on, or NULL: none (abi.py: has_sensitivities) */
    const Tableau *tableau;
} Stepper;

static inline int step_dense_prepare(Step *s, int mode, const double *p) { return s->m->dense_prepare(s, mode, p); }
static inline void step_dense_eval(const Step *s, double t, double *out) { s->m->dense_eval(s, t, out); }

static int all_finite(int n, const double *x) {
    for (int i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* Initial step size as in Hairer's / SciPy's select_initial_step, for an error estimate of
 * order `error_order`. */
AMBLE_HIDDEN double initial_step(int mode, double t, const double *y, const double *f, const double *p,
                                 double t_bound, double max_step, double rtol, double atol, int n, int error_order);
/* Cubic Hermite through both step ends at θ ∈ [0, 1]: cheap, for spotting sign changes. */
AMBLE_HIDDEN void hermite_eval(const Step *s, double theta, double *out);

#endif
