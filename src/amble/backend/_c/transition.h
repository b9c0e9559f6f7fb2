/* The transitions of the hybrid loop: an event found inside a step (flow.h) either crosses a
 * switching surface, restarting the method on its far side, or applies a transition's reset:
 * record it, end the run if it is terminal, else restart in the target mode — with the
 * sensitivities through the saltation matrix, the guards re-armed, a contact brought to rest and
 * the counts of steps, events and Zeno clusters checked.
 *
 * Needs from the including unit: run.h, flow.h, events.h, switch_side.h, record.h, rest.h, sensitivity.h.
 */
#ifndef AMBLE_TRANSITION_H
#define AMBLE_TRANSITION_H

/* Consecutive transitions closer than zeno_dt count towards a Zeno end. */
static void count_zeno(Run *r, double t_ev) {
    if (t_ev - r->ctx[CX_TPREV_EVENT] < r->o.zeno_dt) r->ctx[CX_ZENO] += 1; else r->ctx[CX_ZENO] = 0;
    r->ctx[CX_TPREV_EVENT] = t_ev;
}

/* A switching surface: restart on its far side at x_ev, or stop if the flow there points back
 * into it (sliding). */
static int cross_switch(Run *r, const Hit *e, double *x_ev) {
    Step *s = r->s;
    double *ctx = r->ctx;
    const double *p = r->p;
    const int mode = r->mode, ntr = MODE_NTR[mode], k = e->k;
    int st, zs;
    if (r->recording && r->o.sample_dt <= 0.0) put_row(&r->rec, e->t_ev, mode, s->n, x_ev);
    if (r->h_resume > r->h_abs) r->h_abs = r->h_resume;
    r->h_resume = 0.0;
    count_zeno(r, e->t_ev); /* crossings accumulating (a switch chattering about a kink) */
    double fm[NXMAX];
    if (r->sens && (st = sens_to_event(s, mode, p, r->t, s->y_old, e->t_ev, x_ev, 1, r->sens, fm))) return st;
    r->t = e->t_ev;
    onto_far_side(mode, k, r->t, x_ev, p, s->n, e->from);
    for (int i = 0; i < s->n; ++i) s->y_old[i] = x_ev[i];
    if (rhs(mode, r->t, s->y_old, p, s->f_old)) return ST_SINGULAR_MASS;
    if (r->sens && (st = sens_jump(mode, k, -1, mode, e->t_ev, x_ev, p, fm, s->f_old, 0, r->sens))) return st;
    surfaces(mode, r->t, s->y_old, p, r->g_old);
    surfaces_dot(mode, r->t, s->y_old, s->f_old, p, r->gd_old);
    if (slides_after_crossing(mode, k, r->t, s->y_old, p, s->n, r->g_old[k], r->gd_old[k], e->from)) {
        end_row(r);
        ctx[CX_INFO] = MODE_SW0[mode] + (k - ntr);
        return ST_SLIDING;
    }
    if ((zs = resolve_zero_switches(mode, r->t, s->y_old, p, r->g_old, s->n, k)) >= 0) {
        end_row(r);
        ctx[CX_INFO] = MODE_SW0[mode] + (zs - ntr);
        return ST_SLIDING;
    }
    if (r->o.zeno_n > 0 && ctx[CX_ZENO] >= r->o.zeno_n) {
        end_row(r);
        return ST_ZENO;
    }
    return -1;
}

/* Restarted in the target mode after transition tr (fired: the guard, if it fired into its own
 * mode, else −1): guards re-armed, a contact brought to rest, the run's counts checked. */
static int after_transition(Run *r, int tr, int fired) {
    Step *s = r->s;
    double *ctx = r->ctx;
    const Settings *o = &r->o;
    int st, zs;
    surfaces(r->mode, r->t, s->y_old, r->p, r->g_old);
    surfaces_dot(r->mode, r->t, s->y_old, s->f_old, r->p, r->gd_old);
    arm_zero_guards(r->mode, r->t, s->y_old, s->f_old, r->p, s->n, r->g_old, r->gd_old, fired, 0);
    if ((zs = resolve_zero_switches(r->mode, r->t, s->y_old, r->p, r->g_old, s->n, -1)) >= 0) {
        ctx[CX_INFO] = MODE_SW0[r->mode] + (zs - MODE_NTR[r->mode]);
        return ST_SLIDING;
    }
    /* a contact whose impacts accumulate, or that leaves the impact without normal velocity,
     * comes to rest; sensitivities are not carried through that transition (zeno instead) */
    if (TR_REST[tr] >= 0 && !r->sens
        && ((o->zeno_n > 0 && ctx[CX_ZENO] >= o->zeno_n) || settled(fired, s->n, s->y_old, r->g_old, r->gd_old))) {
        if ((st = come_to_rest(tr, r->t, r->p, s, &r->mode, ctx, &r->rec, r->recording, r->ev_recording, r->g_old,
                               r->gd_old)) >= 0)
            return st;
    }
    if (o->zeno_n > 0 && ctx[CX_ZENO] >= o->zeno_n) return ST_ZENO;
    if (o->max_steps > 0 && ctx[CX_STEPS] >= o->max_steps) return ST_STEPS_DONE;
    if (o->max_events > 0 && ctx[CX_EVENTS] >= o->max_events) return ST_MAX_EVENTS;
    return -1;
}

/* Stop at the event: the state is x_ev, ctx names the transition. */
static int stop_at(Run *r, double t_ev, const double *x_ev, int tr, int status) {
    r->t = t_ev;
    for (int i = 0; i < r->s->n; ++i) r->s->y_old[i] = x_ev[i];
    r->ctx[CX_INFO] = tr;
    return status;
}

/* An event of a transition at x_ev: record it, then end the run (terminal) or reset into the
 * target mode. */
static int apply_reset(Run *r, const Hit *e, const double *x_ev) {
    Step *s = r->s;
    double *ctx = r->ctx;
    const double *p = r->p;
    const int tr = MODE_TR0[r->mode] + e->k;
    const double t_ev = e->t_ev;
    int st;
    r->h_resume = 0.0;
    if (r->recording) put_row(&r->rec, t_ev, r->mode, s->n, x_ev);
    double fm[NXMAX];
    if (r->sens && (st = sens_to_event(s, r->mode, p, r->t, s->y_old, t_ev, x_ev, 0, r->sens, fm))) return st;
    double xpost[NXMAX];
    int target = r->mode;
    if (TR_TERMINAL[tr]) {
        for (int i = 0; i < s->n; ++i) xpost[i] = x_ev[i];
    } else {
        const int err = reset(tr, t_ev, x_ev, p, xpost, &target);
        if (err || target < 0 || target >= NMODES || !all_finite(MODE_NX[target], xpost))
            return stop_at(r, t_ev, x_ev, tr, err == AMBLE_ERR_SINGULAR_RESET || err == 0 ? ST_RESET_FAILED : ST_SINGULAR_MASS);
    }
    if (r->ev_recording) put_event(&r->rec, t_ev, tr, s->n, x_ev, MODE_NX[target], xpost);
    ctx[CX_EVENTS] += 1;
    ctx[CX_ISTEPS_EV] = 0;
    if (TR_TERMINAL[tr]) {
        if (r->sens) sens_jump(r->mode, e->k, tr, r->mode, t_ev, x_ev, p, fm, fm, 1, r->sens);
        return stop_at(r, t_ev, x_ev, tr, ST_TERMINAL);
    }
    count_zeno(r, t_ev);
    const int fired = target == r->mode ? e->k : -1, source = r->mode;
    r->mode = target;
    s->n = MODE_NX[target];
    r->t = t_ev;
    for (int i = 0; i < s->n; ++i) s->y_old[i] = xpost[i];
    if (r->recording) put_row(&r->rec, r->t, r->mode, s->n, s->y_old);
    if (TR_STEP[tr]) { ctx[CX_STEPS] += 1; ctx[CX_TLAST_STEP] = t_ev; }
    if (rhs(r->mode, r->t, s->y_old, p, s->f_old)) return ST_SINGULAR_MASS;
    if (r->sens && (st = sens_jump(source, e->k, tr, r->mode, t_ev, x_ev, p, fm, s->f_old, 0, r->sens))) return st;
    return after_transition(r, tr, fired);
}

#endif
