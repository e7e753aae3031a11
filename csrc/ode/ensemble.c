/* Ensembles: many independent solves of one method, spread over threads.
 * Each trajectory is an ordinary mp_ode_solve (the one driver loop), or, in
 * lanes, a lane of a thread's lane group (lanes.c); only the t_eval samples
 * are kept.  Nothing is shared between threads but the read-only inputs, a
 * work counter and a stop flag. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include "ode/ensemble.h"

#include "models/models.h"
#include "models/rigid.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The main thread asks the caller (which takes the GIL) at most this often:
 * Ctrl-C still answers within a fraction of a second, and other Python
 * threads are not made to hand over the GIL after every trajectory. */
#define ENS_INTERRUPT_PERIOD 0.02 /* s */

typedef struct {
    const mp_ode_method *m;
    const mp_ode_problem *probs;
    const mp_lane_system *lanes; /* NULL: the scalar path */
    size_t k, n, nt;
    double t0, tf;
    const double *y0s;
    const mp_ode_options *o;
    double *yout;
    mp_ode_outcome *out;
    mp_ode_result *results;     /* keep each trajectory's result (or NULL) */
    void *const *events_data;   /* trajectory i's events data (or NULL) */
    atomic_size_t next, done;
    atomic_int stop;    /* set on interrupt or a fatal error */
    atomic_int running; /* worker threads not yet finished */
    int fatal;          /* first fatal status (written once, under stop) */
    mp_ode_interrupt interrupt; /* the main thread's check (may be NULL) */
    void *interrupt_ctx;
    void (*progress)(size_t done, size_t total, void *ctx);
    void *progress_ctx;
    double last_check; /* monotonic time of the main thread's last check */
} ens_ctx;

static int worker_interrupt(void *ctx) { return atomic_load(&((ens_ctx *)ctx)->stop) ? MP_EINTR : MP_OK; }

typedef struct {
    ens_ctx *e;
    int is_main;
} ens_arg;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int main_interrupt(void *ctx)
{
    ens_ctx *e = ctx;
    if (atomic_load(&e->stop)) return MP_EINTR;
    if (!e->interrupt) return MP_OK;
    double t = now_s();
    if (t - e->last_check < ENS_INTERRUPT_PERIOD) return MP_OK;
    e->last_check = t;
    if (e->interrupt(e->interrupt_ctx) != MP_OK) {
        atomic_store(&e->stop, 1);
        return MP_EINTR;
    }
    return MP_OK;
}

/* ---- the lane feed: ens_run's loop for a lane group ---- */

/* Contract: the next trajectory index, or k when stopped or none is left. */
static size_t lane_take(void *ctx)
{
    ens_ctx *e = ((ens_arg *)ctx)->e;
    if (atomic_load(&e->stop)) return e->k;
    size_t i = atomic_fetch_add(&e->next, 1);
    return i < e->k ? i : e->k;
}

/* Contract: trajectory i is written: count it, report progress and check for
 * interrupts on the main thread; non-zero stops the group. */
static int lane_done(void *ctx, size_t i)
{
    ens_arg *a = ctx;
    ens_ctx *e = a->e;
    (void)i;
    size_t d = atomic_fetch_add(&e->done, 1) + 1;
    if (!a->is_main) return atomic_load(&e->stop);
    if (e->progress) e->progress(d, e->k, e->progress_ctx);
    return main_interrupt(e) != MP_OK;
}

static int lane_interrupt(void *ctx)
{
    ens_arg *a = ctx;
    return a->is_main ? main_interrupt(a->e) : worker_interrupt(a->e);
}

/* Contract: run ens_run's share of the ensemble in one lane group; a stop
 * (interrupt, memory) is recorded as the scalar path records it. */
static void ens_run_lanes(ens_arg *a)
{
    ens_ctx *e = a->e;
    mp_lane_feed feed = {lane_take, lane_done, lane_interrupt, a};
    int rc = mp_ode_lanes_run(e->m, e->probs, e->lanes, e->k, e->t0, e->tf, e->y0s, e->o,
                              e->yout, e->out, e->results, &feed);
    if (rc != MP_OK && !atomic_exchange(&e->stop, 1)) e->fatal = rc;
}

/* Contract: trajectory i on the scalar path (mp_ode_solve with options o, its
 * events data set here): its outcome, its samples in yout (NaN for those not
 * reached) and, with results, its whole result (the caller frees it).
 * Returns the solve's status. */
static int ens_solve_one(ens_ctx *e, size_t i, mp_ode_options *o)
{
    mp_ode_result r;
    if (e->events_data) o->events_data = o->action_data = e->events_data[i];
    int rc = mp_ode_solve(e->m, &e->probs[i], e->t0, e->tf, e->y0s + i * e->n, o, &r);
    mp_ode_result_outcome(&r, &e->out[i]);
    double *dst = e->yout + i * e->n * e->nt; /* (n, nt) block */
    for (size_t j = 0; j < e->nt; j++)
        for (size_t c = 0; c < e->n; c++)
            dst[c * e->nt + j] = j < r.m ? r.y[j * e->n + c] : NAN;
    if (e->results) e->results[i] = r; /* the caller frees it */
    else mp_ode_result_free(&r);
    return rc;
}

static void *ens_run(void *argp)
{
    ens_arg *a = argp;
    ens_ctx *e = a->e;
    if (e->lanes) {
        ens_run_lanes(a);
        return NULL;
    }
    mp_ode_options o = *e->o;
    o.interrupt = a->is_main ? main_interrupt : worker_interrupt;
    o.interrupt_ctx = e;
    for (;;) {
        if (atomic_load(&e->stop)) break;
        size_t i = atomic_fetch_add(&e->next, 1);
        if (i >= e->k) break;
        int rc = ens_solve_one(e, i, &o);
        if (rc == MP_EINTR || rc == MP_ECALLBACK || rc == MP_ENOMEM) {
            if (!atomic_exchange(&e->stop, 1)) e->fatal = rc;
            break;
        }
        size_t d = atomic_fetch_add(&e->done, 1) + 1;
        if (a->is_main && e->progress) e->progress(d, e->k, e->progress_ctx);
        if (a->is_main && main_interrupt(e) != MP_OK) break;
    }
    return NULL;
}

/* A worker thread: its share of the ensemble, then one fewer running. */
static void *ens_worker(void *argp)
{
    ens_arg *a = argp;
    ens_run(a);
    atomic_fetch_sub(&a->e->running, 1);
    return NULL;
}

/* Contract: see lanes.h: a row with a lane kernel, t_eval given, no dense
 * output, events only when the lanes run them, and the checks solve_forward
 * makes at its start pass (else the scalar path reports them). */
int mp_ode_lanes_supported(const mp_ode_method *m, const mp_ode_options *o, double t0, double tf,
                           int lane_events)
{
    return m->lanes != MP_LANE_NONE && o->n_eval > 0 && (lane_events || !o->n_events) && !o->dense &&
           mp_ode_span_ok(m, t0, tf, o) == MP_OK;
}

/* Contract: the lane driver built for this processor: AVX2+FMA when it has
 * them, else the portable build. */
int mp_ode_lanes_run(const mp_ode_method *m, const mp_ode_problem *probs,
                     const mp_lane_system *ls, size_t k, double t0, double tf, const double *y0s,
                     const mp_ode_options *o, double *yout, mp_ode_outcome *out,
                     mp_ode_result *results, const mp_lane_feed *feed)
{
#if defined(MP_LANES_HAVE_AVX2)
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        return mp_ode_lanes_run_avx2(m, probs, ls, k, t0, tf, y0s, o, yout, out, results, feed);
#endif
    return mp_ode_lanes_run_base(m, probs, ls, k, t0, tf, y0s, o, yout, out, results, feed);
}

int mp_ode_solve_many(const mp_ode_method *m, const mp_ode_problem *probs,
                      const mp_lane_system *lanes, size_t k, double t0, double tf,
                      const double *y0s, const mp_ode_options *o, int threads, double *yout,
                      mp_ode_outcome *out, mp_ode_result *results, void *const *events_data,
                      void (*progress)(size_t, size_t, void *), void *progress_ctx)
{
    if (k == 0) return MP_OK;
    ens_ctx e = {0};
    e.m = m;
    e.probs = probs;
    e.lanes = lanes;
    e.k = k;
    e.n = probs[0].n;
    e.nt = o->n_eval;
    e.t0 = t0;
    e.tf = tf;
    e.y0s = y0s;
    e.o = o;
    e.yout = yout;
    e.out = out;
    e.results = results;
    e.events_data = events_data;
    e.interrupt = o->interrupt;
    e.interrupt_ctx = o->interrupt_ctx;
    e.progress = progress;
    e.progress_ctx = progress_ctx;
    atomic_init(&e.next, 0);
    atomic_init(&e.done, 0);
    atomic_init(&e.stop, 0);
    for (size_t i = 0; i < k; i++) /* not run (the ensemble was stopped) */
        out[i] = (mp_ode_outcome){.status = MP_EINTR, .t_fail = t0};
    if (threads < 1) threads = 1;
    if ((size_t)threads > k) threads = (int)k;
    pthread_t *tid = threads > 1 ? malloc((size_t)(threads - 1) * sizeof *tid) : NULL;
    if (threads > 1 && !tid) return MP_ENOMEM;
    ens_arg wa = {&e, 0}, ma = {&e, 1};
    int started = 0;
    atomic_init(&e.running, threads - 1);
    for (int i = 0; i < threads - 1; i++) {
        if (pthread_create(&tid[i], NULL, ens_worker, &wa) != 0) {
            atomic_fetch_sub(&e.running, threads - 1 - i); /* these never start */
            break;
        }
        started++;
    }
    ens_run(&ma); /* the calling thread works too, and watches for interrupts */
    /* Its share done (or none left to take: a worker's lane group can take every
       trajectory before the calling thread starts), it keeps watching until the
       workers end: they never ask for interrupts themselves, and a joined-on
       worker with a long trajectory left Ctrl-C unanswered for good. */
    while (atomic_load(&e.running) > 0 && !atomic_load(&e.stop)) {
        struct timespec nap = {0, 5000000}; /* 5 ms */
        nanosleep(&nap, NULL);
        main_interrupt(&e);
    }
    for (int i = 0; i < started; i++) pthread_join(tid[i], NULL);
    free(tid);
    if (e.fatal) return e.fatal;
    if (atomic_load(&e.stop)) return MP_EINTR;
    /* a lane whose body came to rest on a wall: that trajectory again on the
     * scalar path, which rests and lifts off (the lanes do not: it is rare, and
     * a resting lane would hold its group's lock-step) */
    mp_ode_options so = *o;
    so.interrupt = main_interrupt;
    so.interrupt_ctx = &e;
    for (size_t i = 0; lanes && i < k; i++) {
        if (out[i].stop_reason != MP_ODE_STOP_TO_SCALAR) continue;
        if (results) mp_ode_result_free(&results[i]);
        int rc = ens_solve_one(&e, i, &so);
        if (rc == MP_EINTR || rc == MP_ECALLBACK || rc == MP_ENOMEM) return rc;
    }
    return MP_OK;
}

/* ---- an ensemble's problems --------------------------------------------------- */

int mp_ode_ensemble_build(mp_ode_ensemble *e, double t0, double tf, const mp_ode_options *o)
{
    const mp_model *mod = e->model;
    size_t k = e->k;
    e->probs = NULL;
    e->torques = NULL;
    e->lanes = NULL;
    e->why = MP_ENS_OK;
    memset(&e->ls, 0, sizeof e->ls);
    if (e->m->symplectic && !e->m->implicit && e->base.nq == 0) {
        e->why = MP_ENS_SEPARABLE;
        return MP_EDOM;
    }
    if (e->rows && e->rows_kind == MP_ENS_ROWS_SCENE && !mod->dim_of && e->np != mod->nparams) {
        e->why = MP_ENS_COLUMNS;
        e->np_need = mod->nparams;
        return MP_EDOM;
    }
    if (e->rows && e->rows_kind == MP_ENS_ROWS_DATA && e->np != e->nparams) {
        e->why = MP_ENS_COLUMNS;
        e->np_need = e->nparams;
        return MP_EDOM;
    }
    if (!(e->probs = malloc((k ? k : 1) * sizeof *e->probs))) return MP_ENOMEM;
    for (size_t i = 0; i < k; i++) e->probs[i] = e->base;
    if (e->rows && e->rows_kind == MP_ENS_ROWS_SCENE) {
        if (e->torque && !(e->torques = calloc(k ? k : 1, sizeof *e->torques))) return MP_ENOMEM;
        for (size_t i = 0; i < k; i++) {
            const double *row = e->rows + i * e->np;
            size_t dim;
            if (mp_model_prepare(mod, row, e->np, &dim) != MP_OK || dim != e->n) {
                e->why = MP_ENS_ROW;
                e->bad_row = i;
                return MP_EDOM;
            }
            mod->bind(row, &e->probs[i]);
            if (e->torque) {
                e->torques[i] = *e->torque;
                e->torques[i].params = row;
                mp_rigid_bind_torque(mod, &e->torques[i], &e->probs[i]);
            }
        }
    } else if (e->rows && e->rows_kind == MP_ENS_ROWS_DATA) {
        for (size_t i = 0; i < k; i++) e->probs[i].data = (void *)(e->rows + i * e->np);
    }
    /* the lane system: the rows (or the one parameter vector) and a lane rhs */
    mp_lane_system *ls = &e->ls;
    size_t kk = k;
    if (e->rows && e->rows_kind != MP_ENS_ROWS_CALLER) {
        ls->params = e->rows;
        ls->np = ls->pstride = e->np;
    } else if (e->params) {
        ls->params = e->params;
        ls->np = e->nparams;
        kk = 1;
    }
    /* lanes run a system in C: a scene, or a compiled system (its parameter
     * vector); a callback's problem stays on the scalar path */
    int scene_or_compiled = mod != NULL || e->params != NULL;
    if (!mod && ls->params) ls->rhs = e->lane_rhs;
    if (mod && !e->torque && mod->lanes && ls->params) ls->rhs = mod->lanes(ls->params, kk, ls->pstride);
    /* a problem with a switch ahead crosses it as an event: the scalar path */
    int ok = !e->holds_python && scene_or_compiled && e->rows_kind != MP_ENS_ROWS_CALLER &&
             !e->base.sw && mp_ode_lanes_supported(e->m, o, t0, tf, e->n_impacts > 0);
    if (e->want_lanes == 1 && !ok) {
        e->why = MP_ENS_NO_LANES;
        return MP_EDOM;
    }
    ls->impacts = e->impacts;
    ls->n_impacts = e->n_impacts;
    e->lanes = ok && e->want_lanes != 0 ? ls : NULL;
    return MP_OK;
}

void mp_ode_ensemble_free(mp_ode_ensemble *e)
{
    free(e->probs);
    free(e->torques);
    e->probs = NULL;
    e->torques = NULL;
}
