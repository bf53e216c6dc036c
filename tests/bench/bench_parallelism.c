/* How much parallelism an exact run's events allow: bin/nbep itself (src/main.c), with its own
 * copy of src/evloop.c in which every event handled (cells mode, one thread: the events in
 * the calendar's order) reports what it read and wrote. Each event is a node of a graph whose
 * edges run from the last event that wrote what it reads or writes; the longest chain of
 * events (the critical path) is the least number of event times that any exact scheme, however
 * many threads it has and however it schedules them, needs for the run, so events / chain is
 * the most it could gain over one thread, at one event's cost a time (README, Benchmarks, Dense
 * fluids, *What the events allow*). Two bounds: with the edges of true dependences alone (a
 * read after a write, a write after a write: a scheme that keeps versions of what it writes,
 * as an optimistic one may), and with a write after a read too (a scheme that writes in
 * place, as nbep's team does). Then the same with the box cut into regions, each region's
 * events handled in time order by one thread (REGIONS): the ceiling of a scheme that commits
 * by regions.
 *
 * What an event touches, as evloop.c handles it (each sphere's motion and slot M, each list L,
 * each cell C of the list centres):
 *   a contact (a fresh slot): reads M of its two spheres and, for every sphere it changed,
 *     that sphere's list L and the motion M of the list's members (the new prediction);
 *     writes M of every sphere it changed;
 *   a stale slot: reads M of its sphere and of the partner the slot names (the freshness
 *     check), L of its sphere and M of the list's members; writes M of its sphere;
 *   a list expiry: reads M of its sphere, its old list L and the cells C of the block its walk
 *     visits (their members and centres), M of the new list's members; writes M, L of its
 *     sphere, L of every neighbour it joins or leaves, the cell it leaves and the one it
 *     enters.
 *
 *   make build/bench/bench_parallelism
 *   build/bench/bench_parallelism run DECK --resume MELT.h5 -t 1 ...   (any nbep command line)
 *
 * The figures go to stderr at exit. Only with -t 1 (the events in the calendar's order; a team
 * handles them ahead and undoes some): another count is refused. Not for production: every
 * event does the bookkeeping.
 *
 * With NBEP_PAR_TRACE=FILE in the environment it also writes each event's record to FILE, for
 * scripts/optimistic-model.py: its time (f64), its list centre's place across x in the cells'
 * region (f64, 0 to 1), how far its footprint reaches from there, down and up (f64 each, the
 * list centres of the spheres whose motion or list it reads or writes, the nearest way round
 * a periodic x, in the same unit), its kind (u32: 1 an expiry, 2 a reaction, 0 a stale
 * slot), the count of events it depends on (u32) and their numbers (u32 each, from 0 in the
 * order handled): the last writer of each object it reads or writes (true dependences: the
 * writes after reads are left to versions, as an optimistic scheme keeps).
 *
 * Left out, so that the figures are a little optimistic: what a run does outside the events,
 * every sphere brought to the end of each step and the full rebuild of lists, slots and cells
 * at each frame (a review that added them as nodes, on 2744 spheres at dt = 0.05 with a frame
 * every 10 steps, found the path 2 % longer with true dependences and 5 % with writes after
 * reads); and the supports a held sphere's let-go reads (piles only, not fluids). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct nbep_evloop;
struct evl_ws;
static void dag_event(const struct nbep_evloop *e, const struct evl_ws *w, const void *ev);
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) dag_event(e, w, ev)
#include "../../src/evloop.c"
#include "../../src/evloop_team.c"
#include "../../src/main.c"

/* Regions, each with one thread that handles its events in time order (the event's region:
 * where its sphere's list centre lies), the events still waiting for what they read or write
 * as above (writes after reads too): how far a scheme that commits by regions could go with
 * perfect knowledge of what crosses their edges. Slabs across x, and blocks. */
#define N_MODELS 7
static const int REGIONS[N_MODELS][3] = {{1, 1, 1}, {2, 1, 1}, {4, 1, 1}, {8, 1, 1},
                                          {16, 1, 1}, {2, 2, 4}, {4, 4, 4}};

/* The graph's state: for each object (M of sphere k at k, L at n + k, cell c at 2 n + c), the
 * depth of the event that last wrote it, in each model, and (write-after-read model) the
 * deepest event that read it since. */
static struct {
    size_t n, objects;
    uint32_t *wd, *wd_war, *rd_war;
    uint32_t *reads, *writes; /* one event's objects */
    size_t n_reads, n_writes, cap;
    uint64_t events;
    uint32_t depth, depth_war;
    /* the region models (REGIONS): per model, the write-after-read model's depths and each
     * region's last event */
    uint32_t *wd_reg[N_MODELS], *rd_reg[N_MODELS], *last_reg[N_MODELS], depth_reg[N_MODELS];
    double t_first, t_last;
    bool started, failed;
    /* NBEP_PAR_TRACE: the file, each object's last writer (event number + 1, 0 for none) and
     * one event's distinct writers */
    FILE *trace;
    uint32_t *writer, *deps;
    size_t n_deps, deps_cap;
} dag;

static void dag_report(void)
{
    if (dag.failed) {
        fprintf(stderr, "bench_parallelism: no memory for the graph\n");
        return;
    }
    if (!dag.events)
        return;
    for (int m = 0; m < N_MODELS; m++) {
        fprintf(stderr, "bench_parallelism: regions %dx%dx%d: path %u events, events / path %.1f\n",
                REGIONS[m][0], REGIONS[m][1], REGIONS[m][2], dag.depth_reg[m],
                (double)dag.events / dag.depth_reg[m]);
        free(dag.wd_reg[m]);
        free(dag.rd_reg[m]);
        free(dag.last_reg[m]);
    }
    fprintf(stderr,
            "bench_parallelism: %llu events from t = %.6g to %.6g; critical path %u events "
            "(true dependences: events / path = %.1f), %u with writes after reads too (%.1f); "
            "path per unit of time %.1f and %.1f\n",
            (unsigned long long)dag.events, dag.t_first, dag.t_last, dag.depth,
            (double)dag.events / dag.depth, dag.depth_war, (double)dag.events / dag.depth_war,
            dag.depth / (dag.t_last - dag.t_first), dag.depth_war / (dag.t_last - dag.t_first));
    free(dag.wd);
    free(dag.wd_war);
    free(dag.rd_war);
    free(dag.reads);
    free(dag.writes);
    if (dag.trace && fclose(dag.trace) != 0)
        fprintf(stderr, "bench_parallelism: the trace could not be written\n");
    free(dag.writer);
    free(dag.deps);
}

static void dag_start(const nbep_evloop *e)
{
    if (e->team != 1) {
        fprintf(stderr, "bench_parallelism: run it with -t 1 (the events in the calendar's "
                        "order)\n");
        exit(2);
    }
    dag.started = true;
    dag.n = e->n;
    dag.objects = 2 * e->n + e->cells.n_cells;
    dag.cap = 1024;
    dag.wd = calloc(dag.objects, sizeof *dag.wd);
    dag.wd_war = calloc(dag.objects, sizeof *dag.wd_war);
    dag.rd_war = calloc(dag.objects, sizeof *dag.rd_war);
    dag.reads = malloc(dag.cap * sizeof *dag.reads);
    dag.writes = malloc(dag.cap * sizeof *dag.writes);
    atexit(dag_report);
    dag.failed = !dag.wd || !dag.wd_war || !dag.rd_war || !dag.reads || !dag.writes;
    const char *tr = getenv("NBEP_PAR_TRACE");
    if (tr && *tr) { /* after the line above, which would forget a failed open */
        dag.trace = fopen(tr, "wb");
        if (!dag.trace) {
            fprintf(stderr, "bench_parallelism: cannot write the trace %s\n", tr);
            exit(2);
        }
        dag.writer = calloc(dag.objects, sizeof *dag.writer);
        dag.failed |= !dag.writer;
    }
    for (int m = 0; m < N_MODELS; m++) {
        dag.wd_reg[m] = calloc(dag.objects, sizeof *dag.wd_reg[m]);
        dag.rd_reg[m] = calloc(dag.objects, sizeof *dag.rd_reg[m]);
        dag.last_reg[m] = calloc((size_t)REGIONS[m][0] * REGIONS[m][1] * REGIONS[m][2],
                                 sizeof *dag.last_reg[m]);
        dag.failed |= !dag.wd_reg[m] || !dag.rd_reg[m] || !dag.last_reg[m];
    }
}

/* Appends x to one event's list (reads or writes, sharing the capacity: both grow at once). */
static void dag_add(uint32_t **list, size_t *len, uint32_t x)
{
    if (*len == dag.cap) {
        uint32_t *r = realloc(dag.reads, 2 * dag.cap * sizeof *r);
        if (r)
            dag.reads = r;
        uint32_t *w = r ? realloc(dag.writes, 2 * dag.cap * sizeof *w) : NULL;
        if (w)
            dag.writes = w;
        if (!w) {
            dag.failed = true;
            return;
        }
        dag.cap *= 2;
    }
    (*list)[(*len)++] = x;
}

static void read_obj(uint32_t x)
{
    dag_add(&dag.reads, &dag.n_reads, x);
}

static void write_obj(uint32_t x)
{
    dag_add(&dag.writes, &dag.n_writes, x);
}

/* The prediction of sphere k from list js[0..m): its list and its members' motion. */
static void read_prediction(uint32_t k, const uint32_t *js, size_t m)
{
    read_obj((uint32_t)dag.n + k);
    for (size_t q = 0; q < m; q++)
        read_obj(js[q]);
}

static void read_list_of(const nbep_evloop *e, uint32_t k)
{
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, k, &m);
    read_prediction(k, js, m);
}

static uint32_t cell_obj(size_t c)
{
    return (uint32_t)(2 * dag.n + c);
}

/* One event's trace record (NBEP_PAR_TRACE): the distinct last writers of what it reads or
 * writes and how far across x their spheres' list centres lie (a cell's members are among
 * the spheres read), then it becomes the writer of what it writes. */
static void trace_event(const nbep_evloop *e, const evl_ws *w, uint32_t i, double t)
{
    const size_t need = dag.n_reads + dag.n_writes;
    if (need > dag.deps_cap) {
        uint32_t *d = realloc(dag.deps, 2 * need * sizeof *d);
        if (!d) {
            dag.failed = true;
            return;
        }
        dag.deps = d;
        dag.deps_cap = 2 * need;
    }
    uint32_t *d = dag.deps;
    dag.n_deps = 0;
    const double width = e->cells.hi.x - e->cells.lo.x;
    const nbep_vec3 ci = e->cells.m[i].at;
    double reach[2] = {0.0, 0.0};
    for (size_t k = 0; k < need; k++) {
        const uint32_t x = k < dag.n_reads ? dag.reads[k] : dag.writes[k - dag.n_reads];
        const uint32_t by = dag.writer[x];
        bool seen = by == 0;
        for (size_t q = 0; q < dag.n_deps && !seen; q++)
            seen = d[q] == by - 1;
        if (!seen)
            d[dag.n_deps++] = by - 1;
        if (x < 2 * dag.n) { /* a sphere's motion or list */
            const nbep_vec3 dc = nbep_vec3_sub(e->cells.m[x % dag.n].at, ci);
            const double dx = nbep_periodic_image(&e->pb, dc).x / width;
            reach[0] = dx < reach[0] ? dx : reach[0];
            reach[1] = dx > reach[1] ? dx : reach[1];
        }
    }
    const double at = (ci.x - e->cells.lo.x) / width;
    const uint32_t kind = w->rebuilt ? 1u : w->reacted ? 2u : 0u, nd = (uint32_t)dag.n_deps;
    if (fwrite(&t, sizeof t, 1, dag.trace) != 1 || fwrite(&at, sizeof at, 1, dag.trace) != 1 ||
        fwrite(reach, sizeof reach, 1, dag.trace) != 1 ||
        fwrite(&kind, sizeof kind, 1, dag.trace) != 1 ||
        fwrite(&nd, sizeof nd, 1, dag.trace) != 1 ||
        fwrite(d, sizeof *d, dag.n_deps, dag.trace) != dag.n_deps)
        dag.failed = true;
    for (size_t k = 0; k < dag.n_writes; k++)
        dag.writer[dag.writes[k]] = (uint32_t)dag.events + 1;
}

/* Event of sphere i in region model m (dag's reads and writes set). */
static void region_model(const nbep_evloop *e, uint32_t i, int m)
{
    const nbep_vec3 at = e->cells.m[i].at;
    const double c[3] = {at.x, at.y, at.z};
    const double lo[3] = {e->cells.lo.x, e->cells.lo.y, e->cells.lo.z};
    const double hi[3] = {e->cells.hi.x, e->cells.hi.y, e->cells.hi.z};
    size_t r = 0;
    for (int k = 2; k >= 0; k--) {
        const int s = REGIONS[m][k];
        double f = floor((c[k] - lo[k]) / (hi[k] - lo[k]) * s);
        f = f < 0.0 ? 0.0 : f > s - 1 ? s - 1 : f;
        r = r * (size_t)s + (size_t)f;
    }
    uint32_t *wd = dag.wd_reg[m], *rd = dag.rd_reg[m];
    uint32_t d = dag.last_reg[m][r];
    for (size_t k = 0; k < dag.n_reads; k++)
        d = wd[dag.reads[k]] > d ? wd[dag.reads[k]] : d;
    for (size_t k = 0; k < dag.n_writes; k++) {
        const uint32_t x = dag.writes[k];
        d = wd[x] > d ? wd[x] : d;
        d = rd[x] > d ? rd[x] : d;
    }
    d++;
    for (size_t k = 0; k < dag.n_reads; k++)
        rd[dag.reads[k]] = d > rd[dag.reads[k]] ? d : rd[dag.reads[k]];
    for (size_t k = 0; k < dag.n_writes; k++) {
        wd[dag.writes[k]] = d;
        rd[dag.writes[k]] = 0;
    }
    dag.last_reg[m][r] = d;
    dag.depth_reg[m] = d > dag.depth_reg[m] ? d : dag.depth_reg[m];
}

static void dag_event(const nbep_evloop *e, const evl_ws *w, const void *evp)
{
    const nbep_event *ev = evp;
    if (!dag.started)
        dag_start(e);
    if (dag.failed)
        return;
    dag.n_reads = dag.n_writes = 0;
    const uint32_t i = w->item;
    read_obj(i);
    write_obj(i);
    if (w->rebuilt) {
        read_prediction(i, w->near, w->n_near);
        read_list_of(e, i); /* the old list */
        write_obj((uint32_t)dag.n + i);
        for (size_t k = 0; k < w->n_near; k++)
            if (w->gain[k])
                write_obj((uint32_t)dag.n + w->near[k]);
        for (size_t k = 0; k < w->n_was; k++)
            if (!w->kept[k])
                write_obj((uint32_t)dag.n + w->was[k]);
        const size_t to = nbep_cells_locate(&e->cells, w->at);
        nbep_cells_block b;
        nbep_cells_block_of(&e->cells, to, &b);
        for (int z = 0; z < b.cnt[2]; z++)
            for (int y = 0; y < b.cnt[1]; y++)
                for (int x = 0; x < b.cnt[0]; x++)
                    read_obj(cell_obj(nbep_cells_index(&e->cells, b.idx[0][x], b.idx[1][y],
                                                       b.idx[2][z])));
        write_obj(cell_obj(e->cells.m[i].cell));
        write_obj(cell_obj(to));
    } else {
        if (ev->kind == NBEP_EVENT_SPHERE)
            read_obj(ev->partner);
        for (size_t k = 0; k < w->n_changed; k++) {
            write_obj(w->changed[k]);
            read_list_of(e, w->changed[k]);
        }
        read_list_of(e, i);
    }
    if (dag.failed)
        return;
    uint32_t d = 0, dw = 0;
    for (size_t k = 0; k < dag.n_reads; k++) {
        const uint32_t x = dag.reads[k];
        d = dag.wd[x] > d ? dag.wd[x] : d;
        dw = dag.wd_war[x] > dw ? dag.wd_war[x] : dw;
    }
    for (size_t k = 0; k < dag.n_writes; k++) {
        const uint32_t x = dag.writes[k];
        d = dag.wd[x] > d ? dag.wd[x] : d;
        dw = dag.wd_war[x] > dw ? dag.wd_war[x] : dw;
        dw = dag.rd_war[x] > dw ? dag.rd_war[x] : dw;
    }
    d++;
    dw++;
    for (size_t k = 0; k < dag.n_reads; k++) {
        const uint32_t x = dag.reads[k];
        dag.rd_war[x] = dw > dag.rd_war[x] ? dw : dag.rd_war[x];
    }
    for (size_t k = 0; k < dag.n_writes; k++) {
        const uint32_t x = dag.writes[k];
        dag.wd[x] = d;
        dag.wd_war[x] = dw;
        dag.rd_war[x] = 0;
    }
    for (int m = 0; m < N_MODELS; m++)
        region_model(e, i, m);
    if (dag.trace)
        trace_event(e, w, i, ev->time);
    dag.depth = d > dag.depth ? d : dag.depth;
    dag.depth_war = dw > dag.depth_war ? dw : dag.depth_war;
    if (!dag.events)
        dag.t_first = ev->time;
    dag.t_last = ev->time;
    dag.events++;
}
