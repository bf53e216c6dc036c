/* A run: set-up, the end-of-step hook shared by every algorithm (counters, energy, stats rows,
 * frames, progress, stop requests) and the summary. The algorithms (algo_*.c) own the
 * parallel region; this file holds no OpenMP pragmas. */
#include "nbep/sim.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "nbep/physics.h"
#include "sim_impl.h"

/* Stats rows are written to the file in batches of this many (and at every frame). */
#define ROWS_BATCH 4096
/* Progress: a live line on a terminal this often, a plain line otherwise this often. */
#define PROGRESS_TTY_SECONDS 0.25
#define PROGRESS_LOG_SECONDS 10.0

int nbep__thread_id(void)
{
#ifdef _OPENMP
    return omp_get_thread_num();
#else
    return 0;
#endif
}

int nbep_sim_resolve_threads(int requested)
{
#ifdef _OPENMP
    /* omp_get_max_threads honours OMP_NUM_THREADS and defaults to the available cores; no
     * region gets more than the thread limit (OMP_THREAD_LIMIT) nor NBEP_THREADS_MAX (the
     * deck's limit, which OMP_NUM_THREADS does not pass either) */
    int n = requested > 0 ? requested : omp_get_max_threads();
    const int cap = omp_get_thread_limit();
    const int limit = cap > 0 && cap < NBEP_THREADS_MAX ? cap : NBEP_THREADS_MAX;
    if (limit > 0 && n > limit)
        n = limit;
    return n > 0 ? n : 1;
#else
    (void)requested; /* a serial build (make OMP=0) runs one thread whatever was asked */
    return 1;
#endif
}

/* The threads that a parallel region asking for n gets, and then every later one. Every
 * algorithm's threads meet at barriers sized for the run's count, so the count must be what
 * OpenMP gives: fewer under OMP_DYNAMIC=true (it may choose at will: turned off here, nbep's
 * regions are its own) or inside a parallel region of a caller's (nested, one thread). The run
 * takes what it gets: results do not depend on it. */
static int team_size(int n)
{
#ifdef _OPENMP
    omp_set_dynamic(0);
    int got = 1;
#pragma omp parallel num_threads(n) default(none) shared(got)
    {
#pragma omp single
        got = omp_get_num_threads();
    }
    return got;
#else
    return n;
#endif
}

/* The algorithm table: the entry of the scene's run.algorithm, NULL for an unknown name. */
static const nbep_algo *find_algo(const char *name)
{
    static const nbep_algo *const table[] = {&nbep__algo_naive, &nbep__algo_seminaive,
                                             &nbep__algo_predictive};
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (strcmp(table[i]->name, name) == 0)
            return table[i];
    return NULL;
}

nbep_status nbep_sim_stop_status(const atomic_int *stop)
{
    return nbep_status_of_stop(stop);
}

bool nbep_sim_keeps_events(const nbep_scene *sc)
{
    const nbep_algo *algo = find_algo(sc->algorithm);
    return algo && algo->export_events;
}

bool nbep_sim_keeps_contacts(const nbep_scene *sc)
{
    const nbep_algo *algo = find_algo(sc->algorithm);
    return algo && algo->keeps_contacts && algo->keeps_contacts(sc, &sc->state);
}

bool nbep_sim_settle_speeds(const nbep_scene *sc, double *lo, double *hi, unsigned *steps)
{
    const nbep_algo *algo = find_algo(sc->algorithm);
    return algo && algo->settle_speeds && algo->settle_speeds(sc, lo, hi, steps);
}

bool nbep_sim_lasting(const nbep_sim *sim)
{
    return sim->lasting;
}

/* The bytes nbep_sim_create allocates beside the state and the algorithm's part, for a run of
 * n spheres and np planes on nt threads with algo, out: with an output file (keep in step with
 * nbep_sim_create): counters and sums per thread, energies per block, a batch of stats rows,
 * the frames' overlap grid of an algorithm whose overlap is not exact, and the event slots
 * exported at frames. */
static size_t sim_own_bytes(const nbep_algo *algo, size_t n, size_t np, int nt, bool out)
{
    const nbep_sim *sim = NULL; /* for element sizes only: sizeof does not evaluate */
    const size_t blocks = (n + NBEP_BLOCK - 1) / NBEP_BLOCK;
    size_t bytes = sizeof *sim +
                   2 * (size_t)nt *
                       (sizeof *sim->counters[0] + sizeof *sim->tmax[0] +
                        np * sizeof *sim->wall_buf[0]) +
                   blocks * (sizeof *sim->block_ke + sizeof *sim->block_pe) +
                   ROWS_BATCH * (sizeof *sim->rows + np * sizeof *sim->wall_rows);
    if (!algo->exact_overlap)
        bytes += nbep_grid_bytes(n);
    if (out && algo->export_events)
        bytes += n * (sizeof *sim->ev_time + sizeof *sim->ev_partner + sizeof *sim->ev_kind +
                      sizeof *sim->ev_rest);
    return bytes;
}

size_t nbep_sim_memory_estimate(const nbep_scene *sc, int threads)
{
    const size_t n = sc->state.n, np = sc->state.n_planes;
    size_t bytes = nbep_state_bytes(n, np); /* the scene's, which nbep run hands over */
    const nbep_algo *algo = find_algo(sc->algorithm);
    if (algo) /* what the run and its algorithm allocate, counted beside their allocations */
        bytes += sim_own_bytes(algo, n, np, threads, true) + algo->bytes(sc, threads);
    bytes += n * 2 * sizeof(nbep_vec3); /* one frame in flight in HDF5's buffers */
    return bytes;
}

void nbep_sim_threads_use(const nbep_scene *sc, int threads, char *buf, size_t len)
{
    const nbep_algo *algo = find_algo(sc->algorithm);
    if (threads < 2 || !algo)
        snprintf(buf, len, "one does everything");
    else
        algo->threads_use(sc, threads, buf, len);
}

nbep_range nbep__range_split(size_t n, int tid, int nt)
{
    size_t blocks = (n + NBEP_BLOCK - 1) / NBEP_BLOCK;
    size_t b_lo = blocks * (size_t)tid / (size_t)nt;
    size_t b_hi = blocks * (size_t)(tid + 1) / (size_t)nt;
    nbep_range r = {b_lo * NBEP_BLOCK, b_hi * NBEP_BLOCK};
    if (r.lo > n)
        r.lo = n;
    if (r.hi > n)
        r.hi = n;
    return r;
}

void nbep__sim_block_energy(nbep_sim *sim, nbep_range own)
{
    for (size_t lo = own.lo; lo < own.hi; lo += NBEP_BLOCK) {
        size_t hi = lo + NBEP_BLOCK < own.hi ? lo + NBEP_BLOCK : own.hi;
        nbep_physics_energy(&sim->st, lo, hi, &sim->block_ke[lo / NBEP_BLOCK],
                            &sim->block_pe[lo / NBEP_BLOCK]);
    }
}

static void energy_total(const nbep_sim *sim, double *ke, double *pe)
{
    double k = 0.0, p = 0.0;
    for (size_t b = 0; b < sim->n_blocks; b++) { /* fixed order: same bits for any nt */
        k += sim->block_ke[b];
        p += sim->block_pe[b];
    }
    *ke = k;
    *pe = p;
}

/* The run's totals as a frame keeps them (/frames/totals), and back: the counters and sums the
 * summary reports, from step 0 (take_totals, a resumed run's from its frame's). */
static nbep_run_totals give_totals(const nbep_sim *sim)
{
    return (nbep_run_totals){
        .checks = sim->totals[NBEP_COUNTER_CHECKS],
        .predictions = sim->totals[NBEP_COUNTER_PREDICTIONS],
        .sphere_collisions = sim->totals[NBEP_COUNTER_SPHERE_COLLISIONS],
        .plane_collisions = sim->totals[NBEP_COUNTER_PLANE_COLLISIONS],
        .quiet_steps = sim->quiet_steps,
        .energy_initial = sim->energy_initial,
        .max_overlap = sim->max_overlap,
        .max_overlap_rel = sim->max_overlap_rel,
        .virial = sim->virial_total,
        .kinetic_energy = sim->ke_total,
    };
}

static void take_totals(nbep_sim *sim, const nbep_run_totals *t)
{
    sim->totals[NBEP_COUNTER_CHECKS] = t->checks;
    sim->totals[NBEP_COUNTER_PREDICTIONS] = t->predictions;
    sim->totals[NBEP_COUNTER_SPHERE_COLLISIONS] = t->sphere_collisions;
    sim->totals[NBEP_COUNTER_PLANE_COLLISIONS] = t->plane_collisions;
    sim->quiet_steps = t->quiet_steps;
    sim->energy_initial = t->energy_initial;
    sim->max_overlap = t->max_overlap;
    sim->max_overlap_rel = t->max_overlap_rel;
    sim->virial_total = t->virial;
    sim->ke_total = t->kinetic_energy;
}

nbep_status nbep_sim_create(const nbep_scene *sc, const nbep_sim_options *opt, nbep_sim **out,
                            nbep_diag *d)
{
    double t0 = opt->t_begin > 0.0 ? opt->t_begin : nbep_now();
    const nbep_algo *algo = find_algo(sc->algorithm);
    if (!algo)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: unknown algorithm '%s'", sc->algorithm);
    nbep_sim *sim = calloc(1, sizeof *sim);
    if (!sim)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for a run");
    sim->scene = sc;
    sim->opt = *opt;
    sim->nt = team_size(nbep_sim_resolve_threads(opt->threads)); /* resolved already */
    sim->step_first = opt->resume ? (uint64_t)opt->resume->step + 1 : 1;
    sim->resumed = opt->resume != NULL;
    sim->step_end = sc->steps;
    sim->dt = sc->dt;
    sim->algo = algo;
    atomic_init(&sim->stop, 0);
    assert(!opt->take_state || opt->take_state == &sc->state);
    nbep_status st = NBEP_OK;
    if (opt->take_state)
        nbep_state_take(&sim->st, opt->take_state);
    else
        st = nbep_state_copy(&sim->st, &sc->state, d);
    if (st != NBEP_OK) {
        free(sim);
        return st;
    }
    size_t n = sim->st.n;
    /* a resumed frame's positions, velocities and images are in the scene's state already */
    assert(!opt->resume || (!opt->resume->pos && !opt->resume->vel && !opt->resume->image));
    /* what follows, sim_own_bytes counts for nbep check (keep the two in step) */
    sim->n_blocks = (n + NBEP_BLOCK - 1) / NBEP_BLOCK;
    for (int k = 0; k < 2; k++) {
        sim->counters[k] = nbep_alloc_aligned((size_t)sim->nt, sizeof *sim->counters[k]);
        sim->tmax[k] = nbep_alloc_aligned((size_t)sim->nt, sizeof *sim->tmax[k]);
    }
    sim->block_ke = nbep_alloc_aligned(sim->n_blocks, sizeof *sim->block_ke);
    sim->block_pe = nbep_alloc_aligned(sim->n_blocks, sizeof *sim->block_pe);
    sim->cap_rows = ROWS_BATCH;
    sim->rows = malloc(sim->cap_rows * sizeof *sim->rows);
    const size_t np = sim->st.n_planes;
    sim->wall_rows = nbep_alloc_aligned(sim->cap_rows * np, sizeof *sim->wall_rows);
    for (int k = 0; k < 2; k++)
        sim->wall_buf[k] = nbep_alloc_aligned((size_t)sim->nt * np, sizeof *sim->wall_buf[k]);
    if (!sim->counters[0] || !sim->counters[1] || !sim->tmax[0] || !sim->tmax[1] ||
        !sim->block_ke || !sim->block_pe || !sim->rows || !sim->wall_rows ||
        !sim->wall_buf[0] || !sim->wall_buf[1]) {
        nbep_sim_destroy(&sim);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the run's counters");
    }
    for (int k = 0; k < 2; k++)
        for (int t = 0; t < sim->nt; t++)
            sim->tmax[k][t].wall = sim->wall_buf[k] + (size_t)t * np;
    st = algo->create(sim, &sim->algo_ctx, d);
    if (st != NBEP_OK) {
        nbep_sim_destroy(&sim);
        return st;
    }
    if (!algo->exact_overlap) {
        st = nbep_grid_init(&sim->overlap_grid, n, d);
        if (st != NBEP_OK) {
            nbep_sim_destroy(&sim);
            return st;
        }
    }
    /* a frame at step 0 holds the slots of the first predictions, which the run makes again
     * from the same state as the uninterrupted run did, counting them in step 1's row as it
     * did (imported, step 1's checks and predictions came out n and n - 1 short) */
    if (opt->resume && opt->resume->has_events && opt->resume->step > 0 && algo->import_events)
        algo->import_events(sim->algo_ctx, opt->resume);
    const bool go_on = opt->resume && opt->resume->has_totals;
    if (go_on) /* the summary goes on from the frame's totals (energy_initial below) */
        take_totals(sim, &opt->resume->totals);
    sim->sums_first = go_on ? 1 : sim->step_first;
    sim->opt.resume = NULL; /* read: borrowed for nbep_sim_create only */
    sim->lasting = algo->keeps_contacts && algo->keeps_contacts(sc, &sim->st);
    if (opt->out && algo->export_events) {
        sim->ev_time = nbep_alloc_aligned(n, sizeof *sim->ev_time);
        sim->ev_partner = nbep_alloc_aligned(n, sizeof *sim->ev_partner);
        sim->ev_kind = nbep_alloc_aligned(n, sizeof *sim->ev_kind);
        sim->ev_rest = nbep_alloc_aligned(n, sizeof *sim->ev_rest);
        if (!sim->ev_time || !sim->ev_partner || !sim->ev_kind || !sim->ev_rest) {
            nbep_sim_destroy(&sim);
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the run's checkpoints");
        }
    }
    nbep__sim_block_energy(sim, (nbep_range){0, n});
    double ke, pe;
    energy_total(sim, &ke, &pe);
    sim->energy_final = ke + pe;
    if (!go_on)
        sim->energy_initial = sim->energy_final;
    /* no deck within the window of magnitudes and the span (scene.h) gets here: a resumed
     * file's state or a scene built otherwise can */
    if (!isfinite(sim->energy_initial) || !isfinite(sim->energy_final)) {
        nbep_sim_destroy(&sim);
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: the spheres' total energy (kinetic %g, potential %g) is beyond doubles: "
                  "speeds, masses, accelerations or positions too large",
                  ke, pe);
    }
    sim->setup_seconds = nbep_now() - t0;
    *out = sim;
    return NBEP_OK;
}

void nbep_sim_destroy(nbep_sim **simp)
{
    if (!simp || !*simp)
        return;
    nbep_sim *sim = *simp;
    if (sim->algo && sim->algo_ctx)
        sim->algo->destroy(sim->algo_ctx);
    for (int k = 0; k < 2; k++) {
        nbep_free_aligned(sim->counters[k]);
        nbep_free_aligned(sim->tmax[k]);
    }
    nbep_free_aligned(sim->block_ke);
    nbep_free_aligned(sim->block_pe);
    nbep_free_aligned(sim->wall_rows);
    nbep_free_aligned(sim->wall_buf[0]);
    nbep_free_aligned(sim->wall_buf[1]);
    nbep_free_aligned(sim->ev_time);
    nbep_free_aligned(sim->ev_partner);
    nbep_free_aligned(sim->ev_kind);
    nbep_free_aligned(sim->ev_rest);
    nbep_grid_fini(&sim->overlap_grid);
    free(sim->rows);
    nbep_state_fini(&sim->st);
    free(sim);
    *simp = NULL;
}

uint64_t nbep_sim_counter(const nbep_sim *sim, int counter)
{
    return counter >= 0 && counter < NBEP_COUNTER_COUNT ? sim->totals[counter] : 0;
}

const nbep_state *nbep_sim_state(const nbep_sim *sim)
{
    return &sim->st;
}

static nbep_status flush_rows(nbep_sim *sim)
{
    if (sim->n_rows == 0)
        return NBEP_OK;
    nbep_status st = NBEP_OK;
    if (sim->opt.out && sim->scene->out_stats)
        st = nbep_output_stats(sim->opt.out, sim->rows, sim->wall_rows, sim->n_rows,
                               sim->diag);
    sim->n_rows = 0;
    if (st != NBEP_OK)
        sim->out_failed = true;
    return st;
}

static nbep_status emit_frame(nbep_sim *sim, uint64_t step)
{
    if (!nbep_state_all_finite(&sim->st))
        NBEP_FAIL(sim->diag, NBEP_ENUMERIC,
                  "nbep: a position or velocity became non-finite by step %llu; no frame "
                  "written for it",
                  (unsigned long long)step);
    nbep_status st = flush_rows(sim);
    if (st == NBEP_OK && sim->opt.out) {
        const nbep_run_totals t = give_totals(sim);
        nbep_output_totals(sim->opt.out, &t);
        nbep_events_view ev = {sim->ev_time, sim->ev_partner, sim->ev_kind, sim->ev_rest,
                               sim->lasting ? sim->algo->export_contacts : NULL,
                               sim->algo_ctx};
        if (sim->ev_time)
            sim->algo->export_events(sim->algo_ctx, &sim->st, sim->ev_time, sim->ev_partner,
                                     sim->ev_kind, sim->ev_rest);
        st = nbep_output_frame_events(sim->opt.out, (int64_t)step, sim->dt, &sim->st,
                                      sim->ev_time ? &ev : NULL, sim->diag);
        if (st != NBEP_OK)
            sim->out_failed = true;
    }
    if (st == NBEP_OK && sim->opt.on_frame)
        st = sim->opt.on_frame(sim->opt.on_frame_ctx, (int64_t)step, &sim->st, sim->diag);
    if (st == NBEP_OK)
        sim->frame_last = step;
    return st;
}

/* The stepping loop's clock starts at now, and the progress line's with it. */
static void clock_start(nbep_sim *sim, double now)
{
    sim->t_start = sim->t_last_progress = sim->t_mark = now;
    sim->done_mark = 0.0;
    sim->rate_recent = 0.0;
}

void nbep__sim_setup_done(nbep_sim *sim)
{
    const double now = nbep_now();
    sim->setup_seconds += now - sim->t_start;
    clock_start(sim, now);
}

/* One progress line: on a terminal over the live one, padded to the widest line shown so far
 * (a shorter one, as the ETA's digits go or the first predictions' line gives way to the
 * steps', leaves nothing of it behind), ended only when last; otherwise a line of its own. */
static void progress_print(nbep_sim *sim, const char *text, bool last)
{
    if (sim->tty) {
        const int len = (int)strlen(text);
        if (len > sim->tty_width)
            sim->tty_width = len;
        fprintf(stderr, "\r%-*s%s", sim->tty_width, text, last ? "\n" : "");
        sim->line_open = !last;
    } else {
        fprintf(stderr, "%s\n", text);
    }
}

/* The ETA of a line into buf: `seconds` to go, or "-" where there is no pace yet to go by
 * (known false: nothing done, which said "ETA 0 s" with every step to go). */
static const char *eta_text(double seconds, bool known, char buf[NBEP_DURATION_TEXT_MAX])
{
    return known ? nbep_format_duration(seconds, buf) : strcpy(buf, "-");
}

/* Whether a progress line is due now (a last one always is); if so, its time is now. */
static bool progress_due(nbep_sim *sim, double now, bool last)
{
    if (!sim->opt.progress)
        return false;
    double every = sim->tty ? PROGRESS_TTY_SECONDS : PROGRESS_LOG_SECONDS;
    if (!last && now - sim->t_last_progress < every)
        return false;
    sim->t_last_progress = now;
    return true;
}

/* The progress line at `at` steps of the run (a whole step at a step's end; within one, the
 * step before plus the part of its time gone, shown with two decimals: `step 2.47/100`). */
static void progress_at(nbep_sim *sim, double at, bool last)
{
    double now = nbep_now();
    if (!progress_due(sim, now, last))
        return;
    double el = now - sim->t_start;
    /* steps done in this session (a resumed run started at step_first) */
    const double done = at + 1.0 - (double)sim->step_first;
    double rate = el > 0.0 ? done / el : 0.0;
    /* the rate and ETA from the last PROGRESS_LOG_SECONDS or more once there are such, not
     * the whole run's mean: a pile that settles slows tenfold, and the mean's ETA said 13 s
     * with over 5 minutes to go (a user's review) */
    if (now - sim->t_mark >= PROGRESS_LOG_SECONDS) {
        sim->rate_recent = (done - sim->done_mark) / (now - sim->t_mark);
        sim->t_mark = now;
        sim->done_mark = done;
    }
    /* the finished run's line gives its mean, the rate its summary gives (it gave the rate of
     * the last whole window, up to PROGRESS_LOG_SECONDS old, and the two differed: a review) */
    const double to_go = (double)sim->step_end - at;
    if (sim->rate_recent > 0.0 && !(last && to_go <= 0.0))
        rate = sim->rate_recent;
    double pct = sim->step_end ? 100.0 * at / (double)sim->step_end : 100.0;
    /* no rate yet (nothing done: a run stopped during its first step) gives no ETA, "ETA -",
     * not "ETA 0 s" for a run with all its steps to go */
    char where[48], eta[NBEP_DURATION_TEXT_MAX], line[200];
    if (at == floor(at))
        snprintf(where, sizeof where, "%llu", (unsigned long long)at);
    else
        snprintf(where, sizeof where, "%.2f", at);
    /* a live line keeps its columns (the percentage in 5 places), a log line has no need */
    snprintf(line, sizeof line, "step %s/%llu  %*.1f%%  %.4g steps/s  ETA %s", where,
             (unsigned long long)sim->step_end, sim->tty ? 5 : 0, pct, rate,
             eta_text(rate > 0.0 ? to_go / rate : 0.0, rate > 0.0 || to_go <= 0.0, eta));
    progress_print(sim, line, last);
}

static void progress(nbep_sim *sim, uint64_t step, bool last)
{
    progress_at(sim, (double)step, last);
}

void nbep__sim_progress_part(nbep_sim *sim, uint64_t step, double part)
{
    /* at most 0.99: the line never shows the step's end (nor a NaN) before the step has
     * ended, and "%.2f" never rounds it up to it */
    const double at = (double)(step - 1) + (part > 0.0 ? fmin(part, 0.99) : 0.0);
    progress_at(sim, at, false);
}

void nbep__sim_progress_within(nbep_sim *sim, uint64_t step, double t)
{
    /* the part of the step's time gone */
    nbep__sim_progress_part(sim, step, (t - (double)(step - 1) * sim->dt) / sim->dt);
}

void nbep__sim_progress_setup(nbep_sim *sim, double part)
{
    const double now = nbep_now();
    if (!progress_due(sim, now, false))
        return;
    /* the run's clock started before them (nbep_sim_run; nbep__sim_setup_done restarts it) */
    const double el = now - sim->t_start;
    part = part > 0.0 ? fmin(part, 0.999) : 0.0; /* "%.1f": never 100 % before they are made */
    char eta[NBEP_DURATION_TEXT_MAX], line[96];
    snprintf(line, sizeof line, "first predictions %*.1f%%  ETA %s", sim->tty ? 5 : 0,
             100.0 * part, eta_text(part > 0.0 ? el * (1.0 - part) / part : 0.0, part > 0.0, eta));
    progress_print(sim, line, false);
}

void nbep__sim_abandon(nbep_sim *sim)
{
    sim->status = nbep_sim_stop_status(sim->opt.stop_signal);
    sim->abandoned = true;
}

bool nbep__sim_frame_due(const nbep_sim *sim, uint64_t step)
{
    return step % sim->scene->output_every == 0 || step == sim->step_end;
}

void nbep__sim_frame_overlap(nbep_sim *sim, uint64_t step, int tid, nbep_range own,
                             nbep_barrier *bar)
{
    /* frames at a multiple of output.every only: another (the last of a run.steps off that
     * grid) is measured by end_step apart from the row (see there) */
    if (sim->algo->exact_overlap || step % sim->scene->output_every != 0)
        return;
    nbep_barrier_wait(bar); /* every sphere at the step's end */
    if (tid == 0) {
        sim->overlap_rmax = nbep_state_overlap_grid(&sim->st, &sim->overlap_grid);
        sim->overlap_step = step;
    }
    nbep_barrier_wait(bar);
    nbep_overlap best = NBEP_OVERLAP_NONE;
    nbep_state_overlap_part(&sim->st, &sim->overlap_grid, sim->overlap_rmax, own.lo, own.hi,
                            &best);
    nbep_thread_max *m = &sim->tmax[step & 1][tid];
    m->overlap = fmax(m->overlap, best.max);
    m->overlap_rel = fmax(m->overlap_rel, best.rel);
}

int nbep__sim_end_step(nbep_sim *sim, uint64_t step)
{
    const int par = (int)(step & 1);
    nbep_step_stats row = {.step = (int64_t)step};
    uint64_t c[NBEP_COUNTER_COUNT] = {0};
    double ov = 0.0, ov_rel = 0.0;
    const size_t np = sim->st.n_planes;
    double *wall = sim->wall_rows + sim->n_rows * np;
    /* the threads' exact sums merged: the same for any split of the terms among threads */
    nbep_xsum virial = {.adds = 0};
    for (int t = 0; t < sim->nt; t++) {
        nbep_thread_max *tm = &sim->tmax[par][t];
        nbep_xsum_merge(&virial, &tm->virial);
        nbep_xsum_clear(&tm->virial);
    }
    row.virial = nbep_xsum_value(&virial);
    for (size_t p = 0; p < np; p++) {
        nbep_xsum w = {.adds = 0};
        for (int t = 0; t < sim->nt; t++) {
            nbep_xsum_merge(&w, &sim->tmax[par][t].wall[p]);
            nbep_xsum_clear(&sim->tmax[par][t].wall[p]);
        }
        wall[p] = nbep_xsum_value(&w);
    }
    for (int t = 0; t < sim->nt; t++) {
        for (int k = 0; k < NBEP_COUNTER_COUNT; k++) {
            c[k] += sim->counters[par][t].c[k];
            sim->counters[par][t].c[k] = 0;
        }
        ov = fmax(ov, sim->tmax[par][t].overlap);
        ov_rel = fmax(ov_rel, sim->tmax[par][t].overlap_rel);
        sim->tmax[par][t].overlap = sim->tmax[par][t].overlap_rel = 0.0;
    }
    energy_total(sim, &row.kinetic_energy, &row.potential_energy);
    /* A step whose energy or sums overflowed (no deck within the window of magnitudes and
     * the span, scene.h, gets here; a resumed file's state or a scene built otherwise can):
     * the run stops, with its message and status, as at the end of the step before: no row,
     * no frame and no totals of this step, so that nothing non-finite reaches the file or the
     * summary (which reports the last step written). */
    bool finite = isfinite(row.kinetic_energy + row.potential_energy) && isfinite(row.virial);
    for (size_t p = 0; p < np; p++)
        finite = finite && isfinite(wall[p]);
    if (!finite) {
        if (sim->status == NBEP_OK) {
            nbep_diag_add(sim->diag, __FILE__, __LINE__,
                          "nbep: the energy became non-finite at step %llu (a position or "
                          "velocity overflowed or is NaN); the file ends at the step before",
                          (unsigned long long)step);
            sim->status = NBEP_ENUMERIC;
        }
        progress(sim, step - 1, true);
        atomic_store_explicit(&sim->stop, 1, memory_order_relaxed); /* next barrier orders it */
        return 1;
    }
    for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
        sim->totals[k] += c[k];
    row.checks = c[NBEP_COUNTER_CHECKS];
    row.predictions = c[NBEP_COUNTER_PREDICTIONS];
    row.collisions = c[NBEP_COUNTER_SPHERE_COLLISIONS] + c[NBEP_COUNTER_PLANE_COLLISIONS];
    if (row.collisions == 0)
        sim->quiet_steps++;
    sim->energy_final = row.kinetic_energy + row.potential_energy;
    sim->virial_total += row.virial;
    sim->ke_total += row.kinetic_energy;
    sim->steps_done = step;

    const nbep_status stop_st = nbep_sim_stop_status(sim->opt.stop_signal);
    int stop = stop_st != NBEP_OK;
    if (stop)
        sim->status = stop_st;
    bool frame = nbep__sim_frame_due(sim, step) || stop;
    /* (the threads shared the check of a frame at a multiple of output.every:
     * nbep__sim_frame_overlap). A frame off that grid (a stop's own, or the last of a
     * run.steps off it) is checked here into the run's maxima but not into the step's row,
     * which then holds what the uninterrupted run's does: a resume keeps the row (until
     * 2026-11-30 it held that check too, and a hopper stopped at step 1606 in grid mode and
     * resumed had a /stats/max_overlap of 9.4e-16 where the uninterrupted run's is 4.0e-16). */
    double off = 0.0, off_rel = 0.0;
    if (frame && !sim->algo->exact_overlap && sim->overlap_step != step) {
        double m = 0.0, mr = 0.0;
        if (nbep_state_max_overlap(&sim->st, &sim->overlap_grid, &m, &mr, NULL, NULL,
                                   sim->diag) == NBEP_OK) {
            if (step % sim->scene->output_every == 0) { /* on the grid, not shared */
                ov = fmax(ov, m);
                ov_rel = fmax(ov_rel, mr);
            } else {
                off = m;
                off_rel = mr;
            }
        }
    }
    row.max_overlap = ov;
    sim->max_overlap = fmax(sim->max_overlap, fmax(ov, off));
    sim->max_overlap_rel = fmax(sim->max_overlap_rel, fmax(ov_rel, off_rel));
    sim->rows[sim->n_rows++] = row;
    if (sim->n_rows == sim->cap_rows) {
        nbep_status st = flush_rows(sim);
        if (st != NBEP_OK && sim->status == NBEP_OK)
            sim->status = st, stop = 1;
    }
    if (frame) {
        nbep_status st = emit_frame(sim, step);
        if (st != NBEP_OK && (sim->status == NBEP_OK || sim->status == NBEP_ESIGINT ||
                              sim->status == NBEP_ESIGTERM))
            sim->status = st, stop = 1;
    }
    progress(sim, step, step == sim->step_end || stop);
    if (stop)
        atomic_store_explicit(&sim->stop, 1, memory_order_relaxed); /* next barrier orders it */
    return stop;
}

nbep_status nbep_sim_run(nbep_sim *sim, nbep_diag *d)
{
    sim->diag = d;
    sim->status = NBEP_OK;
    sim->out_failed = false;
    sim->tty = sim->opt.progress && isatty(STDERR_FILENO);
    sim->line_open = false;
    sim->tty_width = 0;
    clock_start(sim, nbep_now());
    /* A resumed run's first frame is already in the file. */
    nbep_status st = sim->resumed ? NBEP_OK : emit_frame(sim, 0);
    if (st != NBEP_OK)
        return st;
    sim->steps_done = sim->frame_last = sim->step_first - 1;
    sim->abandoned = false;
    /* a signal since the run began (the steps poll it at their ends; a run of 0 steps has
     * none): it stops here, with frame 0 written */
    sim->status = nbep_sim_stop_status(sim->opt.stop_signal);
    if (sim->status == NBEP_OK && sim->step_end >= sim->step_first)
        sim->algo->run(sim, sim->algo_ctx);
    /* a step abandoned by a signal: the progress ends at the step before, with its last line,
     * as at a stop at a step's end (a terminal's line was left open, and the run's last lines
     * followed on it); so does a run stopped in its first predictions whose line was shown */
    if (sim->abandoned || sim->line_open)
        progress(sim, sim->steps_done, true);
    sim->wall_seconds = nbep_now() - sim->t_start;
    /* after a failed write the file gets nothing more: one error, not a cascade; a run stopped
     * by an energy beyond doubles keeps its rows up to the step before (all finite), which
     * its summary counts; so does one whose step ran out of memory where no write failed (the
     * algorithm's memory: the file is sound, and until 2026-12-07 the rows of the steps since
     * the last frame were dropped) */
    if (!sim->out_failed &&
        (sim->status == NBEP_OK || sim->status == NBEP_ESIGINT || sim->status == NBEP_ESIGTERM ||
         sim->status == NBEP_ENUMERIC || sim->status == NBEP_ENOMEM)) {
        st = flush_rows(sim);
        if (st != NBEP_OK)
            sim->status = st;
    }
    return sim->status;
}

bool nbep_sim_output_failed(const nbep_sim *sim)
{
    return sim->out_failed;
}

bool nbep_sim_abandoned(const nbep_sim *sim, uint64_t *frame_step)
{
    *frame_step = sim->frame_last;
    return sim->abandoned;
}

void nbep_sim_summary(const nbep_sim *sim, nbep_summary *s)
{
    memset(s, 0, sizeof *s);
    snprintf(s->algorithm, sizeof s->algorithm, "%s", sim->scene->algorithm);
    s->threads = sim->nt;
    s->spheres = sim->st.n;
    s->planes = sim->st.n_planes;
    s->steps = sim->steps_done; /* the step reached (a resumed run counts from the start) */
    s->steps_requested = (nbep_summary_count){true, sim->step_end}; /* run.steps */
    s->dt = sim->dt;
    s->setup_seconds = sim->setup_seconds;
    s->wall_seconds = sim->wall_seconds;
    double stepped = (double)(sim->steps_done + 1 - sim->step_first);
    s->steps_per_second = sim->wall_seconds > 0.0 ? stepped / sim->wall_seconds : 0.0;
    s->checks = sim->totals[NBEP_COUNTER_CHECKS];
    s->predictions = sim->totals[NBEP_COUNTER_PREDICTIONS];
    s->sphere_collisions = sim->totals[NBEP_COUNTER_SPHERE_COLLISIONS];
    s->plane_collisions = sim->totals[NBEP_COUNTER_PLANE_COLLISIONS];
    s->collisions = s->sphere_collisions + s->plane_collisions;
    s->quiet_steps = sim->quiet_steps;
    s->energy_initial = sim->energy_initial;
    s->energy_final = sim->energy_final;
    s->energy_rel_drift = sim->energy_initial != 0.0
                              ? (sim->energy_final - sim->energy_initial) /
                                    fabs(sim->energy_initial)
                              : 0.0;
    /* an initial energy so small (subnormal, say) that the quotient passes the doubles: the
     * largest double of its sign, not inf, which JSON cannot hold (a review's scene: one
     * sphere at 1e-160 under gravity above a floor aborted the run at its close) */
    if (isinf(s->energy_rel_drift))
        s->energy_rel_drift = copysign(DBL_MAX, s->energy_rel_drift);
    s->max_overlap = sim->max_overlap;
    s->max_overlap_rel = sim->max_overlap_rel;
    s->peak_rss_bytes = nbep_peak_rss();
    /* SPEC contract 2: for a fully periodic box, P = (N kT + W / (3 T)) / V with kT = 2 <KE> /
     * (3 N) over the run's steps (a resumed run's from step 1 where its file had the totals,
     * else its own part's), W their summed virial and T their simulated time; null otherwise
     * or before any step */
    const double summed = (double)(sim->steps_done + 1 - sim->sums_first);
    const nbep_scene *sc = sim->scene;
    if (sc->has_box && sc->periodic[0] && sc->periodic[1] && sc->periodic[2] && summed > 0.0 &&
        sim->st.n > 0) {
        double V = (sc->box_max.x - sc->box_min.x) * (sc->box_max.y - sc->box_min.y) *
                   (sc->box_max.z - sc->box_min.z);
        double T = summed * sim->dt, ke = sim->ke_total / summed;
        double P = (2.0 * ke / 3.0 + sim->virial_total / (3.0 * T)) / V;
        if (isfinite(P))
            s->pressure = (nbep_summary_nullable){true, P};
    }
}
