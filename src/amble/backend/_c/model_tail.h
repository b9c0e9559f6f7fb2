/* The end of a model's translation unit: what the runtime (runtime.c, compiled once and linked
 * into every model's library) reads of this model.
 *
 * The runtime knows a model only through hidden symbols resolved when the library is linked —
 * no function pointers, no exported names:
 *   the model's sizes, as constants (amble_m_*; the per-mode and per-transition tables MODE_*,
 *     TR_* are defined, not static, by the generated code);
 *   its kernels, as thin wrappers amble_k_* of the unit's static dispatchers (which the compiler
 *     inlines into them);
 *   the DOP853 step (dop853_step.h) and the pieces every method's step shares (step_common.h),
 *     compiled here so that the right-hand side is inlined into the stage loop and, with
 *     NX_FIXED, the state loops have constant trip counts.
 * The runtime was compiled for AMBLE_NXCAP state entries of the integrator's arrays: the symbol
 * amble_nxcap_<AMBLE_NXCAP> it references exists only in a unit generated for that capacity, so a
 * model linked with the runtime of another capacity fails to link instead of misreading.
 *
 * Needs from the including unit: the generated kernels and tables, the macros NMODES, NXMAX, NTR,
 * NPOINTS, NPARAM, NSWMAX, NPFULL, the ST_* codes, and AMBLE_NXCAP.
 */
#ifndef AMBLE_MODEL_TAIL_H
#define AMBLE_MODEL_TAIL_H
#include "dop853_step.h"

typedef char amble_capacity_fits[NXMAX <= AMBLE_NXCAP ? 1 : -1]; /* a compile error otherwise */

#define AMBLE_CAT_(a, b) a##b
#define AMBLE_CAT(a, b) AMBLE_CAT_(a, b)
AMBLE_HIDDEN const int AMBLE_CAT(amble_nxcap_, AMBLE_NXCAP) = AMBLE_NXCAP;

AMBLE_HIDDEN const int amble_m_nmodes = NMODES, amble_m_nxmax = NXMAX, amble_m_ntr = NTR,
                       amble_m_npoints = NPOINTS, amble_m_nparam = NPARAM, amble_m_nswmax = NSWMAX,
                       amble_m_npfull = NPFULL;

AMBLE_HIDDEN void amble_k_params(const double *p, double *q) { amble_params_prelude(p, q); }
AMBLE_HIDDEN int amble_k_rhs(int mode, double t, const double *x, const double *p, double *dx) {
    return rhs(mode, t, x, p, dx);
}
AMBLE_HIDDEN void amble_k_guards(int mode, double t, const double *x, const double *p, double *g) {
    guards(mode, t, x, p, g);
}
AMBLE_HIDDEN void amble_k_guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g) {
    guards_dot(mode, t, x, dx, p, g);
}
AMBLE_HIDDEN void amble_k_switches(int mode, double t, const double *x, const double *p, double *s) {
    switches(mode, t, x, p, s);
}
AMBLE_HIDDEN void amble_k_switches_dot(int mode, double t, const double *x, const double *dx, const double *p, double *s) {
    switches_dot(mode, t, x, dx, p, s);
}
AMBLE_HIDDEN int amble_k_enabled(int tr, double t, const double *x, const double *p) { return enabled(tr, t, x, p); }
AMBLE_HIDDEN int amble_k_reset(int tr, double t, const double *x, const double *p, double *xout, int *target) {
    return reset(tr, t, x, p, xout, target);
}
AMBLE_HIDDEN int amble_k_constraint_forces(int mode, double t, const double *x, const double *p, double *lam) {
    return constraint_forces(mode, t, x, p, lam);
}
AMBLE_HIDDEN void amble_k_dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G) {
    dynamics(mode, t, x, p, M, h, G);
}
AMBLE_HIDDEN void amble_k_energy(int mode, double t, const double *x, const double *p, double *out) {
    energy(mode, t, x, p, out);
}
AMBLE_HIDDEN void amble_k_kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel) {
    kinematics(mode, t, x, p, pos, vel);
}
AMBLE_HIDDEN int amble_k_rhs_jac(int mode, double t, const double *x, const double *p, double *dx, double *J) {
    return rhs_jac(mode, t, x, p, dx, J);
}
AMBLE_HIDDEN int amble_k_rhs_jacp(int mode, double t, const double *x, const double *p, double *J) {
    return rhs_jacp(mode, t, x, p, J);
}
AMBLE_HIDDEN void amble_k_surfaces_grad(int mode, double t, const double *x, const double *p, double *G) {
    surfaces_grad(mode, t, x, p, G);
}
AMBLE_HIDDEN int amble_k_reset_jac(int tr, double t, const double *x, const double *p, double *D) {
    return reset_jac(tr, t, x, p, D);
}

#endif
