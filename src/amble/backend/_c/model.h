/* The model as the runtime sees it: sizes, tables and kernels that the model's own unit defines
 * (model_tail.h and the generated code), resolved when the model's library is linked.
 *
 * The sizes are run-time values here, not macros of constants: the runtime is compiled once for
 * every model of a capacity bucket. Local arrays sized by them are C99 variable-length arrays of
 * the model's own length (stack use as if the runtime were compiled for the model); the
 * integrator's state (Step, stepper.h) holds AMBLE_NXCAP entries. The row stride of caller-owned buffers
 * (recorded rows, batches, the sensitivity layout of abi.py) is the model's NXMAX.
 *
 * Needs from the including unit: amble_core.h (AMBLE_HIDDEN).
 */
#ifndef AMBLE_MODEL_H
#define AMBLE_MODEL_H

extern AMBLE_HIDDEN const int amble_m_nmodes, amble_m_nxmax, amble_m_ntr, amble_m_npoints, amble_m_nparam,
    amble_m_nswmax, amble_m_npfull;
#define NMODES amble_m_nmodes
#define NXMAX amble_m_nxmax   /* the model's longest state */
#define NTR amble_m_ntr
#define NPOINTS amble_m_npoints
#define NPARAM amble_m_nparam
#define NSWMAX amble_m_nswmax /* switching surfaces of the mode with most */
#define NPFULL amble_m_npfull /* parameters and their hoisted subexpressions (backend/hoist.py) */
#define SC (NXMAX + NPARAM)   /* columns of a sensitivity row: state, then parameters */

/* per mode: state length, number and first index of its transitions and of its switching surfaces;
 * per transition: guard direction, terminal, counts as a step, its rest transition (or -1) */
extern AMBLE_HIDDEN const int MODE_NX[], MODE_NTR[], MODE_TR0[], MODE_NSW[], MODE_SW0[];
extern AMBLE_HIDDEN const int TR_DIR[], TR_TERMINAL[], TR_STEP[], TR_REST[];

/* the capacity check of model_tail.h */
#define AMBLE_CAT_(a, b) a##b
#define AMBLE_CAT(a, b) AMBLE_CAT_(a, b)
extern AMBLE_HIDDEN const int AMBLE_CAT(amble_nxcap_, AMBLE_NXCAP);

AMBLE_HIDDEN void amble_k_params(const double *p, double *q);
AMBLE_HIDDEN int amble_k_rhs(int mode, double t, const double *x, const double *p, double *dx);
AMBLE_HIDDEN void amble_k_guards(int mode, double t, const double *x, const double *p, double *g);
AMBLE_HIDDEN void amble_k_guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g);
AMBLE_HIDDEN void amble_k_switches(int mode, double t, const double *x, const double *p, double *s);
AMBLE_HIDDEN void amble_k_switches_dot(int mode, double t, const double *x, const double *dx, const double *p, double *s);
AMBLE_HIDDEN int amble_k_enabled(int tr, double t, const double *x, const double *p);
AMBLE_HIDDEN int amble_k_reset(int tr, double t, const double *x, const double *p, double *xout, int *target);
AMBLE_HIDDEN int amble_k_constraint_forces(int mode, double t, const double *x, const double *p, double *lam);
AMBLE_HIDDEN void amble_k_dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G);
AMBLE_HIDDEN void amble_k_energy(int mode, double t, const double *x, const double *p, double *out);
AMBLE_HIDDEN void amble_k_kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel);
AMBLE_HIDDEN int amble_k_rhs_jac(int mode, double t, const double *x, const double *p, double *dx, double *J);
AMBLE_HIDDEN int amble_k_rhs_jacp(int mode, double t, const double *x, const double *p, double *J);
AMBLE_HIDDEN void amble_k_surfaces_grad(int mode, double t, const double *x, const double *p, double *G);
AMBLE_HIDDEN int amble_k_reset_jac(int tr, double t, const double *x, const double *p, double *D);
#define rhs amble_k_rhs
#define guards amble_k_guards
#define guards_dot amble_k_guards_dot
#define switches amble_k_switches
#define switches_dot amble_k_switches_dot
#define enabled amble_k_enabled
#define reset amble_k_reset
#define dynamics amble_k_dynamics
#define constraint_forces amble_k_constraint_forces
#define energy amble_k_energy
#define kinematics amble_k_kinematics
#define rhs_jac amble_k_rhs_jac
#define rhs_jacp amble_k_rhs_jacp
#define surfaces_grad amble_k_surfaces_grad
#define reset_jac amble_k_reset_jac

/* Each exported entry point that calls kernels starts with it: the caller's NPARAM parameters p
 * replaced by the NPFULL values every kernel reads. */
#define AMBLE_PARAMS(p) double p##_full_[NPFULL]; amble_k_params(p, p##_full_); p = p##_full_

#endif
