/* Many walks in one call: the loop of basin maps and sweeps, with its convergence checks, in C.
 *
 * Called from Python one walk at a time, each walk of a basin cell costs some 15 us of Python
 * (array set-up, the ctypes call, the outcome) holding the GIL, which caps two threads at about
 * 1.2x one. Here a whole block of initial states runs in one call — ctypes releases the GIL for
 * it — so threads (or Dask workers) scale with the cores.
 *
 * Included at the end of hybrid.c (it calls amble_simulate); needs the CX_, OP_, IO_ and ST_
 * codes and NXMAX.
 */
#ifndef AMBLE_BATCH_H
#define AMBLE_BATCH_H

/* A fresh run context at t = 0 in `mode` from state x (the layout of engine.run in Python). */
static void batch_ctx(double *ctx, int mode, const double *x) {
    for (int i = 0; i < CX_X + NXMAX; ++i) ctx[i] = 0.0;
    ctx[CX_MODE] = mode;
    ctx[CX_TPREV_EVENT] = -INFINITY;
    ctx[CX_FRESH] = 1.0;
    for (int i = 0; i < MODE_NX[mode]; ++i) ctx[CX_X + i] = x[i];
}

/* Walk each of the n initial states x0[r * NXMAX ...] (mode `mode`, time 0) for up to `steps`
 * footfalls, in runs of `check_every` footfalls each started afresh from the previous run's
 * final state; after each run the walk stops if max_i |x_i - xref_i| < tol. opt and iopt are the
 * option layouts of the runs (end time, tolerances, caps; capacities are ignored: nothing is
 * recorded). The parameters of walk r are p[r * p_stride ...]: p_stride 0 shares one vector, NPARAM
 * gives each walk its own (a terrain drawn per walk and step). Per walk: the status of its last run (ST_STEPS_DONE if all runs completed), the
 * index of the transition that ended it (or -1), the footfalls taken, the last distance (NaN if
 * no run completed) and the final state (NaN-padded to NXMAX).
 *
 * next: NULL (walk rows 0 … n-1 in order), or a counter shared by several threads calling this
 * on the same rows at once: each takes the next unwalked row with an atomic increment, so the
 * threads share the walks one by one, however unequal their lengths (a walk that falls at once
 * and one that walks all its steps differ a hundredfold; blocks fixed in advance leave one
 * thread working alone at the end). Each row is written by the one thread that took it. */
void amble_walk_batch(int64_t n, int64_t *next, int mode, const double *x0, const double *p, int64_t p_stride,
                      const double *opt, const int64_t *iopt_in, const double *xref, int64_t steps,
                      int64_t check_every, double tol, int *code, int *info, int64_t *done_steps, double *dist,
                      double *x_out) {
    int64_t iopt[IOPT_LEN]; /* every field: the run reads them all (IO_METHOD picks the integrator) */
    for (int i = 0; i < IOPT_LEN; ++i) iopt[i] = iopt_in[i];
    iopt[IO_OUTCAP] = iopt[IO_EVCAP] = 0;
    iopt[IO_YIELDN] = 0; /* no pauses for Python's signal handling inside a block */
    if (check_every < 1) check_every = 1;
    const int nx = MODE_NX[mode];
    double ctx[CX_X + NXMAX];
    int64_t zero = 0, own = 0;
    for (;;) {
        const int64_t r = next ? __atomic_fetch_add(next, 1, __ATOMIC_RELAXED) : own++;
        if (r >= n) break;
        double x[NXMAX];
        for (int i = 0; i < NXMAX; ++i) x[i] = i < nx ? x0[r * NXMAX + i] : NAN;
        int64_t walked = 0;
        int st = ST_STEPS_DONE, tr = -1;
        double d = NAN;
        while (walked < steps) {
            int64_t m = steps - walked < check_every ? steps - walked : check_every;
            batch_ctx(ctx, mode, x);
            iopt[IO_MAXSTEPS] = m;
            st = amble_simulate(p + r * p_stride, ctx, opt, iopt, NULL, NULL, NULL, &zero, NULL, NULL, NULL, NULL,
                                &zero, NULL);
            int end = (int)ctx[CX_MODE];
            for (int i = 0; i < NXMAX; ++i) x[i] = i < MODE_NX[end] ? ctx[CX_X + i] : NAN;
            if (st != ST_STEPS_DONE) {
                walked += (int64_t)ctx[CX_STEPS];
                tr = (st == ST_TERMINAL || st == ST_RESET_FAILED || st == ST_SLIDING) ? (int)ctx[CX_INFO] : -1;
                break;
            }
            walked += m;
            d = 0.0;
            for (int i = 0; i < nx; ++i) {
                double e = fabs(x[i] - xref[i]);
                if (isnan(e)) { d = NAN; break; } /* as NumPy's max: NaN if any entry is */
                if (e > d) d = e;
            }
            if (d < tol) break;
        }
        code[r] = st;
        info[r] = tr;
        done_steps[r] = walked;
        dist[r] = d;
        for (int i = 0; i < NXMAX; ++i) x_out[r * NXMAX + i] = x[i];
    }
}

/* ---- many states put on a post-impact section per call (the cells of a basin map) ---- */

/* Max-abs residual of the section equations at a pre-impact state y: g_row(y) = 0 and
 * Δ(y)[S] = x[S]; r gets the residual vector. Returns INFINITY if the reset fails. */
static double section_residual(int mode, int tr, int row, double t, const double *y, const double *p,
                               const int64_t *S, int ns, const double *x, double *r, double *post) {
    double g[NTR1];
    int target = -1;
    guards(mode, t, y, p, g);
    if (reset(tr, t, y, p, post, &target)) return INFINITY;
    r[0] = g[row];
    double res = fabs(r[0]);
    for (int k = 0; k < ns; ++k) {
        r[1 + k] = post[S[k]] - x[S[k]];
        if (!(fabs(r[1 + k]) <= res)) res = isnan(r[1 + k]) ? NAN : fabs(r[1 + k]);
    }
    return isnan(res) ? INFINITY : res;
}

/* For each of the n states x[c * NXMAX ...] (of the section's target mode): the state of the
 * section (transition tr from `mode`, guard row `row` of that mode, time t) whose coordinates S
 * equal x[S], by the Newton iteration of Section.project in amble/analysis/section.py, from the
 * reference pre-impact state `pre`: minimum-norm steps dy = Jᵀ (J Jᵀ)⁻¹ (−r) with
 * J = [∇g_row; DΔ[S, :]], each halved until the residual decreases, until the residual is below
 * goal = tol · max(1, max |x[S]|) (or, stalled, below 1e3 · goal). ok[c] = 1 and y_out[c] the
 * post-impact state on success; ok[c] = 0 where this iteration cannot decide (a reset that fails,
 * J Jᵀ singular — a reset collapsing directions —, no convergence): the caller decides those cells
 * with the full iteration (its least-squares steps and its errors). next: as for amble_walk_batch. */
void amble_project_batch(int64_t n, int64_t *next, int mode, int tr, int row, double t, const double *pre,
                         const int64_t *S, int ns, const double *x, const double *p, double tol, int max_iter,
                         double *y_out, int *ok) {
    AMBLE_PARAMS(p); /* the kernels below read the hoisted values too (amble_walk_batch gets them from amble_simulate) */
    const int nv = MODE_NX[mode], m = 1 + ns;
    int64_t own = 0;
    for (;;) {
        const int64_t c = next ? __atomic_fetch_add(next, 1, __ATOMIC_RELAXED) : own++;
        if (c >= n) break;
        const double *xc = x + c * NXMAX;
        double y[NXMAX], post[NXMAX], r[NXMAX + 1], rt[NXMAX + 1], trial[NXMAX], tpost[NXMAX];
        for (int i = 0; i < nv; ++i) y[i] = pre[i];
        double scale = 1.0;
        for (int k = 0; k < ns; ++k) if (fabs(xc[S[k]]) > scale) scale = fabs(xc[S[k]]);
        const double goal = tol * scale;
        double res = section_residual(mode, tr, row, t, y, p, S, ns, xc, r, post);
        int done = 0, fail = !isfinite(res);
        for (int it = 0; it < max_iter && !done && !fail; ++it) {
            if (res < goal) { done = 1; break; }
            double G[NTR1 * SC], D[NXMAX * (SC + 1)], J[(NXMAX + 1) * NXMAX], A[(NXMAX + 1) * (NXMAX + 2)];
            surfaces_grad(mode, t, y, p, G);
            if (reset_jac(tr, t, y, p, D)) { fail = 1; break; }
            for (int i = 0; i < nv; ++i) J[i] = G[row * SC + i];
            for (int k = 0; k < ns; ++k)
                for (int i = 0; i < nv; ++i) J[(1 + k) * nv + i] = D[S[k] * (SC + 1) + i];
            /* J Jᵀ z = −r (m × m, augmented), Gaussian elimination with partial pivoting */
            double amax = 0.0;
            for (int a = 0; a < m; ++a) {
                for (int b = 0; b < m; ++b) {
                    double acc = 0.0;
                    for (int i = 0; i < nv; ++i) acc += J[a * nv + i] * J[b * nv + i];
                    A[a * (m + 1) + b] = acc;
                    if (fabs(acc) > amax) amax = fabs(acc);
                }
                A[a * (m + 1) + m] = -r[a];
            }
            for (int col = 0; col < m && !fail; ++col) {
                int piv = col;
                for (int a = col + 1; a < m; ++a) if (fabs(A[a * (m + 1) + col]) > fabs(A[piv * (m + 1) + col])) piv = a;
                if (!(fabs(A[piv * (m + 1) + col]) > 1e-12 * amax)) { fail = 1; break; } /* rank-deficient: leave it */
                if (piv != col)
                    for (int b = 0; b <= m; ++b) { double tmp = A[col * (m + 1) + b]; A[col * (m + 1) + b] = A[piv * (m + 1) + b]; A[piv * (m + 1) + b] = tmp; }
                for (int a = col + 1; a < m; ++a) {
                    const double f = A[a * (m + 1) + col] / A[col * (m + 1) + col];
                    for (int b = col; b <= m; ++b) A[a * (m + 1) + b] -= f * A[col * (m + 1) + b];
                }
            }
            if (fail) break;
            double z[NXMAX + 1], dy[NXMAX];
            for (int a = m - 1; a >= 0; --a) {
                double acc = A[a * (m + 1) + m];
                for (int b = a + 1; b < m; ++b) acc -= A[a * (m + 1) + b] * z[b];
                z[a] = acc / A[a * (m + 1) + a];
            }
            for (int i = 0; i < nv; ++i) {
                double acc = 0.0;
                for (int a = 0; a < m; ++a) acc += J[a * nv + i] * z[a];
                dy[i] = acc;
            }
            double lam = 1.0, rest = INFINITY;
            while (lam > 1e-4) {
                for (int i = 0; i < nv; ++i) trial[i] = y[i] + lam * dy[i];
                rest = section_residual(mode, tr, row, t, trial, p, S, ns, xc, rt, tpost);
                if (rest < res) break;
                lam *= 0.5;
            }
            if (!(lam > 1e-4)) break; /* no decrease along the step: stalled */
            for (int i = 0; i < nv; ++i) y[i] = trial[i];
            for (int a = 0; a < m; ++a) r[a] = rt[a];
            for (int i = 0; i < NXMAX; ++i) post[i] = tpost[i];
            res = rest;
        }
        if (!fail && !done && res < 1e3 * goal) done = 1; /* stalled at rounding level */
        ok[c] = done && !fail;
        for (int i = 0; i < NXMAX; ++i) y_out[c * NXMAX + i] = ok[c] ? post[i] : NAN;
    }
}

#endif
