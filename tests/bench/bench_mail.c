/* Cost of a message between slabs (src/mail.c): a send and its take, with 96 bytes of data (a
 * sphere's motion, as the optimistic scheme would send it), on one thread (a slab sending to
 * another in batches of BATCH, then the other taking them: the cache-warm cost) and on two (each
 * slab sending to the other and taking its own, the boxes' lines going back and forth between
 * cores: what a write across a face would cost). Prints '#' lines, then CSV: threads,
 * messages, the median over repeats of ns per message, and the range.
 *
 *   bench_mail [messages [repeats]]     defaults: 2000000 and 5
 *
 * An event costs about 1.6 microseconds (618 k collisions a second on the fluid deck, one
 * thread); the optimistic scheme sends one message for a collision across a face. */
#include "nbep/mail.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "build_info.h"

enum { SIZE = 96, ROOM = 256, BATCH = 64, MAX_REPEATS = 101 };

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    double sum;
    unsigned long n;
} tally;

static void add_up(void *arg, const nbep_mail_head *h, const void *data)
{
    tally *t = arg;
    double v;
    memcpy(&v, data, sizeof v);
    t->sum += v + h->stamp.t;
    t->n++;
}

static nbep_mail *made(int slabs)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_mail *m = NULL;
    if (nbep_mail_create(slabs, SIZE, ROOM, &m, &d) != NBEP_OK) {
        fprintf(stderr, "bench_mail: %s\n", d.n_errors ? d.msg[0] : "cannot make the boxes");
        exit(1);
    }
    nbep_diag_fini(&d);
    return m;
}

/* One thread: batches from slab 0 to slab 1, each taken whole. */
static double one_thread(unsigned long messages)
{
    nbep_mail *m = made(2);
    nbep_mail_open(m);
    double data[SIZE / sizeof(double)] = {1.0};
    tally t = {.n = 0};
    const double t0 = now();
    for (unsigned long k = 0; k < messages; k += BATCH) {
        for (int b = 0; b < BATCH; b++)
            if (!nbep_mail_send(m, 0, 1, nbep_stamp_at((double)b, k, 0), (uint32_t)b, data, NULL))
                abort();
        if (nbep_mail_take(m, 1, add_up, &t) != BATCH)
            abort();
    }
    const double t1 = now();
    nbep_mail_idle(m, 0);
    nbep_mail_idle(m, 1);
    if (!nbep_mail_quiet(m) || t.n != (messages + BATCH - 1) / BATCH * BATCH)
        abort();
    nbep_mail_destroy(&m);
    return (t1 - t0) / (double)t.n * 1e9;
}

typedef struct {
    nbep_mail *m;
    int slab;
    unsigned long messages;
    tally t;
} side;

static void *exchange(void *arg)
{
    side *s = arg;
    double data[SIZE / sizeof(double)] = {1.0};
    for (unsigned long k = 0; k < s->messages; k++) {
        while (!nbep_mail_send(s->m, s->slab, 1 - s->slab, nbep_stamp_at(1.0, k, 0), 0, data, NULL))
            (void)nbep_mail_take(s->m, s->slab, add_up, &s->t);
        if (k % BATCH == BATCH - 1)
            (void)nbep_mail_take(s->m, s->slab, add_up, &s->t);
    }
    nbep_mail_idle(s->m, s->slab);
    while (!nbep_mail_quiet(s->m))
        if (nbep_mail_take(s->m, s->slab, add_up, &s->t) > 0)
            nbep_mail_idle(s->m, s->slab);
    return NULL;
}

/* Two threads, each sending `messages` to the other: ns per message taken, per thread. */
static double two_threads(unsigned long messages)
{
    nbep_mail *m = made(2);
    nbep_mail_open(m);
    side s[2] = {{.m = m, .slab = 0, .messages = messages},
                 {.m = m, .slab = 1, .messages = messages}};
    pthread_t th[2];
    const double t0 = now();
    for (int k = 0; k < 2; k++)
        if (pthread_create(&th[k], NULL, exchange, &s[k]))
            abort();
    for (int k = 0; k < 2; k++)
        pthread_join(th[k], NULL);
    const double t1 = now();
    if (s[0].t.n != messages || s[1].t.n != messages)
        abort();
    nbep_mail_destroy(&m);
    return (t1 - t0) / (double)messages * 1e9;
}

int main(int argc, char **argv)
{
    const unsigned long messages = argc > 1 ? strtoul(argv[1], NULL, 10) : 2000000ul;
    int repeats = argc > 2 ? atoi(argv[2]) : 5;
    if (messages < BATCH || repeats < 1 || repeats > MAX_REPEATS) {
        fprintf(stderr, "usage: bench_mail [messages (>= %d) [repeats (1 to %d)]]\n", BATCH,
                MAX_REPEATS);
        return 2;
    }
    printf("# bench_mail: nbep %s (%s), %s; %d-byte messages, boxes of %d, batches of %d\n",
           NBEP_VERSION, NBEP_BUILD_COMMIT, NBEP_BUILD_FLAGS,
           SIZE, ROOM, BATCH);
    printf("threads,messages,ns_per_message,ns_min,ns_max\n");
    for (int nt = 1; nt <= 2; nt++) {
        double ns[MAX_REPEATS];
        for (int r = 0; r < repeats; r++)
            ns[r] = nt == 1 ? one_thread(messages) : two_threads(messages);
        const double med = bench_median(ns, repeats);
        printf("%d,%lu,%.1f,%.1f,%.1f\n", nt, messages, med, ns[0], ns[repeats - 1]);
    }
    return 0;
}
