/* The flow part of the hybrid loop, along SciPy's solve_ivp: integrate one step of the method,
 * locate the earliest event inside it, record the step's rows, and move on to its end when it
 * holds no event. The transitions an event starts are transition.h's.
 *
 * Needs from the including unit: run.h, stepper.h, events.h, switch_side.h, record.h, sensitivity.h.
 */
#ifndef AMBLE_FLOW_H
#define AMBLE_FLOW_H

/* The step just taken and the event found in it. */
typedef struct {
    double h_next; /* the step size the method proposes next */
    double t_new;  /* the step's end */
    int k;         /* surface index of the event within the mode, or −1: none */
    double t_ev;   /* its time */
    double from;   /* the surface's value on the near side (where the crossing came from) */
} Hit;

/* One accepted step of the method from the current state, bounded by the end time and by the
 * time a walker may go without a step; the surfaces at its end into g_new, gd_new. */
static int integrate(Run *r, Hit *e) {
    Step *s = r->s;
    const Settings *o = &r->o;
    const double *ctx = r->ctx;
    double t_bound = o->t_end;
    if (o->max_step_time > 0.0 && ctx[CX_TLAST_STEP] + o->max_step_time < t_bound) t_bound = ctx[CX_TLAST_STEP] + o->max_step_time;
    s->t_old = r->t;
    double h_kink = 0.0;
    e->h_next = r->h_abs;
    const int ntr = MODE_NTR[r->mode];
    const double *sw0 = MODE_NSW[r->mode] > 0 ? r->g_old + ntr : NULL;
    const int st = s->m->step(s, r->mode, r->p, t_bound, o->rtol, o->atol, o->max_step, &e->h_next, sw0,
                              sw0 ? r->gd_old + ntr : NULL, &h_kink, r->g_new, r->gd_new);
    if (st) return st;
    if (h_kink > r->h_resume) r->h_resume = h_kink;
    e->t_new = r->t + s->h;
    return -1;
}

/* The earliest enabled crossing inside the step (x_ev: the state there), or a kink within the
 * rounding of the state that no step reaches. */
static int locate_event(Run *r, Hit *e, double *x_ev) {
    Step *s = r->s;
    const int mode = r->mode, ntr = MODE_NTR[mode], nsf = n_surf(mode);
    int st;
    e->from = 0.0;
    if ((st = find_event(s, mode, r->p, r->o.nsub, r->t, e->t_new, r->g_old, r->gd_old, r->g_new, r->gd_new, &e->k,
                         &e->t_ev, x_ev, &e->from, r->ctx[CX_TLAST_STEP], 8.0 * r->o.atol, 8.0 * r->o.rtol)))
        return st;
    if (e->k < 0 && nsf > ntr && (e->k = stuck_at_switch(mode, e->t_new, s->y, r->p, s->n, r->g_old, r->g_new, r->gd_new,
                                                        x_ev)) >= 0) {
        /* approached but out of reach of any step: crossed at the step's end, as if located there */
        e->t_ev = e->t_new;
        e->from = r->g_new[e->k];
        if (r->sens && step_dense_prepare(s, mode, r->p)) return ST_SINGULAR_MASS;
    }
    return -1;
}

/* The step's rows: grid samples up to the event or the step's end, else the end itself. Checks
 * first that they, the event's rows and a rest transition's fit: if not, ST_BUFFER_FULL, and the
 * call returns to resume at this step with larger buffers. */
static int record_step(Run *r, const Hit *e) {
    const Settings *o = &r->o;
    double *ctx = r->ctx;
    Rec *rec = &r->rec;
    const int mode = r->mode, ntr = MODE_NTR[mode], tr0 = MODE_TR0[mode];
    const double t_stop = e->k >= 0 ? e->t_ev : e->t_new;
    int64_t k0 = (int64_t)ctx[CX_GRID_K], k1 = k0;
    if (r->recording && o->sample_dt > 0.0) k1 = grid_end(ctx, o->sample_dt, k0, t_stop);
    const int rest_room = e->k >= 0 && e->k < ntr && TR_REST[tr0 + e->k] >= 0; /* room to come to rest */
    const int64_t need = (k1 - k0) + (e->k >= 0 ? 2 : 0) + ((o->sample_dt > 0.0) ? 0 : 1) + rest_room;
    if ((r->recording && *rec->n_out + need > rec->out_cap) ||
        (e->k >= 0 && r->ev_recording && *rec->n_ev + 1 + rest_room > rec->ev_cap))
        return ST_BUFFER_FULL;
    if (r->recording) {
        if (o->sample_dt > 0.0 && k1 > k0) {
            if (put_grid_rows(rec, r->s, mode, r->p, ctx, o->sample_dt, k0, k1, r->t)) return ST_SINGULAR_MASS;
        } else if (o->sample_dt <= 0.0 && e->k < 0) {
            put_row(rec, e->t_new, mode, r->s->n, r->s->y);
        }
        ctx[CX_GRID_K] = (double)k1;
    }
    return -1;
}

/* The step counts: the run goes on with the size the method proposed. */
static void accept_step(Run *r, const Hit *e) {
    r->h_abs = e->h_next;
    ++r->isteps_call;
    r->ctx[CX_ISTEPS] += 1;
    r->ctx[CX_ISTEPS_EV] += 1;
}

/* A step without event: the sensitivities along, the state to its end; ST_SLIDING if the flow
 * is about to press into a switch from both sides. */
static int advance(Run *r, const Hit *e) {
    Step *s = r->s;
    const int mode = r->mode, ntr = MODE_NTR[mode], nsf = n_surf(mode);
    int st, zs;
    if (r->sens) {
        double y1[NXMAX];
        if ((st = sens_advance(s->m->tableau, mode, r->p, sens_cols(r->sens), r->t, s->h, s->y_old, r->sens + SENS_S, y1)))
            return st;
    }
    r->t = e->t_new;
    for (int i = 0; i < s->n; ++i) { s->y_old[i] = s->y[i]; s->f_old[i] = s->f[i]; }
    for (int k = 0; k < nsf; ++k) { r->g_old[k] = r->g_new[k]; r->gd_old[k] = r->gd_new[k]; }
    if (nsf > ntr && (zs = approaching_slide(mode, r->t, s->y_old, r->p, s->n, r->g_old, r->gd_old, r->h_abs,
                                             20.0 * (r->o.atol + r->o.rtol))) >= 0) {
        end_row(r);
        r->ctx[CX_INFO] = MODE_SW0[mode] + (zs - ntr);
        return ST_SLIDING;
    }
    return -1;
}

#endif
