/* A state on a switching surface, or within the rounding of the state from it: which side the
 * flow goes into (Filippov's choice: the flows of both sides just off the surface, and where one
 * is tangent to it the way it curves), whether the flow presses into it from both sides
 * (sliding, which ends the run), and the moves across it by units of rounding that a crossing
 * the arithmetic cannot reach, or one located exactly on g = 0, needs.
 *
 * Needs from the including unit: events.h (surfaces, surfaces_dot, n_surf, NTR1), DBL_EPSILON,
 * DBL_MIN, MODE_NTR, NXMAX and rhs.
 */
#ifndef AMBLE_SWITCH_SIDE_H
#define AMBLE_SWITCH_SIDE_H

/* ġ of switching surface k a moment later along the flow of one side (sd: its sign of g, ±1) from
 * xs on that side, where ġ vanishes (the flow is tangent to the surface: a force that vanishes at
 * a switch, a pendulum at rest on it): its sign is that of g̈, which decides whether that side's
 * flow curves into the surface or away from it. The moment is shortened while the state would
 * leave the side (0 if it still does, or the right-hand side fails). */
static double later_rate(int mode, int k, double t, const double *xs, const double *fs, const double *p, int n,
                         double sd) {
    double x1[NXMAX], f1[NXMAX], g1[NTR1];
    double dt = 1.5e-8 * fmax(1.0, fabs(t));
    for (int it = 0; it < 6; ++it, dt *= 1e-2) {
        for (int i = 0; i < n; ++i) x1[i] = xs[i] + dt * fs[i];
        surfaces(mode, t + dt, x1, p, g1);
        if (!(sd * g1[k] > 0.0)) continue;
        if (rhs(mode, t + dt, x1, p, f1)) return 0.0;
        surfaces_dot(mode, t + dt, x1, f1, p, g1);
        return g1[k];
    }
    return 0.0;
}

/* The flow of one side of switching surface k (side: 0 for g < 0, 1 for g > 0) at x moved off it
 * by d along coordinate ib (sgn: the sign of ∂g/∂x_ib): the state xs, the field fs there, and ġ.
 * *tangent: ġ is zero up to the rounding of ∇g · f (grad: ∂g/∂xᵢ); *rest: the field also
 * vanishes as d does (twice the distance, more than 1.5 times the field, or none at all), the
 * point an equilibrium of that side's flow. Returns ġ, or NAN if the right-hand side fails. */
static double side_flow(int mode, int k, double t, const double *x, const double *p, int n, int ib, double sgn,
                        double d, int side, const double *grad, double *xs, double *fs, int *tangent, int *rest) {
    double gs[NTR1], x2[NXMAX], f2[NXMAX], round = 0.0, fmax1 = 0.0, fmax2 = 0.0;
    for (int j = 0; j < n; ++j) xs[j] = x2[j] = x[j];
    xs[ib] += (side ? 1.0 : -1.0) * sgn * d;
    if (rhs(mode, t, xs, p, fs)) return NAN;
    surfaces_dot(mode, t, xs, fs, p, gs);
    for (int j = 0; j < n; ++j) round += 4.0 * DBL_EPSILON * fabs(grad[j] * fs[j]);
    *tangent = fabs(gs[k]) <= round;
    *rest = 0;
    if (*tangent) {
        x2[ib] += (side ? 2.0 : -2.0) * sgn * d;
        if (rhs(mode, t, x2, p, f2)) return NAN;
        for (int j = 0; j < n; ++j) { fmax1 = fmax(fmax1, fabs(fs[j])); fmax2 = fmax(fmax2, fabs(f2[j])); }
        *rest = fmax2 > 1.5 * fmax1 || fmax2 == 0.0;
    }
    return gs[k];
}

/* ġ of switching surface k on both sides of it, at x moved off the surface along the coordinate
 * g depends on most (by a relative 1e-9, or twice the gap |g| to it): rate[0] on the g < 0 side,
 * rate[1] on the g > 0 side. Where the flow of a side is tangent to the surface there (side_flow)
 * its rate is ġ a moment later along it (later_rate: the sign of g̈) — unless both sides' flows
 * are at rest at the point (a pendulum hanging at rest on a switch with no force to either side
 * of it, or on one whose crossing leaves the force as it is, as θ̇ = 0 of a friction of size 0):
 * the state is an equilibrium, the rates stay 0, and the run stays there without a decision.
 * Returns 0, or −1 if g does not depend on the state here. */
static int side_rates(int mode, int k, double t, const double *x, const double *p, int n, double *rate,
                      double gap) {
    double e[NXMAX], gd[NTR1], grad[NXMAX], best = 0.0, sgn = 1.0;
    double xs[2][NXMAX], fs[2][NXMAX];
    int ib = -1, tangent[2], rest[2];
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) e[j] = i == j ? 1.0 : 0.0;
        surfaces_dot(mode, t, x, e, p, gd);
        grad[i] = gd[k];
        if (fabs(gd[k]) > best) { best = fabs(gd[k]); ib = i; sgn = gd[k] > 0 ? 1.0 : -1.0; }
    }
    if (ib < 0) return -1;
    const double d = fmax(1e-9 * fmax(1.0, fabs(x[ib])), 2.0 * gap / best); /* past the surface */
    for (int side = 0; side < 2; ++side) {
        rate[side] = side_flow(mode, k, t, x, p, n, ib, sgn, d, side, grad, xs[side], fs[side], &tangent[side],
                               &rest[side]);
        if (isnan(rate[side])) { rate[side] = 0.0; tangent[side] = 0; rest[side] = 1; }
    }
    if (rest[0] && rest[1]) return 0;
    for (int side = 0; side < 2; ++side)
        if (tangent[side]) rate[side] = later_rate(mode, k, t, xs[side], fs[side], p, n, side ? 1.0 : -1.0);
    return 0;
}

/* A switching surface exactly zero where integration starts: the right-hand side there is one
 * of its branches, so ġ at the point says nothing. If the flows on both sides (side_rates) point
 * into the surface it is sliding (returns the surface index); otherwise the surface is placed on
 * the side the flow leaves, so that the crossing is located at once. Returns −1.
 * `fired`: a surface just crossed (its sliding test was made at the crossing). */
static int resolve_zero_switches(int mode, double t, const double *x, const double *p, double *g, int n,
                                 int fired) {
    for (int k = MODE_NTR[mode]; k < n_surf(mode); ++k) {
        if (g[k] != 0.0 || k == fired) continue;
        double rate[2];
        if (side_rates(mode, k, t, x, p, n, rate, 0.0)) continue;
        if (rate[1] < 0.0 && rate[0] > 0.0) return k;
        if (rate[1] > 0.0 && rate[0] >= 0.0) g[k] = -DBL_MIN;      /* leaves towards g > 0 */
        else if (rate[1] <= 0.0 && rate[0] < 0.0) g[k] = DBL_MIN;  /* leaves towards g < 0 */
    }
    return -1;
}

/* After crossing switching surface k (from the side of sign `from`) to x: does the flow there
 * point back into it (sliding)? At g = 0 exactly the flows of both sides decide. */
static int slides_after_crossing(int mode, int k, double t, const double *x, const double *p, int n,
                                 double g, double gd, double from) {
    if (g != 0.0) return gd * from > 0.0;
    double rate[2];
    if (side_rates(mode, k, t, x, p, n, rate, 0.0)) return 0;
    return rate[1] < 0.0 && rate[0] > 0.0;
}

/* A step near a sliding surface straddles it with stages on both sides and ends on the side it
 * started, so its crossing is never seen and the steps shrink to the gap. After each step: a
 * switching surface the flow approaches, within gap_max, with steps shrunk so far that the next
 * one would not clearly cross it (|g| ≥ |ġ| h / 10; a clean crossing is left to event location)
 * is tested with the flows on both sides; if both point into it the run slides there (returns
 * its index). */
static int approaching_slide(int mode, double t, const double *x, const double *p, int n, const double *g,
                             const double *gd, double h, double gap_max) {
    for (int k = MODE_NTR[mode]; k < n_surf(mode); ++k) {
        if (!(g[k] * gd[k] < 0.0) || fabs(g[k]) < 0.1 * fabs(gd[k]) * h || fabs(g[k]) > gap_max) continue;
        double rate[2];
        if (side_rates(mode, k, t, x, p, n, rate, fabs(g[k]))) continue;
        if (rate[1] < 0.0 && rate[0] > 0.0) return k;
    }
    return -1;
}

/* x moved by the fewest units of rounding of its coordinate ib, in direction dir (±INFINITY),
 * until surface k has the sign sgn (±1) strictly; returns 0, or −1 if 64 units do not do it. */
static int nudge_across(int mode, int k, double t, const double *x, const double *p, int n, int ib, double dir,
                        double sgn, double *x_out) {
    double gs[NTR1];
    for (int j = 0; j < n; ++j) x_out[j] = x[j];
    for (int it = 0; it < 64; ++it) {
        x_out[ib] = nextafter(x_out[ib], dir);
        surfaces(mode, t, x_out, p, gs);
        if (gs[k] * sgn > 0.0) return 0;
    }
    return -1;
}

/* The coordinate whose unit of rounding moves surface k most (returns it, or −1 if k depends on
 * no coordinate), the direction that moves g towards sign sgn, and 4 ε Σᵢ |∂g/∂xᵢ| |xᵢ|. */
static int steepest_unit(int mode, int k, double t, const double *x, const double *p, int n, double sgn,
                         double *dir, double *res) {
    double e[NXMAX], g0[NTR1], gi[NTR1], best = 0.0;
    int ib = -1;
    *res = 0.0;
    for (int j = 0; j < n; ++j) e[j] = 0.0;
    surfaces_dot(mode, t, x, e, p, g0); /* ∂g/∂t, taken out of each directional derivative */
    for (int i = 0; i < n; ++i) {
        e[i] = 1.0;
        surfaces_dot(mode, t, x, e, p, gi);
        e[i] = 0.0;
        const double dg = gi[k] - g0[k], unit = fabs(nextafter(x[i], INFINITY) - x[i]);
        *res += 4.0 * DBL_EPSILON * fabs(dg * x[i]);
        if (fabs(dg) * unit > best) { best = fabs(dg) * unit; ib = i; *dir = (sgn > 0.0) == (dg > 0.0) ? INFINITY : -INFINITY; }
    }
    return ib;
}

/* A switching surface the arithmetic cannot reach. Approached (g ġ < 0) to within the rounding
 * of the state, |g| ≤ 4 ε Σᵢ |∂g/∂xᵢ| |xᵢ|, it is no longer crossed by a step: a step long
 * enough to move the state by one unit of rounding rounds some of its stages onto the far side,
 * the jump of the right-hand side there fails the error test, and the steps accepted are those
 * too short to move the state at all, so g keeps its value exactly (g_new == g_old) — until ġ
 * has grown enough for a rounding to fall the other way. Near a point where ġ vanishes on the
 * surface (a kink θ = d met with θ̇ → 0, as in a Zeno accumulation at the intersection of the
 * surfaces θ = d and θ̇ = 0) that takes thousands of steps of 1e-10 s at every approach, far
 * more than the accumulation itself: its crossings then drift apart beyond zeno_dt, the Zeno
 * test never fires, and the step budget runs out. Such a step (g unchanged, approaching, within
 * the rounding) is taken as reaching the surface: x_ev is x moved across it by the fewest units
 * of rounding of the coordinate that moves g most — a change of the state of the size of one
 * step's rounding error. Returns the surface index (x_ev strictly on the far side), or −1. */
static int stuck_at_switch(int mode, double t, const double *x, const double *p, int n, const double *g_old,
                           const double *g, const double *gd, double *x_ev) {
    for (int k = MODE_NTR[mode]; k < n_surf(mode); ++k) {
        if (!(g[k] == g_old[k] && g[k] * gd[k] < 0.0 && fabs(g[k]) > DBL_MIN)) continue;
        const double sgn = g[k] > 0.0 ? -1.0 : 1.0;
        double dir = 0.0, res;
        const int ib = steepest_unit(mode, k, t, x, p, n, sgn, &dir, &res);
        if (ib >= 0 && fabs(g[k]) <= res && nudge_across(mode, k, t, x, p, n, ib, dir, sgn, x_ev) == 0) return k;
    }
    return -1;
}

/* A switching surface crossed onto g = 0 exactly: the right-hand side there may be the branch of
 * the side just left (Piecewise((a, g > 0), (b, True)) crossed upwards is b at g = 0), and the
 * restarted step would mix both. The state is moved strictly onto the far side (nudge_across);
 * `from`: the surface's value before the crossing. */
static void onto_far_side(int mode, int k, double t, double *x, const double *p, int n, double from) {
    double g[NTR1], x1[NXMAX], dir = 0.0, res;
    surfaces(mode, t, x, p, g);
    if (g[k] != 0.0 || from == 0.0) return;
    const double sgn = from > 0.0 ? -1.0 : 1.0;
    const int ib = steepest_unit(mode, k, t, x, p, n, sgn, &dir, &res);
    if (ib >= 0 && nudge_across(mode, k, t, x, p, n, ib, dir, sgn, x1) == 0)
        for (int j = 0; j < n; ++j) x[j] = x1[j];
}

#endif
