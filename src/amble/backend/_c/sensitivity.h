/* Forward sensitivities of a hybrid run: S = ∂x(t)/∂(x0, p), carried through flows and events.
 *
 * Flow: each accepted step is taken again for the pair (x, S) with the same stages of the
 * method's explicit tableau (its stepper's, stepper.h; a method without one has none),
 *   K_S = J_x S + J_p, J = ∂f/∂(x, p) from rhs_jac at every stage state,
 * so S is the derivative of the discrete flow over the accepted step sizes (the step sizes are
 * chosen on x alone). A step cut at an event is taken again up to just before it (a switching
 * surface's far side must not enter the stages) and bridged by one Euler step of the linear
 * system, whose error is second order in the tiny bridge.
 * Events (guard g, reset Δ): the event time τ moves with the initial data,
 *   dτ = −(∇ₓg · S + ∂g/∂p) / ġ⁻,
 * and the sensitivity just after it is (the saltation matrix applied to S)
 *   S⁺ = DΔ (S + f⁻ dτ) + ∂Δ/∂t dτ + ∂Δ/∂p − f⁺ dτ.
 * A switching surface is an event with Δ = identity; a terminal transition leaves S at its
 * pre-event value (f⁺ = f⁻) and records dτ.
 *
 * Buffer (caller-owned, persists across calls): S as NXMAX rows of SC = NXMAX + NPARAM columns
 * (state columns 0 … nx0−1, parameter j at NXMAX + j), then one row dτ of the last transition,
 * then the numbers of state and parameter columns carried; its offsets SENS_S, SENS_TAU,
 * SENS_NCS, SENS_NCP and SENS_SIZE come from the table in amble/backend/abi.py.
 * Needs from the including unit: stepper.h, events.h, rhs_jac, surfaces_grad, reset_jac.
 */
#ifndef AMBLE_SENSITIVITY_H
#define AMBLE_SENSITIVITY_H


/* The columns a run carries: 0 … ncs−1 (initial state), NXMAX … NXMAX+ncp−1 (parameters). */
typedef struct { int ncs, ncp; } Cols;

static Cols sens_cols(const double *sens) { Cols c = {(int)sens[SENS_NCS], (int)sens[SENS_NCP]}; return c; }

#define FOR_COLS(cl, c, body) \
    do { for (int c = 0; c < (cl).ncs; ++c) { body } for (int c = NXMAX; c < NXMAX + (cl).ncp; ++c) { body } } while (0)

/* J = ∂f/∂(x, p) at a state: state columns always, parameter columns if carried. */
static int sens_jac(int mode, double t, const double *x, const double *p, Cols cl, double *dx, double *J) {
    if (rhs_jac(mode, t, x, p, dx, J)) return ST_SINGULAR_MASS;
    if (cl.ncp > 0 && rhs_jacp(mode, t, x, p, J)) return ST_SINGULAR_MASS;
    return 0;
}

/* KS = J_x S + J_p over the carried columns (J_x is sparse: its position rows are unit rows). */
static void jac_times(int n, Cols cl, const double *J, const double *S, double *KS) {
    for (int i = 0; i < n; ++i) {
        double *out = KS + i * SC;
        FOR_COLS(cl, c, out[c] = c >= NXMAX ? J[i * SC + c] : 0.0;);
        for (int k = 0; k < n; ++k) {
            const double a = J[i * SC + k];
            if (a == 0.0) continue;
            const double *row = S + k * SC;
            FOR_COLS(cl, c, out[c] += a * row[c];);
        }
    }
}

/* The carried columns of S (rows of SC) packed as n rows of nc = ncs + ncp contiguous columns,
 * and back: the stage sums of a step then run over one contiguous array, which the compiler
 * vectorises (the layout of the buffer, with its gap between state and parameter columns, it
 * cannot). */
static void sens_pack(int n, Cols cl, const double *S, double *P) {
    const int nc = cl.ncs + cl.ncp;
    for (int i = 0; i < n; ++i) {
        for (int c = 0; c < cl.ncs; ++c) P[i * nc + c] = S[i * SC + c];
        for (int c = 0; c < cl.ncp; ++c) P[i * nc + cl.ncs + c] = S[i * SC + NXMAX + c];
    }
}

static void sens_unpack(int n, Cols cl, const double *P, double *S) {
    const int nc = cl.ncs + cl.ncp;
    for (int i = 0; i < n; ++i) {
        for (int c = 0; c < cl.ncs; ++c) S[i * SC + c] = P[i * nc + c];
        for (int c = 0; c < cl.ncp; ++c) S[i * SC + NXMAX + c] = P[i * nc + cl.ncs + c];
    }
}

/* jac_times on packed columns: KS = J_x S + J_p, S and KS n × nc. */
static void jac_times_packed(int n, Cols cl, const double *J, const double *S, double *KS) {
    const int nc = cl.ncs + cl.ncp;
    for (int i = 0; i < n; ++i) {
        double *out = KS + i * nc;
        const double *Ji = J + i * SC;
        for (int c = 0; c < cl.ncs; ++c) out[c] = 0.0;
        for (int c = 0; c < cl.ncp; ++c) out[cl.ncs + c] = Ji[NXMAX + c];
        for (int k = 0; k < n; ++k) {
            const double a = Ji[k];
            if (a == 0.0) continue;
            const double *row = S + k * nc;
            for (int c = 0; c < nc; ++c) out[c] += a * row[c];
        }
    }
}

/* out = base + h Σ_{j<m} a_j K_j over w entries, the terms in the order of j (zeros of the
 * tableau skipped: half of DOP853's are zero). */
static void stage_sum(int w, int m, const double *a, double h, const double *base, const double *K, int ldk,
                      double *out) {
    double acc[w];
    for (int e = 0; e < w; ++e) acc[e] = 0.0;
    for (int j = 0; j < m; ++j) {
        const double aj = a[j];
        if (aj == 0.0) continue;
        const double *Kj = K + j * ldk;
        for (int e = 0; e < w; ++e) acc[e] += aj * Kj[e];
    }
    for (int e = 0; e < w; ++e) out[e] = base[e] + h * acc[e];
}

/* One step of (y, S) on tableau tb from (t0, y0, S) over h; S is overwritten, y1 gets the state. */
static int sens_advance(const Tableau *tb, int mode, const double *p, Cols cl, double t0, double h, const double *y0,
                        double *S, double *y1) {
    const int n = MODE_NX[mode], ns = tb->stages, w = n * (cl.ncs + cl.ncp);
    double K[ns][NXMAX], KS[ns][w], J[NXMAX * SC];
    double ytmp[NXMAX], S0[w], Stmp[w];
    sens_pack(n, cl, S, S0);
    for (int st = 0; st < ns; ++st) {
        const double *a = tb->a + st * tb->stride;
        stage_sum(n, st, a, h, y0, &K[0][0], NXMAX, ytmp);
        stage_sum(w, st, a, h, S0, &KS[0][0], w, Stmp);
        int err = sens_jac(mode, t0 + tb->c[st] * h, ytmp, p, cl, K[st], J);
        if (err) return err;
        jac_times_packed(n, cl, J, Stmp, KS[st]);
    }
    stage_sum(n, ns, tb->b, h, y0, &K[0][0], NXMAX, y1);
    stage_sum(w, ns, tb->b, h, S0, &KS[0][0], w, Stmp);
    sens_unpack(n, cl, Stmp, S);
    return 0;
}

/* S carried from the start of the current step (t0, y0) to an event at t_ev inside it. Sets
 * fm to the flow just before the event (at the dense-output state x_ev; for a switching surface
 * extrapolated from its near side). */
static int sens_to_event(const Step *s, int mode, const double *p, double t0, const double *y0, double t_ev,
                         const double *x_ev, int is_switch, double *sens, double *fm) {
    const Cols cl = sens_cols(sens);
    double *S = sens + SENS_S;
    const int n = MODE_NX[mode];
    const double span = t_ev - t0;
    double delta = fmax(1e-6 * span, 1e-9 * fmax(1.0, fabs(t_ev)));
    if (delta > 0.5 * span) delta = 0.5 * span;
    double ya[NXMAX], J[NXMAX * SC], KS[NXMAX * SC], fa[NXMAX];
    int st = 0;
    if (span - delta > 0.0 && (st = sens_advance(s->m->tableau, mode, p, cl, t0, span - delta, y0, S, ya))) return st;
    if (!(span - delta > 0.0)) for (int i = 0; i < n; ++i) ya[i] = y0[i];
    /* the bridge over the last δ: S += δ (J_x S + J_p) at the near-side state */
    if ((st = sens_jac(mode, t_ev - delta, ya, p, cl, fa, J))) return st;
    jac_times(n, cl, J, S, KS);
    for (int i = 0; i < n; ++i) FOR_COLS(cl, c, S[i * SC + c] += delta * KS[i * SC + c];);
    if (!is_switch) {
        if (rhs(mode, t_ev, x_ev, p, fm)) return ST_SINGULAR_MASS;
        return 0;
    }
    /* the near-side branch of a jumping right-hand side: f(x(t_ev − δ)) and f(x(t_ev − 2δ)) on the
     * dense output, extrapolated linearly to t_ev (error second order in δ) */
    double xb[NXMAX], f1[NXMAX], f2[NXMAX];
    step_dense_eval(s, t_ev - delta, xb);
    if (rhs(mode, t_ev - delta, xb, p, f1)) return ST_SINGULAR_MASS;
    step_dense_eval(s, t_ev - 2.0 * delta, xb);
    if (rhs(mode, t_ev - 2.0 * delta, xb, p, f2)) return ST_SINGULAR_MASS;
    for (int i = 0; i < n; ++i) fm[i] = 2.0 * f1[i] - f2[i];
    return 0;
}

/* Apply an event to S (see the header). k: surface index within the source mode; tr: transition
 * index, or −1 for a switching surface (Δ = identity); fp: the flow just after (target mode);
 * terminal: keep S (f⁺ = f⁻). Writes dτ into the buffer's τ row unless it is a switch. */
static int sens_jump(int mode, int k, int tr, int target, double t_ev, const double *x_ev, const double *p,
                     const double *fm, const double *fp, int terminal, double *sens) {
    const int n = MODE_NX[mode], nd = MODE_NX[target];
    const Cols cl = sens_cols(sens);
    double G[NTR1 * SC], gd[NTR1], dtau[SC];
    surfaces_grad(mode, t_ev, x_ev, p, G);
    surfaces_dot(mode, t_ev, x_ev, fm, p, gd);
    double *S = sens + SENS_S;
    const double *g = G + k * SC;
    if (!(fabs(gd[k]) > 0.0)) { /* grazing: the event time does not depend smoothly on the data */
        for (int e = 0; e < SENS_NCS; ++e) sens[e] = NAN;
        return 0;
    }
    FOR_COLS(cl, c, {
        double acc = c >= NXMAX ? g[c] : 0.0;
        for (int i = 0; i < n; ++i) acc += g[i] * S[i * SC + c];
        dtau[c] = -acc / gd[k];
    });
    if (tr >= 0) FOR_COLS(cl, c, sens[SENS_TAU + c] = dtau[c];);
    if (terminal) return 0;
    double Y[NXMAX * SC], Sn[NXMAX * SC];
    for (int i = 0; i < n; ++i) FOR_COLS(cl, c, Y[i * SC + c] = S[i * SC + c] + fm[i] * dtau[c];);
    if (tr < 0) {
        for (int i = 0; i < n; ++i) FOR_COLS(cl, c, Sn[i * SC + c] = Y[i * SC + c] - fp[i] * dtau[c];);
    } else {
        double D[NXMAX * (SC + 1)];
        int err = reset_jac(tr, t_ev, x_ev, p, D);
        if (err) return ST_RESET_FAILED;
        for (int a = 0; a < nd; ++a) {
            const double *Da = D + a * (SC + 1);
            FOR_COLS(cl, c, {
                double acc = Da[SC] * dtau[c] - fp[a] * dtau[c] + (c >= NXMAX ? Da[c] : 0.0);
                for (int i = 0; i < n; ++i) acc += Da[i] * Y[i * SC + c];
                Sn[a * SC + c] = acc;
            });
        }
    }
    for (int a = 0; a < nd; ++a) FOR_COLS(cl, c, S[a * SC + c] = Sn[a * SC + c];);
    return 0;
}

#endif
