/* The cells engine: see evloop.h. */
#include "evloop.h"

#include <math.h>
#include <stdlib.h>

#include "nbep/calendar.h"
#include "nbep/cells.h"
#include "nbep/periodic.h"
#include "nbep/predict.h"

/* Partners are handed to the algorithm this many at a time (a block holds some 20 to 40 in a
 * dense fluid): one call per batch, not per pair. */
#define BATCH 64

struct nbep_evloop {
    size_t n;
    nbep_calendar *cal;   /* owned */
    nbep_cells cells;     /* owned */
    nbep_periodic pb;     /* the box's periodic geometry */
    nbep_feq *q;          /* borrowed */
    const uint64_t *ver;  /* borrowed */
};

nbep_status nbep_evloop_create(size_t n, nbep_vec3 lo, nbep_vec3 hi, double reach,
                               const bool *periodic, nbep_feq *q, const uint64_t *ver,
                               nbep_evloop **out, nbep_diag *d)
{
    nbep_evloop *e = calloc(1, sizeof *e);
    if (!e)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the cells engine");
    e->n = n;
    e->q = q;
    e->ver = ver;
    nbep_status st = nbep_calendar_create(n, &e->cal, d);
    if (st == NBEP_OK)
        st = nbep_cells_init(&e->cells, lo, hi, reach, n, periodic, d);
    if (st == NBEP_OK)
        e->pb = nbep_periodic_make(periodic, lo, hi);
    if (st != NBEP_OK) {
        nbep_evloop_destroy(&e);
        return st;
    }
    *out = e;
    return NBEP_OK;
}

void nbep_evloop_destroy(nbep_evloop **e)
{
    if (!e || !*e)
        return;
    nbep_calendar_destroy(&(*e)->cal);
    nbep_cells_fini(&(*e)->cells);
    free(*e);
    *e = NULL;
}

size_t nbep_evloop_bytes(size_t n)
{
    return nbep_calendar_bytes(n) + nbep_cells_bytes(n);
}

void nbep_evloop_assign(nbep_evloop *e, const nbep_vec3 *pos, size_t lo, size_t hi)
{
    nbep_cells_assign(&e->cells, pos, lo, hi);
}

void nbep_evloop_link(nbep_evloop *e)
{
    nbep_cells_link(&e->cells);
}

/* The calendar's tie key: the pair (lower sphere high, higher low), the same in both spheres'
 * slots; a plane contact or a cell exit ranks after every pair of its sphere. */
static uint64_t slot_key(uint32_t i, const nbep_event *ev)
{
    uint32_t a = i, b = UINT32_MAX;
    if (ev->kind == NBEP_EVENT_SPHERE) {
        a = i < ev->partner ? i : ev->partner;
        b = i < ev->partner ? ev->partner : i;
    } else if (ev->kind == NBEP_EVENT_PLANE) {
        b = UINT32_MAX - ev->partner;
    }
    return (uint64_t)a << 32 | b;
}

void nbep_evloop_visit_block(const nbep_evloop *e, uint32_t i,
                             void (*visit)(void *u, uint32_t j), void *u)
{
    const nbep_cells *g = &e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, g->cell[i], &b);
    for (int z = 0; z < b.cnt[2]; z++)
        for (int y = 0; y < b.cnt[1]; y++)
            for (int x = 0; x < b.cnt[0]; x++)
                for (uint32_t j = g->head[nbep_cells_index(g, b.idx[0][x], b.idx[1][y],
                                                           b.idx[2][z])];
                     j != NBEP_CELLS_NONE; j = g->next[j])
                    visit(u, j);
}

/* Sphere i's slot from scratch at time t: planes, the spheres of its block, its cell exit. */
static void predict_one(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                        double t)
{
    nbep_event best = ops->planes(u, i);
    const nbep_cells *g = &e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, g->cell[i], &b);
    uint32_t js[BATCH];
    size_t m = 0;
    /* a batch shares one shift: it is handed over when full or when the shift changes (only
     * at the periodic faces of the box) */
    nbep_vec3 shift = {0.0, 0.0, 0.0};
    const nbep_vec3 period = nbep_periodic_shift(&e->pb, (const int[3]){1, 1, 1});
    for (int z = 0; z < b.cnt[2]; z++)
        for (int y = 0; y < b.cnt[1]; y++)
            for (int x = 0; x < b.cnt[0]; x++) {
                /* the cell's copy of the box: whole periods, 0 off the periodic faces */
                const nbep_vec3 sh = {b.per[0][x] * period.x, b.per[1][y] * period.y,
                                      b.per[2][z] * period.z};
                if (m > 0 && !nbep_vec3_equal(sh, shift)) {
                    ops->pairs(u, i, js, m, shift, &best);
                    m = 0;
                }
                shift = sh;
                for (uint32_t j = g->head[nbep_cells_index(g, b.idx[0][x], b.idx[1][y],
                                                           b.idx[2][z])];
                     j != NBEP_CELLS_NONE; j = g->next[j]) {
                    if (j == i)
                        continue;
                    js[m++] = j;
                    if (m == BATCH) {
                        ops->pairs(u, i, js, m, shift, &best);
                        m = 0;
                    }
                }
            }
    if (m > 0)
        ops->pairs(u, i, js, m, shift, &best);
    nbep_vec3 p, v, a;
    ops->flight(u, i, t, &p, &v, &a);
    double t_exit = t + nbep_cells_exit_time(g, i, p, v, a);
    if (t_exit < NBEP_NEVER && (best.kind == NBEP_EVENT_NONE || t_exit < best.time))
        best = (nbep_event){t_exit, 0, NBEP_EVENT_HORIZON, e->ver[i], 0};
    if (best.kind == NBEP_EVENT_NONE) {
        nbep_feq_set_never(e->q, i, e->ver[i]);
    } else {
        nbep_feq_remove(e->q, i);
        nbep_feq_insert(e->q, i, best);
    }
}

/* The calendar entry of sphere i from its slot. */
static void schedule_one(nbep_evloop *e, uint32_t i)
{
    const nbep_event *ev = nbep_feq_slot(e->q, i);
    if (ev->kind == NBEP_EVENT_SPHERE || ev->kind == NBEP_EVENT_PLANE ||
        ev->kind == NBEP_EVENT_HORIZON)
        nbep_calendar_set(e->cal, i, ev->time, slot_key(i, ev));
    else
        nbep_calendar_remove(e->cal, i);
}

void nbep_evloop_predict(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, size_t lo,
                         size_t hi, double t)
{
    for (size_t i = lo; i < hi; i++)
        predict_one(e, ops, u, (uint32_t)i, t);
}

void nbep_evloop_schedule(nbep_evloop *e)
{
    nbep_calendar_clear(e->cal);
    for (size_t i = 0; i < e->n; i++)
        schedule_one(e, (uint32_t)i);
}

bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     uint64_t stall_events, double stall_dt, nbep_evloop_tally *tally,
                     double *t_stuck)
{
    uint64_t since = 0;
    double t_mark = -INFINITY;
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const nbep_event ev = *nbep_feq_slot(e->q, i);
        tally->events++;
        if (++since >= stall_events) {
            if (!(t - t_mark > stall_dt)) {
                *t_stuck = t;
                return false;
            }
            t_mark = t;
            since = 0;
        }
        if (ev.kind == NBEP_EVENT_HORIZON) {
            nbep_vec3 p, v, a;
            if (e->pb.any) /* a centre past a periodic face enters through the other */
                ops->wrap(u, i, t);
            ops->flight(u, i, t, &p, &v, &a);
            size_t c = nbep_cells_locate(&e->cells, p);
            if (c != e->cells.cell[i])
                nbep_cells_move(&e->cells, i, c);
            tally->exits++;
        } else if (ops->fresh(u, i, &ev)) {
            const uint32_t *changed;
            size_t m = ops->react(u, i, &ev, &changed);
            tally->reactions++;
            for (size_t k = 0; k < m; k++)
                if (changed[k] != i) {
                    predict_one(e, ops, u, changed[k], t);
                    schedule_one(e, changed[k]);
                }
        }
        /* in every case (exit, stale slot, reaction) i looks again from now */
        predict_one(e, ops, u, i, t);
        schedule_one(e, i);
    }
    return true;
}
