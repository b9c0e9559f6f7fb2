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
 * recorded). Per walk: the status of its last run (ST_STEPS_DONE if all runs completed), the
 * index of the transition that ended it (or -1), the footfalls taken, the last distance (NaN if
 * no run completed) and the final state (NaN-padded to NXMAX).
 *
 * next: NULL (walk rows 0 … n-1 in order), or a counter shared by several threads calling this
 * on the same rows at once: each takes the next unwalked row with an atomic increment, so the
 * threads share the walks one by one, however unequal their lengths (a walk that falls at once
 * and one that walks all its steps differ a hundredfold; blocks fixed in advance leave one
 * thread working alone at the end). Each row is written by the one thread that took it. */
void amble_walk_batch(int64_t n, int64_t *next, int mode, const double *x0, const double *p, const double *opt,
                      const int64_t *iopt_in, const double *xref, int64_t steps, int64_t check_every, double tol,
                      int *code, int *info, int64_t *done_steps, double *dist, double *x_out) {
    int64_t iopt[IO_YIELDN + 1];
    for (int i = 0; i <= IO_YIELDN; ++i) iopt[i] = iopt_in[i];
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
            st = amble_simulate(p, ctx, opt, iopt, NULL, NULL, NULL, &zero, NULL, NULL, NULL, NULL, &zero, NULL);
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

#endif
