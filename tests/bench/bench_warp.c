/* What the optimistic scheduler (src/warp.c) gives on threads, on a model whose events cost what
 * the fluid's do: sites on a ring (tests/test_warp.c's model, with a calendar a slab), the ring
 * dealt to the slabs in chunks of CHUNK consecutive sites, round the slabs in turn (so that a
 * share of the sites lies at a face, as the spheres near a slab's side do: 2 / CHUNK of them),
 * each event padded with WORK rounds of a hash (about a microsecond at the default, an event's
 * time in the fluid). The serial loop (one world, one calendar) and the scheduler on SLABS
 * threads, one a slab, in windows of WINDOW time units, alternate REPEATS times; each scheduled
 * run is checked against the serial one (every site, bit for bit). Prints '#' lines, then CSV:
 * slabs, events, the serial run's median seconds, the scheduler's, their ratio (serial over
 * scheduled: the speed-up), and per event the rollbacks, events undone and messages.
 *
 *   bench_warp [sites [slabs [chunk [window [work [t_end [repeats]]]]]]]
 *   defaults:  200000 2     64      0.02     150    2.0    5
 *
 * A sketch of the engine to come, not the engine: its events read two neighbours, not a list
 * of a dozen, and its faces are chunks, not slabs across x. What it measures is the scheduler's
 * own: its bookkeeping, its messages' trips between cores, its rollbacks, its meetings. */
#include "nbep/calendar.h"
#include "nbep/warp.h"

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "build_info.h"
#include "warp_ring.h"

enum { SLABS_MAX = 16, MAX_REPEATS = 101 };

typedef struct {
    uint64_t *val;
    double *next;
    nbep_calendar *cal;
    uint64_t events;
    uint64_t sink; /* the padding's hashes, kept so that they are computed */
} world;

typedef struct {
    size_t sites, chunk;
    int slabs;
    unsigned work;
    world w[SLABS_MAX];
    nbep_warp *warp; /* NULL: the serial loop */
} model;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}


static int owner(const model *x, size_t k)
{
    return x->warp ? (int)((k / x->chunk) % (size_t)x->slabs) : 0;
}

static void keep(model *x, int slab, size_t item)
{
    if (!x->warp)
        return;
    const world *W = &x->w[slab];
    ring_state *s = nbep_warp_keep_room(x->warp, slab, (uint32_t)item);
    if (!s)
        abort();
    *s = item == x->sites ? (ring_state){W->events, 0.0} : (ring_state){W->val[item], W->next[item]};
}

static void send(model *x, int slab, int to, size_t item, ring_note n)
{
    if (!nbep_warp_send(x->warp, slab, to, (uint32_t)item, &n))
        abort();
}

static void set_own(model *x, int slab, size_t k, uint64_t v, double next)
{
    world *W = &x->w[slab];
    W->val[k] = v;
    W->next[k] = next;
    nbep_calendar_set(W->cal, (uint32_t)k, next, k);
}

static void send_copies(model *x, int slab, size_t k, int except)
{
    if (!x->warp)
        return;
    const size_t nb[2] = {(k + x->sites - 1) % x->sites, (k + 1) % x->sites};
    int sent = -1;
    for (int q = 0; q < 2; q++) {
        const int to = owner(x, nb[q]);
        if (to != slab && to != except && to != sent) {
            send(x, slab, to, k, (ring_note){x->w[slab].val[k], 0.0, RING_COPY});
            sent = to;
        }
    }
}

static void site_event(model *x, int slab, size_t k, double t)
{
    world *W = &x->w[slab];
    const size_t km = (k + x->sites - 1) % x->sites, kp = (k + 1) % x->sites;
    uint64_t v = ring_mix(W->val[km], W->val[k], W->val[kp], t);
    uint64_t pad = v;
    for (unsigned r = 0; r < x->work; r++)
        pad = ring_mix64(pad);
    W->sink += pad;
    keep(x, slab, x->sites);
    W->events++;
    keep(x, slab, k);
    set_own(x, slab, k, v, t + ring_gap(v));
    send_copies(x, slab, k, -1);
    if ((v & 3) != 0)
        return;
    const size_t q = (v & 4) ? kp : km;
    const uint64_t vq = ring_mix(v, W->val[q], RING_SALT, t);
    keep(x, slab, q);
    if (owner(x, q) == slab) {
        set_own(x, slab, q, vq, t + ring_gap(vq));
        send_copies(x, slab, q, -1);
    } else {
        W->val[q] = vq;
        send(x, slab, owner(x, q), q, (ring_note){vq, t + ring_gap(vq), RING_WRITE});
    }
}

static bool m_next(void *u, int slab, nbep_stamp *s)
{
    model *x = u;
    nbep_calendar_entry c;
    if (!nbep_calendar_first(x->w[slab].cal, &c))
        return false;
    *s = nbep_stamp_at(c.time, c.key, 0);
    return true;
}

static void m_handle(void *u, int slab, const nbep_stamp *s)
{
    site_event(u, slab, (size_t)s->level[0].key, s->t);
}

static void m_apply(void *u, int slab, int from, const nbep_stamp *s, uint32_t item,
                    const void *data)
{
    (void)s;
    model *x = u;
    ring_note n;
    memcpy(&n, data, sizeof n);
    keep(x, slab, item);
    if (n.kind == RING_WRITE) {
        set_own(x, slab, item, n.val, n.next);
        send_copies(x, slab, item, from);
    } else {
        x->w[slab].val[item] = n.val;
    }
}

static void m_restore(void *u, int slab, uint32_t item, const void *state)
{
    model *x = u;
    ring_state s;
    memcpy(&s, state, sizeof s);
    world *W = &x->w[slab];
    if (item == x->sites) {
        W->events = s.val;
        return;
    }
    W->val[item] = s.val;
    if (owner(x, item) == slab)
        set_own(x, slab, item, s.val, s.next);
}

static const nbep_warp_ops m_ops = {m_next, m_handle, m_apply, m_restore, NULL, NULL};

/* Every world at the start: the same sites; each slab's calendar of its own. */
static void start(model *x)
{
    for (int s = 0; s < x->slabs; s++) {
        world *W = &x->w[s];
        nbep_calendar_clear(W->cal);
        W->events = 0;
        for (size_t k = 0; k < x->sites; k++) {
            W->val[k] = ring_mix64(k);
            W->next[k] = ring_gap(W->val[k]);
            if (owner(x, k) == s)
                nbep_calendar_set(W->cal, (uint32_t)k, W->next[k], k);
        }
        nbep_calendar_retune(W->cal, 0.0);
    }
}

typedef struct {
    model *x;
    int slab;
    double window, t_end;
    pthread_barrier_t *bar;
} slab_thread;

static void *slab_main(void *arg)
{
    slab_thread *t = arg;
    const long windows = (long)(t->t_end / t->window + 0.5);
    for (long k = 1; k <= windows; k++) {
        if (t->slab == 0)
            nbep_warp_open(t->x->warp, t->t_end * (double)k / (double)windows);
        pthread_barrier_wait(t->bar);
        while (!nbep_warp_run(t->x->warp, t->slab, SIZE_MAX))
            ;
        pthread_barrier_wait(t->bar);
    }
    return NULL;
}

static double run_serial(model *x, double t_end)
{
    x->warp = NULL;
    const int slabs = x->slabs;
    x->slabs = 1;
    start(x);
    const double t0 = now();
    nbep_calendar_entry c;
    while (nbep_calendar_first(x->w[0].cal, &c) && c.time < t_end)
        site_event(x, 0, (size_t)c.key, c.time);
    const double dt = now() - t0;
    x->slabs = slabs;
    return dt;
}

static double run_warp(model *x, nbep_warp *w, double window, double t_end)
{
    x->warp = w;
    start(x);
    pthread_barrier_t bar;
    pthread_barrier_init(&bar, NULL, (unsigned)x->slabs);
    slab_thread th[SLABS_MAX];
    pthread_t id[SLABS_MAX];
    const double t0 = now();
    for (int s = 0; s < x->slabs; s++) {
        th[s] = (slab_thread){x, s, window, t_end, &bar};
        if (pthread_create(&id[s], NULL, slab_main, &th[s]) != 0)
            abort();
    }
    for (int s = 0; s < x->slabs; s++)
        pthread_join(id[s], NULL);
    const double dt = now() - t0;
    pthread_barrier_destroy(&bar);
    return dt;
}

int main(int argc, char **argv)
{
    model x = {0};
    x.sites = argc > 1 ? strtoul(argv[1], NULL, 10) : 200000;
    x.slabs = argc > 2 ? atoi(argv[2]) : 2;
    x.chunk = argc > 3 ? strtoul(argv[3], NULL, 10) : 64;
    const double window = argc > 4 ? atof(argv[4]) : 0.02;
    x.work = argc > 5 ? (unsigned)atoi(argv[5]) : 150;
    const double t_end = argc > 6 ? atof(argv[6]) : 2.0;
    const int repeats = argc > 7 ? atoi(argv[7]) : 5;
    if (x.sites < 4 || x.sites > UINT32_MAX / 2 || x.slabs < 1 || x.slabs > SLABS_MAX ||
        x.chunk < 1 || !(window > 0.0) || !(t_end > 0.0) || repeats < 1 ||
        repeats > MAX_REPEATS) {
        fprintf(stderr, "usage: bench_warp [sites [slabs (1 to %d) [chunk [window [work [t_end "
                        "[repeats]]]]]]]\n",
                SLABS_MAX);
        return 2;
    }
    nbep_diag d;
    nbep_diag_init(&d);
    uint64_t *ref = malloc(x.sites * sizeof *ref);
    for (int s = 0; s < x.slabs; s++) {
        x.w[s].val = malloc(x.sites * sizeof *x.w[s].val);
        x.w[s].next = malloc(x.sites * sizeof *x.w[s].next);
        if (!ref || !x.w[s].val || !x.w[s].next ||
            nbep_calendar_create(x.sites, &x.w[s].cal, &d) != NBEP_OK) {
            fprintf(stderr, "bench_warp: no memory\n");
            return 1;
        }
    }
    nbep_warp *w = NULL;
    if (nbep_warp_create(x.slabs, sizeof(ring_state), sizeof(ring_note), 1024, &m_ops, &x, &w, &d) !=
        NBEP_OK) {
        nbep_diag_print(&d, stderr);
        return 1;
    }
    printf("# bench_warp: %zu sites in chunks of %zu, %d slabs, windows of %g, %u hash rounds an "
           "event, to t = %g, %d repeats (%s)\n",
           x.sites, x.chunk, x.slabs, window, x.work, t_end, repeats, NBEP_BUILD_COMMIT);
    double ts[MAX_REPEATS], tw[MAX_REPEATS], ratio[MAX_REPEATS];
    uint64_t events = 0;
    for (int r = 0; r < repeats; r++) {
        ts[r] = run_serial(&x, t_end);
        events = x.w[0].events;
        memcpy(ref, x.w[0].val, x.sites * sizeof *ref);
        tw[r] = run_warp(&x, w, window, t_end);
        ratio[r] = ts[r] / tw[r];
        uint64_t got = 0;
        for (int s = 0; s < x.slabs; s++)
            got += x.w[s].events;
        for (size_t k = 0; k < x.sites; k++)
            if (x.w[owner(&x, k)].val[k] != ref[k] || got != events) {
                fprintf(stderr, "bench_warp: site %zu (or the count of events) differs from the "
                                "serial run\n",
                        k);
                return 1;
            }
    }
    nbep_warp_tally all = {0};
    for (int s = 0; s < x.slabs; s++) {
        const nbep_warp_tally t = nbep_warp_tally_of(w, s);
        all.rollbacks += t.rollbacks;
        all.undone += t.undone;
        all.sent += t.sent;
    }
    const double per = (double)events * repeats;
    printf("# every scheduled run the serial one's, bit for bit; the ratio: serial time over "
           "scheduled, per repeat's median\n");
    printf("slabs,events,serial_s,scheduled_s,speedup,rollbacks_per_event,undone_per_event,"
           "messages_per_event\n");
    printf("%d,%llu,%.4f,%.4f,%.3f,%.4f,%.4f,%.4f\n", x.slabs, (unsigned long long)events,
           bench_median(ts, repeats), bench_median(tw, repeats), bench_median(ratio, repeats),
           (double)all.rollbacks / per, (double)all.undone / per, (double)all.sent / per);
    fprintf(stderr, "# (padding sink %llu)\n", (unsigned long long)(x.w[0].sink & 1));
    nbep_warp_destroy(&w);
    for (int s = 0; s < x.slabs; s++) {
        free(x.w[s].val);
        free(x.w[s].next);
        nbep_calendar_destroy(&x.w[s].cal);
    }
    free(ref);
    nbep_diag_fini(&d);
    return 0;
}
