/* Recording a run into caller-owned buffers: sample rows (time, mode, state padded with NaN to
 * NXMAX) and event rows (time, transition, pre- and post-event states). Counters and capacities
 * are int64_t, shared with NumPy int64 arrays.
 *
 * Needs from the including unit: stepper.h, the ST_* and CX_* codes, NXMAX.
 */
#ifndef AMBLE_RECORD_H
#define AMBLE_RECORD_H

typedef struct {
    double *out_t, *out_x, *ev_t, *ev_xpre, *ev_xpost;
    int *out_mode, *ev_tr;
    int64_t *n_out, *n_ev;
    int64_t out_cap, ev_cap;
} Rec;

static void put_row(Rec *r, double t, int mode, int n, const double *x) {
    int64_t k = (*r->n_out)++;
    r->out_t[k] = t;
    r->out_mode[k] = mode;
    double *row = r->out_x + k * NXMAX;
    int i = 0;
    for (; i < n; ++i) row[i] = x[i];
    for (; i < NXMAX; ++i) row[i] = NAN;
}

static void put_event(Rec *r, double t, int tr, int n_pre, const double *x_pre, int n_post, const double *x_post) {
    int64_t e = (*r->n_ev)++;
    r->ev_t[e] = t;
    r->ev_tr[e] = tr;
    for (int i = 0; i < NXMAX; ++i) {
        r->ev_xpre[e * NXMAX + i] = i < n_pre ? x_pre[i] : NAN;
        r->ev_xpost[e * NXMAX + i] = i < n_post ? x_post[i] : NAN;
    }
}

/* One past the last output-grid index at or before t_stop, starting from index k0. */
static int64_t grid_end(const double *ctx, double sample_dt, int64_t k0, double t_stop) {
    int64_t k1 = k0;
    while (ctx[CX_GRID_T0] + k1 * sample_dt <= t_stop) ++k1;
    return k1;
}

/* Rows of the output grid k0 .. k1-1 of the step from t, on its dense output (samples at or
 * before t were written by the previous step). The rows are written by the model's unit
 * (the method's dense_rows), where the state length and the row stride are constants. Returns 0 or
 * ST_SINGULAR_MASS. */
static int put_grid_rows(Rec *r, Step *s, int mode, const double *p, const double *ctx, double sample_dt,
                         int64_t k0, int64_t k1, double t) {
    if (step_dense_prepare(s, mode, p)) return ST_SINGULAR_MASS;
    const int64_t first = *r->n_out;
    const int64_t m = s->m->dense_rows(s, ctx[CX_GRID_T0], sample_dt, k0, k1, t, r->out_t + first, r->out_x + first * NXMAX);
    for (int64_t k = first; k < first + m; ++k) r->out_mode[k] = mode;
    *r->n_out = first + m;
    return 0;
}

#endif
