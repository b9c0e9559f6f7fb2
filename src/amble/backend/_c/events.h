/* Event location inside one accepted integration step.
 *
 * A step is screened by sampling each guard of the mode at a few times inside it (a uniform grid
 * plus, per guard, the extremum of the cubic through g and ġ at both ends) on the cheap Hermite
 * interpolant; only if some guard changes sign in its direction is the method's dense output
 * built, the samples redone on it, and each bracketed crossing refined by regula falsi (locate).
 * The event is the earliest crossing whose enabling condition holds there. What happens on a
 * switching surface itself (its side, sliding, crossings within rounding) is switch_side.h's.
 *
 * Needs from the including unit: stepper.h, the ST_* codes, NTR, NSWMAX, NSUB_MAX, MODE_NTR,
 * MODE_TR0, MODE_NSW, TR_DIR and guards, guards_dot, switches, switches_dot, enabled.
 */
#ifndef AMBLE_EVENTS_H
#define AMBLE_EVENTS_H
#include <float.h>

/* The surfaces of a mode: its transitions' guards (indices 0 .. MODE_NTR-1), then the switching
 * surfaces of its right-hand side (events without a reset; both directions, always enabled). */
#define NTR1 (NTR + NSWMAX > 0 ? NTR + NSWMAX : 1)
#define NSAMP_MAX (NSUB_MAX + 1 + 2 * (NTR + NSWMAX))

static int n_surf(int mode) { return MODE_NTR[mode] + MODE_NSW[mode]; }

static void surfaces(int mode, double t, const double *x, const double *p, double *g) {
    guards(mode, t, x, p, g);
    if (MODE_NSW[mode] > 0) switches(mode, t, x, p, g + MODE_NTR[mode]);
}

static void surfaces_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g) {
    guards_dot(mode, t, x, dx, p, g);
    if (MODE_NSW[mode] > 0) switches_dot(mode, t, x, dx, p, g + MODE_NTR[mode]);
}

static int surf_dir(int mode, int k) { return k < MODE_NTR[mode] ? TR_DIR[MODE_TR0[mode] + k] : 0; }

/* A step transition also needs a step of non-zero duration: t after t_min (the last step). */
static int surf_enabled(int mode, int k, double t, const double *x, const double *p, double t_min) {
    if (k >= MODE_NTR[mode]) return 1;
    if (TR_STEP[MODE_TR0[mode] + k] && !(t > t_min)) return 0;
    return enabled(MODE_TR0[mode] + k, t, x, p);
}

/* A guard zero where a mode is entered (after a reset, at the start) cannot be seen crossing
 * from its pre-crossing side. If it is exactly zero and ġ there points across it in its
 * direction, the crossing is genuine and the guard is placed on the pre-crossing side by the
 * smallest amount. If it is zero up to round-off with ġ ≈ 0 (a point left at rest on the ground:
 * restitution 0, or started there), the flow an instant later decides: accelerating across, it
 * fires again at once (and repeated zero-time events end the run as zeno) instead of sinking
 * through unseen. `fired`: index within the mode of a transition that has just fired into its
 * own mode; it sits on its own root and only the second test applies to it.
 * `start`: the state is where the run starts (no transition yet). A step transition's guard is
 * then left as it is: a run started on its section (an apex, a post-impact state) has that point
 * as its first section point, and the step is the next crossing, not one at t = 0. Impacts and
 * terminals are armed at the start too: a point started on the ground moving into it strikes it. */
static void arm_zero_guards(int mode, double t, const double *x, const double *f, const double *p, int n,
                            double *g, const double *gd, int fired, int start) {
    double scale = 1.0;
    for (int i = 0; i < n; ++i) scale = fmax(scale, fabs(x[i]));
    for (int k = 0; k < MODE_NTR[mode]; ++k) {
        const int dir = TR_DIR[MODE_TR0[mode] + k];
        if (start && TR_STEP[MODE_TR0[mode] + k]) continue;
        if (fabs(gd[k]) > 1e-12 * scale) {
            if (k == fired || g[k] != 0.0) continue;
            if (dir == 0 || (dir < 0) == (gd[k] < 0.0)) g[k] = gd[k] < 0.0 ? DBL_MIN : -DBL_MIN;
            continue;
        }
        if (fabs(g[k]) > 1e-12 * scale) continue;
        double x1[NXMAX], f1[NXMAX], g1[NTR1];
        const double dt = 1.5e-8 * fmax(1.0, fabs(t));
        for (int i = 0; i < n; ++i) x1[i] = x[i] + dt * f[i];
        if (rhs(mode, t + dt, x1, p, f1)) continue;
        surfaces_dot(mode, t + dt, x1, f1, p, g1);
        if (g1[k] == 0.0) continue;
        if (dir == 0 || (dir < 0) == (g1[k] < 0.0)) g[k] = g1[k] < 0.0 ? DBL_MIN : -DBL_MIN;
    }
}

static int crosses(int dir, double ga, double gb) {
    if (dir < 0) return ga > 0.0 && gb <= 0.0;
    if (dir > 0) return ga < 0.0 && gb >= 0.0;
    return (ga > 0.0 && gb <= 0.0) || (ga < 0.0 && gb >= 0.0);
}

/* Guard k of `mode` along the dense output at time t. */
static double guard_at(const Step *s, int mode, int k, double t, const double *p, double *xbuf) {
    double g[NTR1];
    step_dense_eval(s, t, xbuf);
    surfaces(mode, t, xbuf, p, g);
    return g[k];
}

/* Root of guard k in [ta, tb] (crossing in direction dir) on the dense output by regula falsi
 * with the Anderson–Björck modification (the end kept twice has its value scaled by 1 − g_new /
 * g_replaced, or halved — Illinois — if that is not positive); returns a time on the far side of
 * the crossing, within ~1e-14 relative. Compass gait, 400 crossings: 6.5 evaluations on average,
 * none above 10 (the Illinois method: 11.2 on average, up to 27). */
static double locate(const Step *s, int mode, int k, int dir, double ta, double ga, double tb,
                     double gb, const double *p) {
    double xbuf[NXMAX];
    int side = 0;
    double tol = 4e-16 * fmax(1.0, fmax(fabs(ta), fabs(tb)));
    for (int it = 0; it < 200 && (tb - ta) > tol; ++it) {
        double tm = (ga * tb - gb * ta) / (ga - gb);
        /* a secant point within the tolerance of an end is moved to that distance from it: with
         * one end converged onto the root (its g at round-off) the secant keeps falling onto it,
         * and bisecting instead took up to 30 evaluations; this step brackets the root at once */
        const double d = 0.5 * tol;
        if (!(tm > ta + d)) tm = ta + d;
        else if (!(tm < tb - d)) tm = tb - d;
        if (!(tm > ta && tm < tb)) tm = 0.5 * (ta + tb);
        double gm = guard_at(s, mode, k, tm, p, xbuf);
        if (crosses(dir, ga, gm)) {
            if (side == -1) { const double m = 1.0 - gm / gb; ga *= m > 0.0 ? m : 0.5; }
            tb = tm; gb = gm;
            side = -1;
        } else {
            if (side == 1) { const double m = 1.0 - gm / ga; gb *= m > 0.0 ? m : 0.5; }
            ta = tm; ga = gm;
            side = 1;
        }
    }
    return tb;
}

/* Sample times θ ∈ [0, 1] inside a step of size h, sorted: a uniform grid of nsub intervals, plus
 * for each guard the extremum of the cubic through g and ġ at both ends — so a guard that dips
 * below zero and comes back within one step (two crossings) is still seen. Returns their number. */
static int sample_times(double h, int ntr, int nsub, const double *g_old, const double *gd0,
                        const double *g_new, const double *gd1, double *th) {
    int ns = 0;
    for (int j = 0; j <= nsub; ++j) th[ns++] = (double)j / nsub;
    for (int k = 0; k < ntr; ++k) {
        double a0 = g_old[k], a1 = h * gd0[k], b0 = g_new[k], b1 = h * gd1[k];
        /* cubic c(θ) = a0 + a1 θ + c2 θ² + c3 θ³ matching values and slopes */
        double c2 = 3 * (b0 - a0) - 2 * a1 - b1, c3 = 2 * (a0 - b0) + a1 + b1;
        /* c'(θ) = a1 + 2 c2 θ + 3 c3 θ² has the Bernstein coefficients a1, a1 + c2, b1 on [0, 1]:
         * all of one sign, c is monotone in the step and has no extremum to sample (most steps) */
        const double m1 = a1 + c2;
        if ((a1 > 0.0 && m1 > 0.0 && b1 > 0.0) || (a1 < 0.0 && m1 < 0.0 && b1 < 0.0)) continue;
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
            if (r[q] > 0.0 && r[q] < 1.0 && ns < NSAMP_MAX) th[ns++] = r[q];
    }
    for (int a = 1; a < ns; ++a) /* insertion sort: a handful of values */
        for (int b = a; b > 0 && th[b - 1] > th[b]; --b) { double tmp = th[b]; th[b] = th[b - 1]; th[b - 1] = tmp; }
    return ns;
}

/* Guards at the inner sample times, on the Hermite interpolant (dense = 0) or the dense output. */
static void sample_guards(const Step *s, int mode, const double *p, double t, int ns, const double *th,
                          int dense, double gs[][NTR1]) {
    double xs[NXMAX];
    for (int j = 1; j < ns - 1; ++j) {
        if (dense) step_dense_eval(s, t + s->h * th[j], xs);
        else hermite_eval(s, th[j], xs);
        surfaces(mode, t + s->h * th[j], xs, p, gs[j]);
    }
}

/* Does any guard of the mode cross in its direction between two consecutive samples? */
static int any_crossing(int mode, int ns, double gs[][NTR1]) {
    for (int k = 0; k < n_surf(mode); ++k)
        for (int j = 0; j + 1 < ns; ++j)
            if (crosses(surf_dir(mode, k), gs[j][k], gs[j + 1][k])) return 1;
    return 0;
}

/* The earliest enabled crossing over the samples (dense output ready): returns its surface index
 * within the mode (or -1) and sets *t_ev, x_ev and *from (the surface's value before it). */
static int first_enabled_crossing(const Step *s, int mode, const double *p, double t, double t_new, int ns,
                                  const double *th, double gs[][NTR1], double *t_ev, double *x_ev,
                                  double *from, double t_min) {
    const int nsf = n_surf(mode);
    int ev_k = -1;
    for (int k = 0; k < nsf; ++k) {
        int dir = surf_dir(mode, k);
        for (int j = 0; j + 1 < ns; ++j) {
            double ta = t + s->h * th[j], tb = (j + 2 == ns) ? t_new : t + s->h * th[j + 1];
            if (ta >= *t_ev) break;
            if (tb <= ta || !crosses(dir, gs[j][k], gs[j + 1][k])) continue;
            double tr = locate(s, mode, k, dir, ta, gs[j][k], tb, gs[j + 1][k], p);
            if (tr >= *t_ev) break;
            double xr[NXMAX];
            if (tr >= t_new) { tr = t_new; for (int i = 0; i < s->n; ++i) xr[i] = s->y[i]; }
            else step_dense_eval(s, tr, xr);
            if (surf_enabled(mode, k, tr, xr, p, t_min)) {
                *t_ev = tr;
                ev_k = k;
                *from = gs[j][k];
                for (int i = 0; i < s->n; ++i) x_ev[i] = xr[i];
                break;
            }
        }
    }
    return ev_k;
}

/* Side a surface is on before it crosses in direction dir (0: the side of g0), as ±1. */
static double pre_side(int dir, double g0) { return dir < 0 ? 1.0 : dir > 0 ? -1.0 : (g0 >= 0.0 ? 1.0 : -1.0); }

/* θ ∈ (0, 1) of the extremum of surface k inside the step, where ġ (ġ0 at θ = 0, ġ1 at θ = 1, of
 * opposite signs) vanishes along the dense output: Illinois on ġ = ∇g · f(x(θ)). */
static double extremum_theta(const Step *s, int mode, int k, const double *p, double gd0, double gd1) {
    double xa[NXMAX], fa[NXMAX], gd[NTR1];
    double ta = 0.0, tb = 1.0, fa0 = gd0, fb0 = gd1;
    int side = 0;
    double tm = 0.5;
    for (int it = 0; it < 60 && tb - ta > 1e-12; ++it) {
        tm = (fa0 * tb - fb0 * ta) / (fa0 - fb0);
        if (!(tm > ta && tm < tb)) tm = 0.5 * (ta + tb);
        double t = s->t_old + s->h * tm;
        step_dense_eval(s, t, xa);
        if (rhs(mode, t, xa, p, fa)) break;
        surfaces_dot(mode, t, xa, fa, p, gd);
        if ((gd[k] < 0.0) == (fa0 < 0.0)) {
            ta = tm; fa0 = gd[k];
            if (side == 1) fb0 *= 0.5;
            side = 1;
        } else {
            tb = tm; fb0 = gd[k];
            if (side == -1) fa0 *= 0.5;
            side = -1;
        }
    }
    return tm;
}

/* Surfaces whose ġ turns inside the step while both ends are on their pre-crossing side: a dip
 * towards zero that the screening may miss or see by round-off. Its extremum on the dense output
 * decides: deeper than the integration tolerance (gtol, in g's units) it is a crossing and its
 * time becomes a sample; otherwise (a tangency, or no crossing) the surface has no event in this
 * step (skip[k] = 1). Returns the new number of samples. */
static int refine_dips(Step *s, int mode, const double *p, double gtol_abs, double gtol_rel, const double *g_old,
                       const double *gd_old, const double *g_new, const double *gd_new, int ns, double *th,
                       int *skip) {
    for (int k = 0; k < n_surf(mode); ++k) {
        double sd = pre_side(surf_dir(mode, k), g_old[k]);
        if (!(sd * g_old[k] > 0.0 && sd * g_new[k] > 0.0 && sd * gd_old[k] < 0.0 && sd * gd_new[k] > 0.0)) continue;
        double te = extremum_theta(s, mode, k, p, gd_old[k], gd_new[k]);
        double xe[NXMAX], ge[NTR1];
        step_dense_eval(s, s->t_old + s->h * te, xe);
        surfaces(mode, s->t_old + s->h * te, xe, p, ge);
        double tol = gtol_abs + gtol_rel * fmax(fabs(g_old[k]), fabs(g_new[k]));
        if (sd * ge[k] < -tol && ns < NSAMP_MAX) {
            int j = ns++;
            for (; j > 0 && th[j - 1] > te; --j) th[j] = th[j - 1];
            th[j] = te;
        } else {
            skip[k] = 1;
        }
    }
    return ns;
}

/* Event of the step just taken from (t, g_old, gd_old) to (t_new, g_new, gd_new: ġ at t_new):
 * sets *ev_k (guard index within the mode, or -1), *t_ev and x_ev. Returns 0 or
 * ST_SINGULAR_MASS (the dense output could not be built). */
static int find_event(Step *s, int mode, const double *p, int nsub, double t, double t_new,
                      const double *g_old, const double *gd_old, const double *g_new, const double *gd_new,
                      int *ev_k, double *t_ev, double *x_ev, double *from, double t_min,
                      double gtol_abs, double gtol_rel) {
    const int ntr = n_surf(mode);
    *ev_k = -1;
    *t_ev = INFINITY;
    if (ntr <= 0) return 0;
    double th[NSAMP_MAX];
    int ns = sample_times(s->h, ntr, nsub, g_old, gd_old, g_new, gd_new, th);
    double gs[NSAMP_MAX][NTR1];
    int skip[NTR1], dips = 0;
    for (int k = 0; k < ntr; ++k) {
        skip[k] = 0;
        double sd = pre_side(surf_dir(mode, k), g_old[k]);
        dips |= sd * g_old[k] > 0.0 && sd * g_new[k] > 0.0 && sd * gd_old[k] < 0.0 && sd * gd_new[k] > 0.0;
    }
    for (int k = 0; k < ntr; ++k) { gs[0][k] = g_old[k]; gs[ns - 1][k] = g_new[k]; }
    sample_guards(s, mode, p, t, ns, th, 0, gs);
    if (!any_crossing(mode, ns, gs) && !dips) return 0;
    if (step_dense_prepare(s, mode, p)) return ST_SINGULAR_MASS;
    if (dips) {
        int ns0 = ns;
        ns = refine_dips(s, mode, p, gtol_abs, gtol_rel, g_old, gd_old, g_new, gd_new, ns, th, skip);
        for (int k = 0; k < ntr; ++k) gs[ns - 1][k] = g_new[k];
        if (ns == ns0 && !any_crossing(mode, ns, gs)) return 0;
    }
    sample_guards(s, mode, p, t, ns, th, 1, gs);
    for (int k = 0; k < ntr; ++k)
        if (skip[k]) for (int j = 0; j < ns; ++j) gs[j][k] = g_old[k]; /* no event of surface k here */
    *ev_k = first_enabled_crossing(s, mode, p, t, t_new, ns, th, gs, t_ev, x_ev, from, t_min);
    return 0;
}

#endif
