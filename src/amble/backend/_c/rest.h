/* A unilateral contact coming to rest: when the firings of a transition accumulate (a Zeno
 * cluster of impacts, or restitution 0 repeating the impact at once) and the transition declares
 * a rest transition (TR_REST), that transition is taken instead of ending the run as zeno — a
 * reset into the resting mode, where the contact force holds the constraint.
 *
 * Needs from the including unit: events.h, record.h, the ST_* and CX_* codes, TR_REST, reset, rhs.
 */
#ifndef AMBLE_REST_H
#define AMBLE_REST_H

/* After an impact of guard k (fired into its own mode, -1 otherwise; g after arm_zero_guards):
 * is the contact closed with no normal velocity left (the rate zero to the round-off of the
 * state, the threshold of arm_zero_guards) and does the flow press into it — arm_zero_guards
 * then armed the guard to fire again at once (g = DBL_MIN)? Restitution 0 leaves a contact so,
 * and so does a point started on it; where the flow pulls away the point leaves freely. */
static int settled(int k, int n, const double *x, const double *g, const double *gd) {
    if (k < 0) return 0;
    double scale = 1.0;
    for (int i = 0; i < n; ++i) scale = fmax(scale, fabs(x[i]));
    return fabs(gd[k]) <= 1e-12 * scale && g[k] == DBL_MIN;
}

/* Take the rest transition of transition tr at time t from the state in s->y_old (mode *mode):
 * reset, record the event and the post-event row, and re-arm the guards of the new mode in
 * g_old, gd_old. Returns -1 (the run goes on) or a status ST_* that ends it. The caller has made
 * room for one more row and one more event. */
static int come_to_rest(int tr, double t, const double *p, Step *s, int *mode, double *ctx, Rec *rec,
                        int recording, int ev_recording, double *g_old, double *gd_old) {
    const int rt = TR_REST[tr];
    double xr[NXMAX];
    int target = *mode;
    int err = reset(rt, t, s->y_old, p, xr, &target);
    if (err || target < 0 || target >= NMODES || !all_finite(MODE_NX[target], xr)) {
        ctx[CX_INFO] = rt;
        return err == AMBLE_ERR_SINGULAR_RESET || err == 0 ? ST_RESET_FAILED : ST_SINGULAR_MASS;
    }
    if (ev_recording) put_event(rec, t, rt, s->n, s->y_old, MODE_NX[target], xr);
    ctx[CX_EVENTS] += 1;
    ctx[CX_ISTEPS_EV] = 0;
    ctx[CX_ZENO] = 0; /* at rest the cluster is over */
    *mode = target;
    s->n = MODE_NX[target];
    for (int i = 0; i < s->n; ++i) s->y_old[i] = xr[i];
    if (recording) put_row(rec, t, target, s->n, s->y_old);
    if (rhs(target, t, s->y_old, p, s->f_old)) return ST_SINGULAR_MASS;
    surfaces(target, t, s->y_old, p, g_old);
    surfaces_dot(target, t, s->y_old, s->f_old, p, gd_old);
    arm_zero_guards(target, t, s->y_old, s->f_old, p, s->n, g_old, gd_old, -1, 0);
    return -1;
}

#endif
