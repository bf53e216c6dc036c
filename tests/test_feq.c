/* Tests of the future event queue: each operation, superseding and its tie rules, the t_end
 * boundary of find, index ranges, and the invariant checker catching bad slots. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "nbep/feq.h"
#include "nbep_test.h"

/* Spheres in the fixture's queue: enough for ranges with slots on both sides. */
#define N_SPHERES 9
#define N_PLANES 3

static int setup_queue(void **state)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_feq *q = NULL;
    nbep_status s = nbep_feq_create(N_SPHERES, &q, &d);
    nbep_diag_fini(&d);
    if (s != NBEP_OK)
        return -1;
    *state = q;
    return 0;
}

static int teardown_queue(void **state)
{
    nbep_feq *q = *state;
    nbep_feq_destroy(&q);
    return 0;
}

static nbep_event sphere_event(double time, uint32_t partner)
{
    return (nbep_event){.time = time, .partner = partner, .kind = NBEP_EVENT_SPHERE,
                        .ver_self = 4, .ver_partner = 11};
}

static nbep_event plane_event(double time, uint32_t plane)
{
    return (nbep_event){.time = time, .partner = plane, .kind = NBEP_EVENT_PLANE,
                        .ver_self = 4, .ver_partner = 0};
}

static void assert_slot_is(const nbep_feq *q, size_t i, nbep_event e)
{
    const nbep_event *s = nbep_feq_slot(q, i);
    assert_int_equal(s->kind, e.kind);
    assert_int_equal(s->partner, e.partner);
    assert_true(s->time == e.time);
    assert_int_equal(s->ver_self, e.ver_self);
    assert_int_equal(s->ver_partner, e.ver_partner);
}

static void test_a_new_queue_has_every_slot_invalid(void **state)
{
    nbep_feq *q = *state;
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find_invalid(q, 0, N_SPHERES, ids), N_SPHERES);
    for (uint32_t i = 0; i < N_SPHERES; i++) {
        assert_int_equal(ids[i], i);
        assert_int_equal(nbep_feq_slot(q, i)->kind, NBEP_EVENT_NONE);
    }
    assert_int_equal(nbep_feq_find(q, 0, N_SPHERES, 1.0e300, ids), 0);
}

static void test_an_event_goes_into_an_invalid_slot(void **state)
{
    nbep_feq *q = *state;
    nbep_event e = sphere_event(3.17, 5);
    assert_true(nbep_feq_insert(q, 2, e));
    assert_slot_is(q, 2, e);
    /* The other slots are untouched. */
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find_invalid(q, 0, N_SPHERES, ids), N_SPHERES - 1);
}

static void test_a_later_event_does_not_replace_an_earlier_one(void **state)
{
    nbep_feq *q = *state;
    nbep_event early = sphere_event(1.43, 6), late = plane_event(2.71, 1);
    assert_true(nbep_feq_insert(q, 4, early));
    assert_false(nbep_feq_insert(q, 4, late));
    assert_slot_is(q, 4, early);
}

static void test_an_earlier_event_supersedes_a_later_one(void **state)
{
    nbep_feq *q = *state;
    nbep_event late = sphere_event(2.71, 6), early = plane_event(1.43, 2);
    assert_true(nbep_feq_insert(q, 4, late));
    assert_true(nbep_feq_insert(q, 4, early));
    assert_slot_is(q, 4, early);
    /* Earlier by the smallest step a double can take still wins. */
    nbep_event a_hair_earlier = sphere_event(nextafter(1.43, 0.0), 8);
    assert_true(nbep_feq_insert(q, 4, a_hair_earlier));
    assert_slot_is(q, 4, a_hair_earlier);
}

/* Inserts a then b into slot i of a fresh queue and returns the slot. */
static nbep_event winner_of(nbep_event a, nbep_event b)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_feq *q = NULL;
    assert_int_equal(nbep_feq_create(N_SPHERES, &q, &d), NBEP_OK);
    (void)nbep_feq_insert(q, 3, a);
    (void)nbep_feq_insert(q, 3, b);
    nbep_event w = *nbep_feq_slot(q, 3);
    nbep_feq_destroy(&q);
    nbep_diag_fini(&d);
    return w;
}

static void test_equal_times_keep_a_sphere_partner_over_a_plane_in_either_order(void **state)
{
    (void)state;
    /* Kind SPHERE (1) sorts before PLANE (2), whatever the partner numbers. */
    nbep_event sphere = sphere_event(0.625, 7), plane = plane_event(0.625, 0);
    assert_int_equal(winner_of(sphere, plane).kind, NBEP_EVENT_SPHERE);
    assert_int_equal(winner_of(plane, sphere).kind, NBEP_EVENT_SPHERE);
}

static void test_equal_times_keep_the_smaller_partner_in_either_order(void **state)
{
    (void)state;
    nbep_event to_2 = sphere_event(0.625, 2), to_8 = sphere_event(0.625, 8);
    assert_int_equal(winner_of(to_2, to_8).partner, 2);
    assert_int_equal(winner_of(to_8, to_2).partner, 2);
    nbep_event plane_0 = plane_event(0.625, 0), plane_2 = plane_event(0.625, 2);
    assert_int_equal(winner_of(plane_2, plane_0).partner, 0);
    assert_int_equal(winner_of(plane_0, plane_2).partner, 0);
}

static void test_an_equal_time_insert_reports_whether_it_was_stored(void **state)
{
    nbep_feq *q = *state;
    assert_true(nbep_feq_insert(q, 1, sphere_event(0.625, 8)));
    assert_false(nbep_feq_insert(q, 1, plane_event(0.625, 0)));
    assert_true(nbep_feq_insert(q, 1, sphere_event(0.625, 2)));
    assert_false(nbep_feq_insert(q, 1, sphere_event(0.625, 2)));  /* the same event again */
    assert_int_equal(nbep_feq_slot(q, 1)->partner, 2);
}

static void test_the_same_contact_predicted_later_keeps_the_newer_counts(void **state)
{
    (void)state;
    nbep_event old = sphere_event(0.625, 2), newer = old;
    newer.ver_partner = old.ver_partner + 1;
    assert_int_equal(winner_of(old, newer).ver_partner, newer.ver_partner);
    assert_int_equal(winner_of(newer, old).ver_partner, newer.ver_partner);
    /* and the same when this sphere's own count is the newer one */
    nbep_event own = old;
    own.ver_self = old.ver_self + 1;
    assert_int_equal(winner_of(old, own).ver_self, own.ver_self);
    assert_int_equal(winner_of(own, old).ver_self, own.ver_self);
}

static void test_an_event_that_never_happens_is_not_stored(void **state)
{
    nbep_feq *q = *state;
    assert_false(nbep_feq_insert(q, 0, sphere_event(INFINITY, 1)));
    assert_int_equal(nbep_feq_slot(q, 0)->kind, NBEP_EVENT_NONE);
    nbep_event e = plane_event(5.5, 1);
    assert_true(nbep_feq_insert(q, 0, e));
    assert_false(nbep_feq_insert(q, 0, sphere_event(INFINITY, 1)));
    assert_slot_is(q, 0, e);
}

static void test_a_nan_time_is_not_stored(void **state)
{
    nbep_feq *q = *state;
    assert_false(nbep_feq_insert(q, 0, sphere_event(NAN, 1)));
    assert_int_equal(nbep_feq_slot(q, 0)->kind, NBEP_EVENT_NONE);
}

static void test_a_removed_slot_is_found_invalid(void **state)
{
    nbep_feq *q = *state;
    for (uint32_t i = 0; i < N_SPHERES; i++)
        assert_true(nbep_feq_insert(q, i, plane_event(1.0 + 0.1 * i, i % N_PLANES)));
    nbep_feq_remove(q, 6);
    nbep_feq_remove(q, 2);
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find_invalid(q, 0, N_SPHERES, ids), 2);
    assert_int_equal(ids[0], 2);
    assert_int_equal(ids[1], 6);
    assert_int_equal(nbep_feq_slot(q, 6)->kind, NBEP_EVENT_NONE);
    /* Removed slots are not found as events either, however late t_end is. */
    assert_int_equal(nbep_feq_find(q, 0, N_SPHERES, 1.0e300, ids), N_SPHERES - 2);
    /* After a remove any event is accepted again, even a later one. */
    nbep_event later = sphere_event(9.25, 3);
    assert_true(nbep_feq_insert(q, 6, later));
    assert_slot_is(q, 6, later);
}

static void test_find_invalid_looks_only_inside_its_range(void **state)
{
    nbep_feq *q = *state;
    assert_true(nbep_feq_insert(q, 4, sphere_event(2.0, 1)));
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find_invalid(q, 3, 6, ids), 2);
    assert_int_equal(ids[0], 3);
    assert_int_equal(ids[1], 5);
    assert_int_equal(nbep_feq_find_invalid(q, 4, 4, ids), 0);
}

static void test_an_event_exactly_at_the_step_end_is_not_found(void **state)
{
    nbep_feq *q = *state;
    const double t_end = 0.3; /* not exact in binary: the comparison must still be strict */
    assert_true(nbep_feq_insert(q, 1, sphere_event(t_end, 2)));
    assert_true(nbep_feq_insert(q, 5, plane_event(nextafter(t_end, 0.0), 0)));
    assert_true(nbep_feq_insert(q, 7, plane_event(nextafter(t_end, 1.0), 2)));
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find(q, 0, N_SPHERES, t_end, ids), 1);
    assert_int_equal(ids[0], 5);
    /* The next step finds the other two. */
    assert_int_equal(nbep_feq_find(q, 0, N_SPHERES, t_end + 0.1, ids), 3);
}

static void test_find_reports_only_its_range_in_increasing_index(void **state)
{
    nbep_feq *q = *state;
    /* Times decreasing with the index, so an answer sorted by time would come out reversed. */
    for (uint32_t i = 0; i < N_SPHERES; i++)
        assert_true(nbep_feq_insert(q, i, plane_event(2.0 - 0.125 * i, 1)));
    uint32_t ids[N_SPHERES];
    memset(ids, 0xff, sizeof ids);
    assert_int_equal(nbep_feq_find(q, 2, 7, 10.0, ids), 5);
    for (uint32_t k = 0; k < 5; k++)
        assert_int_equal(ids[k], 2 + k);
    assert_int_equal(ids[5], UINT32_MAX); /* wrote nothing past the count */
    /* Within the range, only the events before t_end: 2 - 0.125 i < 1.5 for i > 4. */
    assert_int_equal(nbep_feq_find(q, 2, 7, 1.5, ids), 2);
    assert_int_equal(ids[0], 5);
    assert_int_equal(ids[1], 6);
    assert_int_equal(nbep_feq_find(q, 3, 3, 10.0, ids), 0);
}

static void test_check_accepts_a_sound_queue(void **state)
{
    nbep_feq *q = *state;
    const double t_now = 1.25;
    assert_true(nbep_feq_insert(q, 0, sphere_event(t_now, 8)));    /* due now is fine */
    assert_true(nbep_feq_insert(q, 8, sphere_event(3.5, 0)));
    assert_true(nbep_feq_insert(q, 4, plane_event(2.0, N_PLANES - 1)));
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_feq_check(q, t_now, N_PLANES, &d), 0);
    assert_int_equal(d.n_errors, 0);
    nbep_diag_fini(&d);
}

/* Inserts e into slot i of the fixture's otherwise sound queue and expects check to flag
 * exactly that slot with a message naming the sphere and the reason. */
static void assert_check_flags(nbep_feq *q, size_t i, nbep_event e, double t_now,
                               const char *reason)
{
    assert_true(nbep_feq_insert(q, (i + 1) % N_SPHERES, plane_event(t_now + 1.0, 0)));
    assert_true(nbep_feq_insert(q, i, e));
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_feq_check(q, t_now, N_PLANES, &d), 1);
    assert_int_equal(d.n_errors, 1);
    char head[64];
    snprintf(head, sizeof head, "nbep: event slot of sphere %zu: ", i);
    assert_non_null(strstr(d.msg[0], head));
    assert_non_null(strstr(d.msg[0], reason));
    nbep_diag_fini(&d);
}

static void test_check_flags_a_sphere_partnered_with_itself(void **state)
{
    assert_check_flags(*state, 3, sphere_event(2.5, 3), 1.0, "partner is the sphere itself");
}

static void test_check_flags_an_event_in_the_past(void **state)
{
    assert_check_flags(*state, 6, sphere_event(nextafter(1.0, 0.0), 2), 1.0,
                       "time is before the current time");
}

static void test_check_flags_a_sphere_partner_out_of_range(void **state)
{
    assert_check_flags(*state, 2, sphere_event(2.5, N_SPHERES), 1.0,
                       "partner sphere out of range");
}

static void test_check_flags_a_plane_partner_out_of_range(void **state)
{
    assert_check_flags(*state, 2, plane_event(2.5, N_PLANES), 1.0, "partner plane out of range");
}

static void test_check_counts_every_bad_slot_and_describes_the_first(void **state)
{
    nbep_feq *q = *state;
    assert_true(nbep_feq_insert(q, 7, sphere_event(2.5, 7)));
    assert_true(nbep_feq_insert(q, 1, plane_event(0.5, 0)));
    assert_true(nbep_feq_insert(q, 4, plane_event(2.5, 0)));  /* sound */
    assert_true(nbep_feq_insert(q, 5, sphere_event(2.5, 99)));
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_feq_check(q, 1.0, N_PLANES, &d), 3);
    assert_int_equal(d.n_errors, 1);
    assert_non_null(strstr(d.msg[0], "sphere 1:"));
    nbep_diag_fini(&d);
    /* Without a diag only the count comes back. */
    assert_int_equal(nbep_feq_check(q, 1.0, N_PLANES, NULL), 3);
}

static void test_an_empty_queue_can_be_made_and_destroyed(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_feq *q = NULL;
    assert_int_equal(nbep_feq_create(0, &q, &d), NBEP_OK);
    assert_non_null(q);
    uint32_t id;
    assert_int_equal(nbep_feq_find_invalid(q, 0, 0, &id), 0);
    assert_int_equal(nbep_feq_check(q, 0.0, 0, &d), 0);
    nbep_feq_destroy(&q);
    assert_null(q);
    nbep_feq_destroy(&q);    /* NULL-safe */
    nbep_feq_destroy(NULL);
    nbep_diag_fini(&d);
}

static void test_a_queue_too_large_for_sphere_ids_is_refused(void **state)
{
    (void)state;
    if (SIZE_MAX <= UINT32_MAX)
        skip();
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_feq *q = NULL;
    assert_int_equal(nbep_feq_create((size_t)UINT32_MAX + 1, &q, &d), NBEP_ENOMEM);
    assert_null(q);    /* out-parameter untouched */
    assert_int_equal(d.n_errors, 1);
    assert_non_null(strstr(d.msg[0], "4294967296 spheres"));
    nbep_diag_fini(&d);
}

/* "Nothing ahead" (nbep_feq_set_never): a valid slot of kind NEVER at +inf that carries the
 * sphere's own count, by which the predictive loop knows it is still fresh (a slot without
 * it would be predicted again every step); find never reports it, however late t_end, nor
 * find_invalid; any event inserted after it replaces it; check accepts it. */
static void test_a_never_slot_is_valid_carries_the_count_and_gives_way(void **state)
{
    nbep_feq *q = *state;
    nbep_feq_set_never(q, 4, 37);
    const nbep_event *s = nbep_feq_slot(q, 4);
    assert_int_equal(s->kind, NBEP_EVENT_NEVER);
    assert_true(s->time == INFINITY);
    assert_int_equal(s->ver_self, 37);
    uint32_t ids[N_SPHERES];
    assert_int_equal(nbep_feq_find(q, 0, N_SPHERES, INFINITY, ids), 0);
    assert_int_equal(nbep_feq_find_invalid(q, 4, 5, ids), 0);
    assert_int_equal(nbep_feq_check(q, 1.0, N_PLANES, NULL), 0);
    nbep_event late = plane_event(1.0e300, 1);
    assert_true(nbep_feq_insert(q, 4, late));
    assert_slot_is(q, 4, late);
    /* and set again over an event */
    nbep_feq_set_never(q, 4, 38);
    assert_int_equal(nbep_feq_slot(q, 4)->kind, NBEP_EVENT_NEVER);
    assert_int_equal(nbep_feq_slot(q, 4)->ver_self, 38);
}

#define QUEUE_TEST(f) cmocka_unit_test_setup_teardown(f, setup_queue, teardown_queue)

int main(void)
{
    const struct CMUnitTest tests[] = {
        QUEUE_TEST(test_a_new_queue_has_every_slot_invalid),
        QUEUE_TEST(test_an_event_goes_into_an_invalid_slot),
        QUEUE_TEST(test_a_later_event_does_not_replace_an_earlier_one),
        QUEUE_TEST(test_an_earlier_event_supersedes_a_later_one),
        cmocka_unit_test(test_equal_times_keep_a_sphere_partner_over_a_plane_in_either_order),
        cmocka_unit_test(test_equal_times_keep_the_smaller_partner_in_either_order),
        QUEUE_TEST(test_an_equal_time_insert_reports_whether_it_was_stored),
        cmocka_unit_test(test_the_same_contact_predicted_later_keeps_the_newer_counts),
        QUEUE_TEST(test_an_event_that_never_happens_is_not_stored),
        QUEUE_TEST(test_a_nan_time_is_not_stored),
        QUEUE_TEST(test_a_never_slot_is_valid_carries_the_count_and_gives_way),
        QUEUE_TEST(test_a_removed_slot_is_found_invalid),
        QUEUE_TEST(test_find_invalid_looks_only_inside_its_range),
        QUEUE_TEST(test_an_event_exactly_at_the_step_end_is_not_found),
        QUEUE_TEST(test_find_reports_only_its_range_in_increasing_index),
        QUEUE_TEST(test_check_accepts_a_sound_queue),
        QUEUE_TEST(test_check_flags_a_sphere_partnered_with_itself),
        QUEUE_TEST(test_check_flags_an_event_in_the_past),
        QUEUE_TEST(test_check_flags_a_sphere_partner_out_of_range),
        QUEUE_TEST(test_check_flags_a_plane_partner_out_of_range),
        QUEUE_TEST(test_check_counts_every_bad_slot_and_describes_the_first),
        cmocka_unit_test(test_an_empty_queue_can_be_made_and_destroyed),
        cmocka_unit_test(test_a_queue_too_large_for_sphere_ids_is_refused),
    };
    return cmocka_run_group_tests_name("feq", tests, NULL, NULL);
}
