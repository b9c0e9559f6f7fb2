/* Where a hybrid run stands: its settings, read once from opt and iopt, and what the loop carries
 * from one step to the next. Loaded from ctx at the start of a call of amble_simulate and saved
 * back at its end, so a run resumes exactly where it stopped (buffers grown, signals handled).
 *
 * The loop's pieces (flow.h, transition.h) take a Run and return −1 (the run goes on) or the
 * status ST_* that ends the call.
 *
 * Needs from the including unit: stepper.h, events.h, switch_side.h, record.h, NSUB_MAX, the CX_, OP_, IO_ codes.
 */
#ifndef AMBLE_RUN_H
#define AMBLE_RUN_H

typedef struct {
    double t_end, rtol, atol, max_step, max_step_time, sample_dt, zeno_dt;
    int64_t max_steps, max_events, zeno_n, max_isteps, max_isteps_ev, yield_n;
    int nsub;
} Settings;

typedef struct {
    const double *p;
    double *ctx, *sens; /* sens: NULL, or the buffer of sensitivity.h */
    Settings o;
    Rec rec;
    int recording, ev_recording;
    Step *s;            /* the method's state; s->y_old is the current state */
    int mode;
    double t, h_abs;
    double h_resume;    /* the step size before a switching surface spoiled a step: resumed once it is crossed */
    int64_t isteps_call;
    double *g_old, *gd_old, *g_new, *gd_new; /* the mode's surfaces and rates at both ends of the step (NTR1) */
} Run;

static void settings_read(Settings *o, const double *opt, const int64_t *iopt) {
    o->t_end = opt[OP_TEND], o->rtol = opt[OP_RTOL], o->atol = opt[OP_ATOL];
    o->max_step = opt[OP_MAXSTEP] > 0 ? opt[OP_MAXSTEP] : INFINITY;
    o->max_step_time = opt[OP_MAXSTEPTIME], o->sample_dt = opt[OP_SAMPLEDT], o->zeno_dt = opt[OP_ZENODT];
    o->max_steps = iopt[IO_MAXSTEPS], o->max_events = iopt[IO_MAXEVENTS], o->zeno_n = iopt[IO_ZENON];
    o->max_isteps = iopt[IO_MAXISTEPS], o->max_isteps_ev = iopt[IO_MAXISTEPS_EV], o->yield_n = iopt[IO_YIELDN];
    int nsub = (int)iopt[IO_NSUB];
    if (nsub < 1) nsub = 1;
    if (nsub > NSUB_MAX) nsub = NSUB_MAX;
    o->nsub = nsub;
}

/* The state of ctx into the run, the initial row if still to be recorded, and f there. Returns
 * −1, or a status to return at once with ctx untouched. */
static int run_load(Run *r) {
    Step *s = r->s;
    double *ctx = r->ctx;
    r->mode = (int)ctx[CX_MODE];
    if (r->mode < 0 || r->mode >= NMODES) return ST_RESET_FAILED;
    s->n = MODE_NX[r->mode];
    r->t = ctx[CX_T];
    for (int i = 0; i < s->n; ++i) s->y_old[i] = ctx[CX_X + i];
    if (!all_finite(s->n, s->y_old)) return ST_NONFINITE;
    if (ctx[CX_FRESH] != 0.0) {
        if (r->recording) {
            if (*r->rec.n_out + 1 > r->rec.out_cap) return ST_BUFFER_FULL;
            put_row(&r->rec, r->t, r->mode, s->n, s->y_old);
        }
        ctx[CX_FRESH] = 0.0;
    }
    if (rhs(r->mode, r->t, s->y_old, r->p, s->f_old)) return ST_SINGULAR_MASS;
    return -1;
}

/* The first step size and the surfaces at the start; −1, or ST_SLIDING if the state starts on a
 * switch it cannot leave. */
static int run_arm(Run *r) {
    Step *s = r->s;
    const Settings *o = &r->o;
    r->h_abs = r->ctx[CX_H];
    if (!(r->h_abs > 0.0))
        r->h_abs = initial_step(r->mode, r->t, s->y_old, s->f_old, r->p, o->t_end, o->max_step, o->rtol, o->atol,
                                s->n, s->m->error_order);
    surfaces(r->mode, r->t, s->y_old, r->p, r->g_old);
    surfaces_dot(r->mode, r->t, s->y_old, s->f_old, r->p, r->gd_old);
    /* no transition yet (a resumed call has had one, or left the start behind): the run's start */
    const int start = r->ctx[CX_TPREV_EVENT] == -INFINITY;
    arm_zero_guards(r->mode, r->t, s->y_old, s->f_old, r->p, s->n, r->g_old, r->gd_old, -1, start);
    r->h_resume = 0.0;
    int zs;
    if ((zs = resolve_zero_switches(r->mode, r->t, s->y_old, r->p, r->g_old, s->n, -1)) >= 0) {
        r->ctx[CX_INFO] = MODE_SW0[r->mode] + (zs - MODE_NTR[r->mode]);
        return ST_SLIDING;
    }
    return -1;
}

/* The ends checked before each step: time, a walker that stopped stepping, the step budgets, and
 * the periodic return to Python (ST_YIELD). */
static int run_limits(const Run *r) {
    const Settings *o = &r->o;
    const double *ctx = r->ctx;
    if (r->t >= o->t_end) return ST_END_TIME;
    if (o->max_step_time > 0.0 && r->t - ctx[CX_TLAST_STEP] >= o->max_step_time) return ST_STEP_TIMEOUT;
    if (o->max_isteps > 0 && ctx[CX_ISTEPS] >= (double)o->max_isteps) return ST_MAX_ISTEPS;
    if (o->max_isteps_ev > 0 && ctx[CX_ISTEPS_EV] >= (double)o->max_isteps_ev) return ST_STALLED;
    if (o->yield_n > 0 && r->isteps_call >= o->yield_n) return ST_YIELD;
    return -1;
}

/* A run that samples a grid ends with a row of the state where it stopped. */
static void end_row(Run *r) {
    if (r->recording && r->o.sample_dt > 0.0) put_row(&r->rec, r->t, r->mode, r->s->n, r->s->y_old);
}

/* Where the run stands, back into ctx. */
static void run_save(const Run *r) {
    double *ctx = r->ctx;
    ctx[CX_T] = r->t;
    ctx[CX_MODE] = r->mode;
    ctx[CX_H] = r->h_abs;
    for (int i = 0; i < NXMAX; ++i) ctx[CX_X + i] = i < r->s->n ? r->s->y_old[i] : 0.0;
}

#endif
