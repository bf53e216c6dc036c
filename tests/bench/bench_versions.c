/* What the optimistic slab scheme's own bookkeeping would cost a thread, per event
 * (docs/optimistic-design.md, step 2): bin/nbep itself (src/main.c) with its own copy of
 * src/evloop.c in which every event handled (cells mode, one thread) also does, on that one
 * thread, the work each slab's thread would do beside the physics, as though the box were cut
 * into NBEP_VER_SLABS slabs across x (a sphere owned by the slab of its list centre):
 *
 *   - a version of each sphere the event wrote (its motion, 96 bytes, with the event's stamp:
 *     time and pair key) appended to the event's slab's log, what its rollback would undo:
 *     through the ops' save, or with NBEP_VER_LEAN set, for a sphere far from its slab's
 *     sides (below), a lean version of 80 bytes, what a reaction changes (lean_save: the
 *     periodic image in one more only at a list expiry); NBEP_VER_LEAN=2 writes those past
 *     the caches (put_lean: a log is read again only by a rollback);
 *   - for a sphere whose centre lies within SIDE_REACH of its slab's side (only such a sphere
 *     is in a list of another slab's, or has one of another slab's in its list), its record:
 *     the check a write makes for a read from another slab that came too soon (a later read
 *     stamp), its newest version; and if another slab owns it, the version again as a message
 *     to that slab's inbox;
 *   - for each list read to predict a sphere again (by its owner: a sphere of another slab
 *     that the event changed is predicted there from the message), if the sphere lies within
 *     SIDE_REACH of a side, the owner of each member, and for each of another slab a note in
 *     that member's record (the latest time another slab read it, and which slabs);
 *   - at each window's end (NBEP_VER_WINDOW, in time units, default 0.003) the logs and
 *     inboxes are emptied and the records' stamps left behind, as the window's meeting makes
 *     everything before it final.
 *
 * So its time with NBEP_VER_SLABS set against its time without is the per-event share of the
 * work a slab's thread does alone: a lower bound on the scheme's bookkeeping (it leaves out
 * what only threads show: the cache lines of notes and messages passing between cores, the
 * window's meeting, the rollbacks themselves, which scripts/optimistic-model.py counts). The
 * design has room for it below about 12 % of an event on two threads and 35 % on 16 (README,
 * Threads on dense scenes).
 *
 *   make build/bench/bench_versions
 *   NBEP_VER_SLABS=2 NBEP_VER_WINDOW=0.003 build/bench/bench_versions run DECK -t 1 ...
 *   scripts/bench-versions.sh [COUNT PHI]    (side by side, medians)
 *
 * With NBEP_VER_MODULE set, the records of spheres near a side and the notes are those of
 * src/versions.c (versions.h), the scheme's own: the spheres whose list centre lies within
 * SIDE_REACH of a side are tracked (at each window's meeting, those whose list expired in the
 * window looked at again), a write of such a sphere puts its version in its owner's pool,
 * and a read of a list member of another slab takes the member's version valid at the event's
 * stamp (its motion copied out, as a prediction would read it); a message to another slab goes
 * through src/mail.c (mail.h), each box taken at the window's meeting (or when full), which
 * then checks that the window's work is done (a sphere's message is sent by the writer, its
 * version still put by the writer into the owner's pool); and every event's record, each
 * sphere it wrote (its motion, as the ops' save keeps it, in place of the lean versions) and
 * each message it sent, goes into its slab's log in src/undo.c (undo.h), emptied at each
 * meeting. A sphere that comes near a
 * side within a window (its list expired there) is not tracked till the next (counted:
 * untracked); a pool full (NBEP_VER_ROOM versions a slab, default 4096 and an eighth of a
 * slab's share of the spheres) ends the window at the next event (counted). The tally adds the
 * puts and reads, and the puts that sent a slab back (in the serial order only a read and a
 * write at one time can: with NBEP_VER_VERIFY those that did with no read at their time are
 * counted, from the stand-in's records kept beside).
 *
 * Without NBEP_VER_SLABS (or 0) the hook returns at once: the baseline, the same binary. With
 * NBEP_VER_VERIFY set every list is read through, and a member of another slab in a list that
 * SIDE_REACH would have skipped, or read from another slab with no record kept, is counted
 * (the bound's check: tests/test_optimistic_model.sh wants none). The tally (events, versions,
 * events and lists near a side, notes, messages, windows, reads too soon: none in the serial
 * order) goes to stderr at exit. Only with -t 1. Not for production. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

struct nbep_evloop;
struct evl_ws;
struct nbep_evloop_ops;
static void ver_event(struct nbep_evloop *e, const struct evl_ws *w, const void *ev,
                      const struct nbep_evloop_ops *ops, void *u);
/* expanded inside nbep__evloop_handle, where ops and u are its arguments */
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) ver_event(e, w, ev, ops, u)
#include "../../src/evloop.c"
#include "../../src/evloop_team.c"
#include "../../src/main.c"
/* its own copy of the cells callbacks too, for lean_save (cells_user) */
#include "../../src/pred_cells.c"
#include "nbep/mail.h"
#include "nbep/undo.h"
#include "nbep/versions.h"
#include "nbep_test_stamp.h"

#define SLABS_MAX 64
/* NBEP_VER_MODULE: a slab's box of messages (mail.c); a full one is taken at once (counted), as
 * its owner would take it at its next event */
#define MAIL_ROOM 1024

/* a version: the stamp of the event that wrote it and the motion it wrote */
typedef struct {
    double t;
    uint64_t key;
    uint32_t sphere;
    nbep_evloop_motion m;
} version;

/* a lean version: the stamp's time and what a reaction changes (80 bytes, against the 120
 * of a whole one; an expiry's periodic image goes in a second lean version's place, as a
 * rare extra entry: the key is the event's, found again from its log position) */
typedef struct {
    double t;
    uint32_t sphere, image; /* image: 1 for the entry holding an expiry's image in pos */
    nbep_vec3 pos, vel;
    double tau;
    uint64_t ver;
} lean_version;
_Static_assert(sizeof(lean_version) % 16 == 0,
               "a lean version is whole 16-byte words (put_lean)");

typedef struct {
    version *log, *inbox;
    lean_version *lean;
    size_t n_log, n_inbox, n_lean, cap_log, cap_inbox, cap_lean;
} slab;

/* what a slab's thread keeps of a sphere, on one line: its newest version (index in its
 * writer's log) and that version's window; the latest read of it from another slab (its time,
 * its window) and which slabs read it then (a bit each, modulo 64): a version inserted before
 * that time rolls those readers back to it */
typedef struct {
    double read_t;
    uint32_t read_win, newest, newest_win, pad;
    uint64_t readers;
} sphere;

static struct {
    int slabs;       /* 0: off */
    double window;
    bool started, failed;
    double t_win;    /* the current window's end */
    double lo, inv, width; /* the cells' low x side, slabs per unit of x, a slab's width */
    uint32_t win;    /* its number, from 1: what a sphere's newest and read stamps belong to */
    size_t n;
    sphere *sp;      /* n */
    bool lean;       /* NBEP_VER_LEAN: the versions of spheres far from a side lean (lean_save) */
    bool stream;     /* NBEP_VER_LEAN=2: and written past the caches (put_lean) */
    bool verify;     /* NBEP_VER_VERIFY: the lists skipped are read through too, and a member
                      * of another slab found there counted (missed) */
    slab s[SLABS_MAX];
    nbep_versions *mod; /* NBEP_VER_MODULE: the near spheres' records and notes, versions.c's */
    nbep_mail *mail;    /* and the messages, mail.c's */
    nbep_undo *undo;    /* and each slab's log, undo.c's */
    uint32_t *moved;    /* the spheres whose list expired in the window, n_moved (at most n) */
    size_t n_moved;
    bool mod_open;      /* a window of it open */
    bool end_window;    /* a pool filled up: the next event starts a window */
    unsigned long long puts, module_reads, sent_back, sent_wrongly, untracked, full, mailed,
        boxes_full, not_quiet;
    unsigned long long events, versions, near, lists_read, reads_checked, notes, messages,
        windows, too_soon, missed;
} ver;

/* The events in every slab's undo log. */
static size_t undo_logged(void)
{
    size_t n = 0;
    for (int k = 0; k < ver.slabs; k++)
        n += nbep_undo_count(ver.undo, k);
    return n;
}

static void ver_report(void)
{
    if (!ver.started)
        return;
    if (ver.failed)
        fprintf(stderr, "bench_versions: no memory for the logs\n");
    fprintf(stderr,
            "bench_versions: slabs %d%s, window %g: %llu events, %llu versions, %llu near a side "
            "(%.1f %%), %llu lists near a side read, %llu reads checked, %llu notes, %llu "
            "messages, %llu windows, %llu reads too soon",
            ver.slabs,
            ver.stream ? " (lean versions, streamed)" : ver.lean ? " (lean versions)" : "",
            ver.window, ver.events, ver.versions, ver.near,
            ver.events ? 100.0 * (double)ver.near / (double)ver.events : 0.0, ver.lists_read,
            ver.reads_checked, ver.notes, ver.messages, ver.windows, ver.too_soon);
    if (ver.verify)
        fprintf(stderr, ", %llu reads of another slab in lists skipped", ver.missed);
    if (ver.mod)
        fprintf(stderr,
                "; versions.c: %llu puts, %llu reads, %llu sent back, %llu untracked, %llu "
                "pools full; mail.c: %llu messages taken, %llu boxes full, %llu meetings not "
                "quiet",
                ver.puts, ver.module_reads, ver.sent_back, ver.untracked, ver.full, ver.mailed,
                ver.boxes_full, ver.not_quiet);
    if (ver.mod && ver.verify)
        fprintf(stderr, ", %llu sent back with no read at their time", ver.sent_wrongly);
    if (ver.undo)
        fprintf(stderr, "; undo.c: %zu events logged in the last window", undo_logged());
    fputc('\n', stderr);
    nbep_versions_destroy(&ver.mod);
    nbep_mail_destroy(&ver.mail);
    nbep_undo_destroy(&ver.undo);
    free(ver.moved);
    for (int k = 0; k < ver.slabs; k++) {
        free(ver.s[k].log);
        free(ver.s[k].inbox);
        free(ver.s[k].lean);
    }
    free(ver.sp);
}

/* Whether the environment sets a switch: set, and neither empty nor 0. */
static bool env_on(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static void ver_start(const nbep_evloop *e)
{
    ver.started = true;
    const char *s = getenv("NBEP_VER_SLABS"), *w = getenv("NBEP_VER_WINDOW");
    ver.slabs = s ? atoi(s) : 0;
    ver.window = w ? atof(w) : 0.003;
    if (ver.slabs < 0 || ver.slabs > SLABS_MAX || !(ver.window > 0.0)) {
        fprintf(stderr, "bench_versions: NBEP_VER_SLABS from 0 to %d, NBEP_VER_WINDOW above 0\n",
                SLABS_MAX);
        exit(2);
    }
    if (e->team != 1) {
        fprintf(stderr, "bench_versions: run it with -t 1\n");
        exit(2);
    }
    atexit(ver_report);
    if (!ver.slabs)
        return;
    ver.n = e->n;
    ver.lo = e->cells.lo.x;
    ver.width = (e->cells.hi.x - ver.lo) / ver.slabs;
    ver.inv = 1.0 / ver.width;
    ver.verify = env_on("NBEP_VER_VERIFY");
    ver.lean = env_on("NBEP_VER_LEAN");
    ver.stream = ver.lean && strcmp(getenv("NBEP_VER_LEAN"), "2") == 0;
    ver.sp = calloc(ver.n, sizeof *ver.sp);
    ver.failed = !ver.sp;
    if (env_on("NBEP_VER_MODULE")) {
        /* a slab's pool: its share of the spheres' versions in a window, and more (a full
         * one ends the window) */
        const char *r = getenv("NBEP_VER_ROOM"); /* a test's small pools: windows end early */
        const size_t room = r && atol(r) > 0 ? (size_t)atol(r)
                                             : 4096 + ver.n / (size_t)ver.slabs / 8;
        nbep_diag d;
        nbep_diag_init(&d);
        if (nbep_versions_create(ver.n, sizeof(nbep_evloop_motion), ver.slabs, room, &ver.mod,
                                 &d) != NBEP_OK ||
            nbep_mail_create(ver.slabs, sizeof(nbep_evloop_motion), MAIL_ROOM, &ver.mail, &d) !=
                NBEP_OK ||
            nbep_undo_create(ver.slabs, sizeof(nbep_evloop_motion), &ver.undo, &d) != NBEP_OK)
            ver.failed = true;
        nbep_diag_fini(&d);
        ver.moved = malloc((ver.n ? ver.n : 1) * sizeof *ver.moved);
        ver.failed |= !ver.moved;
    }
}

/* How near a slab's side a list centre must lie for its list to hold a member of another
 * slab: each member's centre lies within the cutoff and two strays of it (each was within the
 * cutoff of the list's centre, give or take its own stray, when it joined). So a sphere whose
 * centre lies further than that inside its slab is read by no other slab, and its list names
 * none of another. */
#define SIDE_REACH(e) ((e)->cut + 2.0 * (e)->stray)

/* Room for one more in a slab's array (doubling). */
static bool grow(void **a, size_t *cap, size_t len, size_t size)
{
    if (len < *cap)
        return true;
    const size_t c = *cap ? 2 * *cap : 4096;
    void *p = realloc(*a, c * size);
    if (!p)
        return false;
    *a = p;
    *cap = c;
    return true;
}

/* The slab of a place across x. */
static int slab_of(double x)
{
    const int k = (int)((x - ver.lo) * ver.inv);
    return k < 0 ? 0 : k >= ver.slabs ? ver.slabs - 1 : k;
}

/* Whether place x lies within r of a side of its slab (a periodic x's ends are sides too; a
 * place past the box's ends, as a wall's box allows, counts as near). */
static bool near_slab_side(double x, double r)
{
    const double f = (x - ver.lo) * ver.inv;
    if (!(f >= 0.0 && f < ver.slabs))
        return true;
    const double in = (f - (int)f) * ver.width;
    return in < r || ver.width - in < r;
}

/* A message from mail.c's box: its motion copied out, as its owner would put it. */
static void took(void *arg, const nbep_mail_head *h, const void *data)
{
    (void)h;
    memcpy(arg, data, sizeof(nbep_evloop_motion));
    ver.mailed++;
}

/* Slab k takes its mail. */
static void take_mail(int k)
{
    nbep_evloop_motion m;
    (void)nbep_mail_take(ver.mail, k, took, &m);
}

/* A window of versions.c's opens, the last closed: at the first, the spheres whose list centre
 * lies within SIDE_REACH of a side are tracked (a pass over all); at each later one, only the
 * spheres whose list expired in the last window are looked at again (a centre moves only
 * then), as the scheme's meeting would */
static void module_window(const nbep_evloop *e)
{
    if (ver.mod_open) {
        nbep_versions_close(ver.mod);
        /* the meeting: every box taken, every slab idle, the window's work done */
        for (int k = 0; k < ver.slabs; k++)
            take_mail(k);
        for (int k = 0; k < ver.slabs; k++)
            nbep_mail_idle(ver.mail, k);
        ver.not_quiet += !nbep_mail_quiet(ver.mail);
        nbep_undo_clear(ver.undo);
    }
    /* all again at the first, and where the moves filled their list (one sphere's list may
     * expire many times a window) */
    const bool first = !ver.mod_open || ver.n_moved == ver.n;
    const size_t m = first ? ver.n : ver.n_moved;
    for (size_t q = 0; q < m && !ver.failed; q++) {
        const uint32_t k = first ? (uint32_t)q : ver.moved[q];
        if (!near_slab_side(e->cells.m[k].at.x, SIDE_REACH(e)))
            nbep_versions_untrack(ver.mod, k);
        else if (!nbep_versions_track(ver.mod, k))
            ver.failed = true;
    }
    ver.n_moved = 0;
    nbep_versions_open(ver.mod);
    nbep_mail_open(ver.mail);
    ver.mod_open = true;
}

/* Entry v of a log, written past the caches where the machine can (SSE2's streaming stores,
 * five of 16 bytes: a log is read again only by a rollback, so it need not displace the run's
 * own data from the caches; realloc's blocks and the 80-byte entries are 16-byte aligned). */
static void put_lean(lean_version *dst, const lean_version *v)
{
#ifdef __SSE2__
    if (ver.stream) {
        const __m128i *from = (const __m128i *)v;
        __m128i *to = (__m128i *)dst;
        for (size_t k = 0; k < sizeof *v / sizeof *from; k++)
            _mm_stream_si128(to + k, _mm_loadu_si128(from + k));
        return;
    }
#endif
    *dst = *v;
}

/* What an event changes of sphere k, kept as a lean version in slab s's log (ver.lean): its
 * motion, local time and response count, and where the event may have wrapped it (a list
 * expiry) its periodic image in one more entry. (A granular run's two words of the TC model,
 * which the ops' save keeps too, would take a third; the fluids have none.) */
static bool lean_save(slab *s, void *u, uint32_t k, double t, bool wraps)
{
    const cells_user *x = u;
    const pred_ctx *c = x->c;
    for (int e = 0; e <= (int)wraps; e++) {
        if (!grow((void **)&s->lean, &s->cap_lean, s->n_lean, sizeof *s->lean))
            return false;
        lean_version v = {.t = t, .sphere = k, .image = (uint32_t)e};
        if (e) {
            const int32_t *im = &x->s->image[3 * (size_t)k];
            v.pos = (nbep_vec3){im[0], im[1], im[2]};
        } else {
            v.pos = x->s->pos[k];
            v.vel = x->s->vel[k];
            v.tau = c->tau[k];
            v.ver = c->ver[k];
        }
        put_lean(&s->lean[s->n_lean++], &v);
    }
    return true;
}

/* NBEP_VER_MODULE: sphere k, written by the event at (t, key) of slab `by`, into that slab's
 * undo log (undo.c; its motion, as the ops' save keeps it); near a side (`side`), its version
 * put in its owner's pool (versions.c) and, if another slab owns it, a message to the owner
 * (mail.c; its box taken when full), logged to be cancelled. */
static void module_write(const nbep_evloop_ops *ops, void *u, uint32_t k, double t, uint64_t key,
                         int by, bool side, int owner)
{
    nbep_evloop_motion m;
    ops->save(u, k, &m);
    if (!nbep_undo_keep(ver.undo, by, k, &m)) {
        ver.failed = true;
        return;
    }
    if (!side)
        return; /* no other slab reads it or owns it: the log is all */
    uint64_t roll = 0;
    if (!nbep_versions_tracked(ver.mod, k))
        ver.untracked++;
    else if (!nbep_versions_put(ver.mod, owner, k, nbep_stamp_at(t, key, 0), &m, &roll))
        ver.full++, ver.end_window = true;
    else
        ver.puts++, ver.sent_back += roll != 0;
    /* in the serial order a note is never later than now: a slab sent back read k at this very
     * time (ties: the note keeps the time only); checked against the stand-in's own record of
     * the reads, kept with NBEP_VER_VERIFY */
    const sphere *x = &ver.sp[k];
    if (ver.verify && roll && !(x->read_win == ver.win && x->read_t == t))
        ver.sent_wrongly++;
    if (owner == by)
        return;
    nbep_undo_sent sent = {.stamp = {t, key}, .sphere = k, .to = owner};
    while (!nbep_mail_send(ver.mail, by, owner, sent.stamp, k, &m, &sent.id)) {
        ver.boxes_full++;
        take_mail(owner);
    }
    ver.messages++;
    if (!nbep_undo_sent_one(ver.undo, by, &sent))
        ver.failed = true;
}

/* Sphere k, written by the event at (t, key) of slab `by`: the check for a read too soon,
 * its version in the writer's log, and a message if another slab owns it. */
static void write_version(const nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                          uint32_t k, double t, uint64_t key, int by, bool wraps)
{
    const double at = e->cells.m[k].at.x;
    slab *s = &ver.s[by]; /* the writer's log: what its rollback would undo */
    ver.versions++;
    const bool side = near_slab_side(at, SIDE_REACH(e));
    if (ver.mod) {
        module_write(ops, u, k, t, key, by, side, slab_of(at));
        return;
    }
    if (ver.lean && !side) { /* no other slab reads it or owns it: the lean log is all */
        if (!lean_save(s, u, k, t, wraps))
            ver.failed = true;
        return;
    }
    if (!grow((void **)&s->log, &s->cap_log, s->n_log, sizeof *s->log)) {
        ver.failed = true;
        return;
    }
    version *v = &s->log[s->n_log];
    v->t = t;
    v->key = key;
    v->sphere = k;
    ops->save(u, k, &v->m);
    if (!side) {
        s->n_log++;
        return; /* no other slab reads it or owns it: the log is all */
    }
    const int owner = slab_of(at);
    sphere *x = &ver.sp[k];
    if (x->read_win == ver.win && x->read_t > t)
        ver.too_soon++; /* never, in the serial order */
    x->newest = (uint32_t)s->n_log;
    x->newest_win = ver.win;
    s->n_log++;
    if (owner != by) {
        slab *r = &ver.s[owner];
        if (!grow((void **)&r->inbox, &r->cap_inbox, r->n_inbox, sizeof *r->inbox)) {
            ver.failed = true;
            return;
        }
        r->inbox[r->n_inbox++] = *v;
        ver.messages++;
    }
}

/* Sphere k's list (js[0..m)), read to predict k again after an event at time t. k's owner
 * predicts it (a sphere of another slab that the event changed gets its new motion as a
 * message, and its owner predicts it from there), so the reader is k's slab. If k's centre
 * lies further than SIDE_REACH inside that slab, the list names none of another and is not
 * looked at; else each member of another slab gets a note: its latest read from another slab
 * and the reader. */
static void read_list(const nbep_evloop *e, uint32_t k, const uint32_t *js, size_t m, double t,
                      uint64_t key)
{
    const double at = e->cells.m[k].at.x;
    const bool skip = !near_slab_side(at, SIDE_REACH(e));
    if (skip && !ver.verify)
        return;
    const int by = slab_of(at);
    ver.lists_read += !skip;
    for (size_t q = 0; q < m; q++) {
        const uint32_t j = js[q];
        ver.reads_checked += !skip;
        if (slab_of(e->cells.m[j].at.x) == by)
            continue;
        if (skip) {
            ver.missed++;
            continue;
        }
        if (ver.verify && !near_slab_side(e->cells.m[j].at.x, SIDE_REACH(e)))
            ver.missed++; /* read from another slab, yet its writes keep no record */
        if (ver.mod && ver.verify) { /* the stand-in's record too, for sent_wrongly */
            sphere *x = &ver.sp[j];
            if (x->read_win != ver.win || x->read_t < t)
                x->read_win = ver.win, x->read_t = t;
        }
        if (ver.mod) {
            nbep_evloop_motion got;
            if (nbep_versions_tracked(ver.mod, j)) {
                (void)nbep_versions_read(ver.mod, by, j, nbep_stamp_at(t, key, 0), &got, NULL);
                ver.module_reads++;
            } else {
                ver.untracked++;
            }
            ver.notes++;
            continue;
        }
        sphere *x = &ver.sp[j];
        if (x->read_win != ver.win || x->read_t < t) {
            x->read_win = ver.win;
            x->read_t = t;
            x->readers = 0;
        }
        x->readers |= (uint64_t)1 << (by % 64);
        ver.notes++;
    }
}

static void ver_event(nbep_evloop *e, const evl_ws *w, const void *evp,
                      const nbep_evloop_ops *ops, void *u)
{
    if (!ver.started)
        ver_start(e);
    if (!ver.slabs || ver.failed)
        return;
    const nbep_event *ev = evp;
    const double t = ev->time;
    const uint32_t i = w->item;
    ver.events++;
    if (t >= ver.t_win || ver.end_window) { /* a meeting: everything before it final */
        for (int k = 0; k < ver.slabs; k++)
            ver.s[k].n_log = ver.s[k].n_inbox = ver.s[k].n_lean = 0;
        ver.win++;
        ver.t_win = (floor(t / ver.window) + 1.0) * ver.window;
        ver.windows++;
        ver.end_window = false;
        if (ver.mod)
            module_window(e);
        if (ver.failed)
            return;
    }
    const uint64_t key = nbep__evloop_slot_key(i, ev);
    if (ver.mod && w->rebuilt && ver.n_moved < ver.n)
        ver.moved[ver.n_moved++] = i; /* its centre moved: tracked or not, from the next window */
    const double cx = e->cells.m[i].at.x;
    const int by = slab_of(cx);
    if (ver.mod && !nbep_undo_begin(ver.undo, by, STAMP_AT(t, key, 0))) {
        ver.failed = true;
        return;
    }
    /* what the event wrote: its sphere and, for a reaction, every sphere it changed */
    write_version(e, ops, u, i, t, key, by, w->rebuilt);
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != i)
            write_version(e, ops, u, w->changed[k], t, key, by, false);
    /* a sphere the event changed has its centre within the cutoff of i's: past that and
     * SIDE_REACH (and two strays of margin) inside i's slab, no list it reads is looked at */
    const bool near = near_slab_side(cx, 2.0 * e->cut + 4.0 * e->stray);
    if (!near && !ver.verify)
        return;
    ver.near += near;
    if (w->rebuilt) { /* its new list */
        read_list(e, i, w->near, w->n_near, t, key);
        return;
    }
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
    read_list(e, i, js, m, t, key);
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != i) {
            js = nbep_nblist_of(&e->nl, w->changed[k], &m);
            read_list(e, w->changed[k], js, m, t, key);
        }
}
