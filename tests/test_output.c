/* Tests of the HDF5 output (layout nbep-1) and the JSON summary. Files are read back with the
 * HDF5 C API directly, never through output.c's own readers, and compared bitwise with the
 * values the test put in. Scratch files live in build/tests/tmp/. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <float.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <hdf5.h>

#include "build_info.h"
#include "nbep/output.h"
#include "nbep_test.h"

#define N_SPHERES 5
#define N_PLANES 2
#define N_FRAMES 3
#define N_STATS 20
#define FRAME_EVERY 10
#define DT 0.00125

/* A deck text with what a string attribute must keep: newlines, quotes, a tab, UTF-8. */
static const char deck_text[] = "# Überlauf: \"box\" test\nrun: {\tsteps = 20; dt = 0.00125; };\n"
                                "physics: { restitution = 0.85; };\n";
static const char overrides[] = "physics.restitution=0.85\nrun.steps=20";

typedef struct fixture {
    nbep_scene sc;
    nbep_diag d;
} fixture;

/* Values without simple relations, distinct for every frame k, sphere i, component c and
 * field (0 position, 1 velocity). */
static double frame_value(int k, size_t i, int c, int field)
{
    return (field ? -1.0 : 1.0) * (1.25 + 0.37 * (double)i - 0.113 * c) * (k + 1) + 0.0071 * k;
}

static void fill_frame(nbep_state *s, int k)
{
    for (size_t i = 0; i < s->n; i++) {
        s->pos[i] = nbep_vec3_make(frame_value(k, i, 0, 0), frame_value(k, i, 1, 0),
                                   frame_value(k, i, 2, 0));
        s->vel[i] = nbep_vec3_make(frame_value(k, i, 0, 1), frame_value(k, i, 1, 1),
                                   frame_value(k, i, 2, 1));
    }
    if (k == 1 && s->n > 0) {
        /* Values a text round trip or a conversion would not keep bit for bit. */
        s->pos[0] = nbep_vec3_make(-0.0, 4.9406564584124654e-324, DBL_MAX);
        s->vel[0] = nbep_vec3_make(0.1, -DBL_MIN, 1.0 / 3.0);
    }
}

static nbep_step_stats stats_row(int r)
{
    return (nbep_step_stats){.step = r + 1,
                             .checks = 1000u + 37u * (uint64_t)r,
                             .predictions = 17u * (uint64_t)r,
                             .collisions = (uint64_t)(r % 3),
                             .kinetic_energy = 12.5 - 0.031 * r,
                             .potential_energy = -3.75 + 0.029 * r,
                             .max_overlap = r % 4 ? 1.0e-13 * r : 0.0};
}

static nbep_summary known_summary(void)
{
    nbep_summary s = {.algorithm = "predictive",
                      .threads = 2,
                      .spheres = 4096,
                      .planes = 6,
                      .steps = 1000,
                      .dt = 0.001,
                      .setup_seconds = 0.25,
                      .wall_seconds = 1.5,
                      .steps_per_second = 1000 / 1.5,
                      .checks = 123456789012u,
                      .predictions = 987654321u,
                      .collisions = 4242,
                      .sphere_collisions = 4000,
                      .plane_collisions = 242,
                      .quiet_steps = 950,
                      .energy_initial = -1234.5,
                      .energy_final = -1234.25,
                      .energy_rel_drift = 0.25 / -1234.5,
                      .max_overlap = 3.0e-14,
                      .max_overlap_rel = 6.0e-13,
                      .peak_rss_bytes = 52428800,
                      .status = NBEP_SUMMARY_TERMINATED,
                      .steps_requested = {.known = true, .value = 2500}};
    return s;
}

static int setup(void **state)
{
    fixture *fx = calloc(1, sizeof *fx);
    assert_non_null(fx);
    nbep_diag_init(&fx->d);
    nbep_scene *sc = &fx->sc;
    sc->deck_path = "tests/data/output.deck";
    sc->deck_text = (char *)deck_text;
    sc->overrides = (char *)overrides;
    snprintf(sc->algorithm, sizeof sc->algorithm, "predictive");
    sc->steps = N_STATS;
    sc->dt = DT;
    sc->threads = 0;
    sc->seed = 424242;
    sc->gravity = nbep_vec3_make(0.25, -1.5, -9.81);
    sc->restitution = 0.85;
    sc->has_box = true;
    sc->box_min = nbep_vec3_make(-1.0, -2.0, 0.0);
    sc->box_max = nbep_vec3_make(4.0, 5.5, 6.25);
    sc->output_every = FRAME_EVERY;
    sc->out_position = sc->out_velocity = sc->out_stats = true;
    sc->sweep_replicas = 1;
    assert_int_equal(nbep_state_init(&sc->state, N_SPHERES, N_PLANES, &fx->d), NBEP_OK);
    nbep_state *s = &sc->state;
    for (size_t i = 0; i < s->n; i++) {
        s->acc[i] = i == 3 ? nbep_vec3_make(0.0, 0.0, -1.0) : sc->gravity;
        s->radius[i] = 0.05 + 0.013 * (double)i;
        s->mass[i] = 1.0 + 0.3 * (double)i;
    }
    s->plane_normal[0] = nbep_vec3_make(0.0, 0.0, 1.0);
    s->plane_offset[0] = 0.0;
    s->plane_normal[1] = nbep_vec3_make(-0.6, 0.8, 0.0);
    s->plane_offset[1] = -3.5;
    fill_frame(s, 0);
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    fixture *fx = *state;
    nbep_state_fini(&fx->sc.state);
    nbep_diag_fini(&fx->d);
    free(fx);
    return 0;
}

static void assert_ok(nbep_status st, nbep_diag *d)
{
    if (st != NBEP_OK) {
        nbep_diag_print(d, stderr);
        fail_msg("status %d (%s)", (int)st, nbep_status_text(st));
    }
}

/* Creates path from fx's scene, writes N_FRAMES frames (steps 0, 10, 20) with N_STATS stats
 * rows in two batches before them, and closes with summary (may be NULL). */
static void write_run(fixture *fx, const char *path, const nbep_summary *summary)
{
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(path, &fx->sc, 3, &o, &fx->d), &fx->d);
    assert_non_null(o);
    nbep_state *s = &fx->sc.state;
    nbep_step_stats rows[N_STATS];
    for (int r = 0; r < N_STATS; r++)
        rows[r] = stats_row(r);
    for (int k = 0; k < N_FRAMES; k++) {
        if (fx->sc.out_stats && k == 1)
            assert_ok(nbep_output_stats(o, rows, NULL, 12, &fx->d), &fx->d);
        if (fx->sc.out_stats && k == 2)
            assert_ok(nbep_output_stats(o, rows + 12, NULL, N_STATS - 12, &fx->d), &fx->d);
        fill_frame(s, k);
        assert_ok(nbep_output_frame(o, (int64_t)k * FRAME_EVERY, DT, s, &fx->d), &fx->d);
    }
    assert_ok(nbep_output_close(&o, summary, &fx->d), &fx->d);
    assert_null(o);
}

static hid_t open_ro(const char *path)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0)
        fail_msg("HDF5 cannot open %s", path);
    return f;
}

static bool exists(hid_t f, const char *name)
{
    htri_t e = H5Lexists(f, name, H5P_DEFAULT);
    assert_true(e >= 0);
    return e > 0;
}

/* Asserts that dataset name has exactly the file type and the shape given. */
static void assert_dataset(hid_t f, const char *name, hid_t type, int rank, hsize_t d0,
                           hsize_t d1, hsize_t d2)
{
    if (!exists(f, name))
        fail_msg("%s is missing", name);
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    assert_true(ds >= 0);
    hid_t t = H5Dget_type(ds), space = H5Dget_space(ds);
    if (H5Tequal(t, type) <= 0)
        fail_msg("%s has the wrong type (class %d, size %zu)", name, (int)H5Tget_class(t),
                 H5Tget_size(t));
    hsize_t dims[3] = {0}, want[3] = {d0, d1, d2};
    assert_int_equal(H5Sget_simple_extent_ndims(space), rank);
    H5Sget_simple_extent_dims(space, dims, NULL);
    for (int k = 0; k < rank; k++)
        if (dims[k] != want[k])
            fail_msg("%s dimension %d is %llu, expected %llu", name, k,
                     (unsigned long long)dims[k], (unsigned long long)want[k]);
    H5Sclose(space);
    H5Tclose(t);
    H5Dclose(ds);
}

static void read_dataset(hid_t f, const char *name, hid_t mem_type, void *buf)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    assert_true(ds >= 0);
    assert_true(H5Dread(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    H5Dclose(ds);
}

/* A scalar string attribute of object obj (a path), read as stored; caller frees. */
static char *read_string_attr(hid_t f, const char *obj, const char *name)
{
    hid_t a = H5Aopen_by_name(f, obj, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0)
        fail_msg("attribute %s of %s is missing", name, obj);
    hid_t t = H5Aget_type(a);
    assert_int_equal(H5Tget_class(t), H5T_STRING);
    assert_int_equal(H5Tget_cset(t), H5T_CSET_UTF8);
    hid_t m = H5Tcopy(H5T_C_S1);
    char *out;
    if (H5Tis_variable_str(t) > 0) {
        char *v = NULL;
        H5Tset_size(m, H5T_VARIABLE);
        H5Tset_cset(m, H5T_CSET_UTF8);
        assert_true(H5Aread(a, m, &v) >= 0);
        out = strdup(v);
        H5free_memory(v);
    } else {
        size_t n = H5Tget_size(t);
        out = calloc(n + 1, 1);
        H5Tset_size(m, n + 1);
        H5Tset_cset(m, H5T_CSET_UTF8);
        assert_true(H5Aread(a, m, out) >= 0);
    }
    H5Tclose(m);
    H5Tclose(t);
    H5Aclose(a);
    return out;
}

static void assert_string_attr(hid_t f, const char *obj, const char *name, const char *want)
{
    char *got = read_string_attr(f, obj, name);
    if (strcmp(got, want) != 0)
        fail_msg("attribute %s of %s is \"%s\", expected \"%s\"", name, obj, got, want);
    free(got);
}

/* A numeric attribute of the root: checks its file type and element count, reads it. */
static void read_root_attr(hid_t f, const char *name, hid_t type, hssize_t n, hid_t mem,
                           void *buf)
{
    hid_t a = H5Aopen(f, name, H5P_DEFAULT);
    if (a < 0)
        fail_msg("root attribute %s is missing", name);
    hid_t t = H5Aget_type(a), space = H5Aget_space(a);
    if (H5Tequal(t, type) <= 0)
        fail_msg("root attribute %s has the wrong type", name);
    assert_int_equal(H5Sget_simple_extent_npoints(space), n);
    assert_true(H5Aread(a, mem, buf) >= 0);
    H5Sclose(space);
    H5Tclose(t);
    H5Aclose(a);
}

/* The `count` attribute of group (u64): its complete rows. */
static uint64_t read_count(hid_t f, const char *group)
{
    hid_t a = H5Aopen_by_name(f, group, "count", H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0)
        fail_msg("attribute count of %s is missing", group);
    hid_t t = H5Aget_type(a);
    assert_true(H5Tequal(t, H5T_STD_U64LE) > 0);
    uint64_t c = 0;
    assert_true(H5Aread(a, H5T_NATIVE_UINT64, &c) >= 0);
    H5Tclose(t);
    H5Aclose(a);
    return c;
}

static void assert_bits_equal(const void *got, const void *want, size_t bytes, const char *what)
{
    if (memcmp(got, want, bytes) != 0)
        fail_msg("%s differs from what was written", what);
}

/* Checks that path holds frames 0..n_frames-1 as write_run wrote them. */
static void assert_frames(const char *path, size_t n, int n_frames, bool velocity)
{
    hid_t f = open_ro(path);
    assert_dataset(f, "/frames/step", H5T_STD_I64LE, 1, (hsize_t)n_frames, 0, 0);
    assert_dataset(f, "/frames/time", H5T_IEEE_F64LE, 1, (hsize_t)n_frames, 0, 0);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, (hsize_t)n_frames, n, 3);
    int64_t steps[N_FRAMES];
    double times[N_FRAMES];
    read_dataset(f, "/frames/step", H5T_NATIVE_INT64, steps);
    read_dataset(f, "/frames/time", H5T_NATIVE_DOUBLE, times);
    nbep_vec3 *pos = calloc((size_t)n_frames * n, sizeof *pos);
    nbep_vec3 *vel = calloc((size_t)n_frames * n, sizeof *vel);
    read_dataset(f, "/frames/position", H5T_NATIVE_DOUBLE, pos);
    if (velocity) {
        assert_dataset(f, "/frames/velocity", H5T_IEEE_F64LE, 3, (hsize_t)n_frames, n, 3);
        read_dataset(f, "/frames/velocity", H5T_NATIVE_DOUBLE, vel);
    }
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_state want;
    assert_int_equal(nbep_state_init(&want, n, 0, &d), NBEP_OK);
    for (int k = 0; k < n_frames; k++) {
        assert_int_equal(steps[k], (int64_t)k * FRAME_EVERY);
        double t = (double)(k * FRAME_EVERY) * DT;
        assert_bits_equal(&times[k], &t, sizeof t, "/frames/time");
        fill_frame(&want, k);
        assert_bits_equal(pos + (size_t)k * n, want.pos, n * sizeof *pos, "/frames/position");
        if (velocity)
            assert_bits_equal(vel + (size_t)k * n, want.vel, n * sizeof *vel,
                              "/frames/velocity");
    }
    nbep_state_fini(&want);
    nbep_diag_fini(&d);
    free(pos);
    free(vel);
    H5Fclose(f);
}

/* ---- layout -------------------------------------------------------------------------------- */

static void test_every_spec_path_exists_with_its_type_and_shape(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_summary sum = known_summary();
    write_run(fx, nbep_test_tmp("output_layout.h5", path, sizeof path), &sum);
    hid_t f = open_ro(path);
    assert_dataset(f, "/spheres/radius", H5T_IEEE_F64LE, 1, N_SPHERES, 0, 0);
    assert_dataset(f, "/spheres/mass", H5T_IEEE_F64LE, 1, N_SPHERES, 0, 0);
    assert_dataset(f, "/spheres/acceleration", H5T_IEEE_F64LE, 2, N_SPHERES, 3, 0);
    assert_dataset(f, "/planes/normal", H5T_IEEE_F64LE, 2, N_PLANES, 3, 0);
    assert_dataset(f, "/planes/offset", H5T_IEEE_F64LE, 1, N_PLANES, 0, 0);
    assert_dataset(f, "/frames/step", H5T_STD_I64LE, 1, N_FRAMES, 0, 0);
    assert_dataset(f, "/frames/time", H5T_IEEE_F64LE, 1, N_FRAMES, 0, 0);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, N_FRAMES, N_SPHERES, 3);
    assert_dataset(f, "/frames/velocity", H5T_IEEE_F64LE, 3, N_FRAMES, N_SPHERES, 3);
    assert_dataset(f, "/stats/step", H5T_STD_I64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/checks", H5T_STD_U64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/predictions", H5T_STD_U64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/collisions", H5T_STD_U64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/kinetic_energy", H5T_IEEE_F64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/potential_energy", H5T_IEEE_F64LE, 1, N_STATS, 0, 0);
    assert_dataset(f, "/stats/max_overlap", H5T_IEEE_F64LE, 1, N_STATS, 0, 0);
    assert_true(H5Aexists_by_name(f, "/summary", "json", H5P_DEFAULT) > 0);
    assert_int_equal(read_count(f, "/frames"), N_FRAMES);
    assert_int_equal(read_count(f, "/stats"), N_STATS);
    H5Fclose(f);
}

static void test_sphere_and_plane_arrays_read_back_bit_for_bit(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_bodies.h5", path, sizeof path), NULL);
    const nbep_state *s = &fx->sc.state;
    double radius[N_SPHERES], mass[N_SPHERES], offset[N_PLANES];
    nbep_vec3 acc[N_SPHERES], normal[N_PLANES];
    hid_t f = open_ro(path);
    read_dataset(f, "/spheres/radius", H5T_NATIVE_DOUBLE, radius);
    read_dataset(f, "/spheres/mass", H5T_NATIVE_DOUBLE, mass);
    read_dataset(f, "/spheres/acceleration", H5T_NATIVE_DOUBLE, acc);
    read_dataset(f, "/planes/normal", H5T_NATIVE_DOUBLE, normal);
    read_dataset(f, "/planes/offset", H5T_NATIVE_DOUBLE, offset);
    H5Fclose(f);
    assert_bits_equal(radius, s->radius, sizeof radius, "/spheres/radius");
    assert_bits_equal(mass, s->mass, sizeof mass, "/spheres/mass");
    assert_bits_equal(acc, s->acc, sizeof acc, "/spheres/acceleration");
    assert_bits_equal(normal, s->plane_normal, sizeof normal, "/planes/normal");
    assert_bits_equal(offset, s->plane_offset, sizeof offset, "/planes/offset");
}

static void test_frames_read_back_bit_for_bit_with_their_steps_and_times(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_frames.h5", path, sizeof path), NULL);
    assert_frames(path, N_SPHERES, N_FRAMES, true);
}

/* Asserts chunked layout with chunk shape c, unlimited first dimension, fixed others. */
static void assert_extendable(hid_t f, const char *name, int rank, const hsize_t *chunk)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    assert_true(ds >= 0);
    hid_t dcpl = H5Dget_create_plist(ds), space = H5Dget_space(ds);
    assert_int_equal(H5Pget_layout(dcpl), H5D_CHUNKED);
    hsize_t got[3] = {0}, dims[3], maxdims[3];
    assert_int_equal(H5Pget_chunk(dcpl, 3, got), rank);
    for (int k = 0; k < rank; k++)
        if (got[k] != chunk[k])
            fail_msg("%s chunk dimension %d is %llu, expected %llu", name, k,
                     (unsigned long long)got[k], (unsigned long long)chunk[k]);
    H5Sget_simple_extent_dims(space, dims, maxdims);
    assert_true(maxdims[0] == H5S_UNLIMITED);
    for (int k = 1; k < rank; k++)
        assert_true(maxdims[k] == dims[k]);
    H5Sclose(space);
    H5Pclose(dcpl);
    H5Dclose(ds);
}

static void test_frame_and_stats_datasets_are_chunked_and_extendable(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_chunks.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    hsize_t frame_chunk[3] = {1, N_SPHERES, 3};
    assert_extendable(f, "/frames/position", 3, frame_chunk);
    assert_extendable(f, "/frames/velocity", 3, frame_chunk);
    hsize_t series[1] = {512}, stats[1] = {4096};
    assert_extendable(f, "/frames/step", 1, series);
    assert_extendable(f, "/frames/time", 1, series);
    assert_extendable(f, "/stats/step", 1, stats);
    assert_extendable(f, "/stats/max_overlap", 1, stats);
    H5Fclose(f);
}

/* 4 MiB / (3 doubles) spheres per chunk at most: 174762; 200000 spheres take two chunks,
 * of 100000 each (HDF5 stores a last chunk whole: chunks of 174762 would store 349524); an odd
 * count, 200001, two of 100001 (chunks of 100000 would be three, the last of one sphere
 * stored as 100000). */
static void huge_frame_in_equal_chunks(void **state, size_t n, size_t per_chunk)
{
    nbep_diag d;
    nbep_diag_init(&d);
    fixture *fx = *state;
    nbep_scene sc = fx->sc;
    assert_int_equal(nbep_state_init(&sc.state, n, 0, &d), NBEP_OK);
    sc.out_velocity = sc.out_stats = false;
    fill_frame(&sc.state, 2);
    char path[256];
    nbep_output *o = NULL;
    nbep_test_tmp("output_huge.h5", path, sizeof path);
    assert_ok(nbep_output_create(path, &sc, 1, &o, &d), &d);
    assert_ok(nbep_output_frame(o, 0, DT, &sc.state, &d), &d);
    assert_ok(nbep_output_close(&o, NULL, &d), &d);
    hid_t f = open_ro(path);
    hsize_t chunk[3] = {1, per_chunk, 3};
    assert_extendable(f, "/frames/position", 3, chunk);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, 1, n, 3);
    nbep_vec3 *pos = calloc(n, sizeof *pos);
    read_dataset(f, "/frames/position", H5T_NATIVE_DOUBLE, pos);
    assert_bits_equal(pos, sc.state.pos, n * sizeof *pos, "/frames/position");
    free(pos);
    H5Fclose(f);
    nbep_state_fini(&sc.state);
    nbep_diag_fini(&d);
}

static void test_a_huge_frame_is_split_into_equal_chunks_of_at_most_4_mib(void **state)
{
    huge_frame_in_equal_chunks(state, 200000, 100000);
    huge_frame_in_equal_chunks(state, 200001, 100001);
}

static void test_stats_rows_read_back_in_order_across_batches(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_stats.h5", path, sizeof path), NULL);
    int64_t step[N_STATS];
    uint64_t checks[N_STATS], predictions[N_STATS], collisions[N_STATS];
    double ke[N_STATS], pe[N_STATS], overlap[N_STATS];
    hid_t f = open_ro(path);
    read_dataset(f, "/stats/step", H5T_NATIVE_INT64, step);
    read_dataset(f, "/stats/checks", H5T_NATIVE_UINT64, checks);
    read_dataset(f, "/stats/predictions", H5T_NATIVE_UINT64, predictions);
    read_dataset(f, "/stats/collisions", H5T_NATIVE_UINT64, collisions);
    read_dataset(f, "/stats/kinetic_energy", H5T_NATIVE_DOUBLE, ke);
    read_dataset(f, "/stats/potential_energy", H5T_NATIVE_DOUBLE, pe);
    read_dataset(f, "/stats/max_overlap", H5T_NATIVE_DOUBLE, overlap);
    H5Fclose(f);
    for (int r = 0; r < N_STATS; r++) {
        nbep_step_stats want = stats_row(r);
        assert_int_equal(step[r], want.step);
        assert_int_equal(checks[r], want.checks);
        assert_int_equal(predictions[r], want.predictions);
        assert_int_equal(collisions[r], want.collisions);
        assert_bits_equal(&ke[r], &want.kinetic_energy, sizeof ke[r], "/stats/kinetic_energy");
        assert_bits_equal(&pe[r], &want.potential_energy, sizeof pe[r],
                          "/stats/potential_energy");
        assert_bits_equal(&overlap[r], &want.max_overlap, sizeof overlap[r],
                          "/stats/max_overlap");
    }
}

static void test_root_attributes_hold_the_settings_the_deck_and_the_build(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_attrs.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    assert_string_attr(f, "/", "format", "nbep-1");
    assert_string_attr(f, "/", "version", NBEP_VERSION);
    assert_string_attr(f, "/", "algorithm", "predictive");
    assert_string_attr(f, "/", "neighbors", "all"); /* the fixture's run.neighbors, run.order */
    assert_string_attr(f, "/", "order", "time");
    assert_string_attr(f, "/", "deck", deck_text);
    assert_string_attr(f, "/", "overrides", overrides);
    char *flags = read_string_attr(f, "/", "build_flags");
    assert_true(strlen(flags) > 0);
    free(flags);
    free(read_string_attr(f, "/", "build_commit"));
    uint64_t steps, seed;
    int64_t threads;
    double dt, restitution, gravity[3];
    read_root_attr(f, "steps", H5T_STD_U64LE, 1, H5T_NATIVE_UINT64, &steps);
    read_root_attr(f, "seed", H5T_STD_U64LE, 1, H5T_NATIVE_UINT64, &seed);
    read_root_attr(f, "threads", H5T_STD_I64LE, 1, H5T_NATIVE_INT64, &threads);
    read_root_attr(f, "dt", H5T_IEEE_F64LE, 1, H5T_NATIVE_DOUBLE, &dt);
    read_root_attr(f, "restitution", H5T_IEEE_F64LE, 1, H5T_NATIVE_DOUBLE, &restitution);
    read_root_attr(f, "gravity", H5T_IEEE_F64LE, 3, H5T_NATIVE_DOUBLE, gravity);
    double box[2][3];
    read_root_attr(f, "box_min", H5T_IEEE_F64LE, 3, H5T_NATIVE_DOUBLE, box[0]);
    read_root_attr(f, "box_max", H5T_IEEE_F64LE, 3, H5T_NATIVE_DOUBLE, box[1]);
    H5Fclose(f);
    assert_int_equal(steps, N_STATS);
    assert_int_equal(seed, 424242);
    assert_int_equal(threads, 3);   /* the resolved count given to create, not the deck's 0 */
    double want_dt = DT, want_e = 0.85, want_g[3] = {0.25, -1.5, -9.81};
    assert_bits_equal(&dt, &want_dt, sizeof dt, "dt");
    assert_bits_equal(&restitution, &want_e, sizeof dt, "restitution");
    assert_bits_equal(gravity, want_g, sizeof gravity, "gravity");
    const double want_box[2][3] = {{-1.0, -2.0, 0.0}, {4.0, 5.5, 6.25}};
    assert_bits_equal(box, want_box, sizeof box, "box");
}

static void test_a_deck_larger_than_an_object_header_is_stored_whole(void **state)
{
    fixture *fx = *state;
    /* 100 kB: beyond the 64 KiB an attribute may take inside an object header. */
    size_t len = 100000;
    char *deck = malloc(len + 1);
    for (size_t k = 0; k < len; k++)
        deck[k] = k % 61 == 60 ? '\n' : (char)('a' + k % 26);
    deck[len] = '\0';
    fx->sc.deck_text = deck;
    char path[256];
    write_run(fx, nbep_test_tmp("output_bigdeck.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    assert_string_attr(f, "/", "deck", deck);
    H5Fclose(f);
    free(deck);
}

static void test_summary_attribute_is_the_json_text(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_summary sum = known_summary();
    write_run(fx, nbep_test_tmp("output_summary.h5", path, sizeof path), &sum);
    char *json = nbep_summary_to_json(&sum);
    assert_non_null(json);
    hid_t f = open_ro(path);
    assert_string_attr(f, "/summary", "json", json);
    H5Fclose(f);
    free(json);
}

/* A file closed without a summary (a run that did not get to write one) has no /summary at all:
 * SPEC's /summary is the carrier of its json (until 2026-12-01 an empty group was made with the
 * file, and a script's "'summary' in f" took a killed run's file for a finished one's) */
static void test_closing_without_a_summary_leaves_no_summary_group(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_nosummary.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    const bool has = exists(f, "/summary");
    H5Fclose(f);
    assert_false(has);
}

static void test_velocity_not_asked_for_is_not_created(void **state)
{
    fixture *fx = *state;
    fx->sc.out_velocity = false;
    char path[256];
    write_run(fx, nbep_test_tmp("output_novel.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    assert_false(exists(f, "/frames/velocity"));
    H5Fclose(f);
    assert_frames(path, N_SPHERES, N_FRAMES, false);
}

static void test_position_not_asked_for_is_not_created(void **state)
{
    fixture *fx = *state;
    fx->sc.out_position = false;
    char path[256];
    write_run(fx, nbep_test_tmp("output_nopos.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    assert_false(exists(f, "/frames/position"));
    assert_dataset(f, "/frames/velocity", H5T_IEEE_F64LE, 3, N_FRAMES, N_SPHERES, 3);
    assert_dataset(f, "/frames/step", H5T_STD_I64LE, 1, N_FRAMES, 0, 0);
    H5Fclose(f);
}

static void test_stats_not_asked_for_leave_no_stats_group(void **state)
{
    fixture *fx = *state;
    fx->sc.out_stats = false;
    char path[256];
    write_run(fx, nbep_test_tmp("output_nostats.h5", path, sizeof path), NULL);
    hid_t f = open_ro(path);
    assert_false(exists(f, "/stats"));
    H5Fclose(f);
}

static void test_a_scene_without_spheres_or_planes_still_records_frames(void **state)
{
    fixture *fx = *state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_scene sc = fx->sc;
    assert_int_equal(nbep_state_init(&sc.state, 0, 0, &d), NBEP_OK);
    char path[256];
    nbep_output *o = NULL;
    nbep_test_tmp("output_empty.h5", path, sizeof path);
    assert_ok(nbep_output_create(path, &sc, 1, &o, &d), &d);
    assert_ok(nbep_output_frame(o, 0, DT, &sc.state, &d), &d);
    assert_ok(nbep_output_frame(o, 10, DT, &sc.state, &d), &d);
    assert_ok(nbep_output_close(&o, NULL, &d), &d);
    hid_t f = open_ro(path);
    assert_dataset(f, "/spheres/radius", H5T_IEEE_F64LE, 1, 0, 0, 0);
    assert_dataset(f, "/planes/normal", H5T_IEEE_F64LE, 2, 0, 3, 0);
    assert_dataset(f, "/planes/offset", H5T_IEEE_F64LE, 1, 0, 0, 0);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, 2, 0, 3);
    assert_dataset(f, "/frames/step", H5T_STD_I64LE, 1, 2, 0, 0);
    H5Fclose(f);
    nbep_state_fini(&sc.state);
    nbep_diag_fini(&d);
}

/* ---- handles and errors -------------------------------------------------------------------- */

static void test_closing_releases_every_hdf5_id(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_summary sum = known_summary();
    write_run(fx, nbep_test_tmp("output_ids.h5", path, sizeof path), &sum);
    assert_int_equal(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0);
}

static void test_closing_a_null_handle_does_nothing(void **state)
{
    fixture *fx = *state;
    nbep_output *o = NULL;
    assert_int_equal(nbep_output_close(&o, NULL, &fx->d), NBEP_OK);
    assert_int_equal(nbep_output_close(NULL, NULL, &fx->d), NBEP_OK);
    assert_int_equal(fx->d.n_errors, 0);
}

static void assert_no_file(const char *path)
{
    struct stat st;
    if (stat(path, &st) == 0 || errno != ENOENT)
        fail_msg("%s exists", path);
}

/* The one message d holds must be a single line that starts "nbep: PATH: " */
static void assert_one_line_naming(const nbep_diag *d, const char *path)
{
    assert_int_equal(d->n_errors, 1);
    char prefix[300];
    snprintf(prefix, sizeof prefix, "nbep: %s: ", path);
    if (strncmp(d->msg[0], prefix, strlen(prefix)) != 0)
        fail_msg("message \"%s\" does not start with \"%s\"", d->msg[0], prefix);
    assert_null(strchr(d->msg[0], '\n'));
}

/* (exit 2: a missing directory is the user's to fix, like a missing deck) */
static void test_a_path_in_a_missing_directory_fails_as_usage_naming_the_path(void **state)
{
    fixture *fx = *state;
    const char *path = "/nonexistent-dir/x.h5";
    nbep_output *o = NULL;
    assert_int_equal(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), NBEP_EUSAGE);
    assert_null(o);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "No such file or directory"));
}

static void test_a_path_naming_a_directory_fails_and_leaves_the_directory(void **state)
{
    fixture *fx = *state;
    const char *path = "build/tests/tmp";
    nbep_output *o = NULL;
    assert_int_equal(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), NBEP_EUSAGE);
    assert_null(o);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "Is a directory"));
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    assert_no_file("build/tests/tmp.partial");
}

static void test_a_failure_after_the_file_was_created_leaves_no_file(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_removed.h5", path, sizeof path);
    /* A sphere count no dataspace can hold makes /spheres/radius fail after the file and its
     * root attributes exist (no array is read: the dataspace fails first). */
    nbep_scene sc = fx->sc;
    sc.state.n = SIZE_MAX;
    nbep_output *o = NULL;
    assert_int_equal(nbep_output_create(path, &sc, 1, &o, &fx->d), NBEP_EIO);
    assert_null(o);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "/spheres/radius"));
    assert_no_file(path);
    assert_no_file(strcat(path, ".partial"));
}

static void test_a_failed_create_keeps_an_older_file_at_the_path(void **state)
{
    fixture *fx = *state;
    char path[256];
    FILE *f = fopen(nbep_test_tmp("output_older.h5", path, sizeof path), "w");
    assert_non_null(f);
    fputs("an older run", f);
    fclose(f);
    nbep_scene sc = fx->sc;
    sc.state.n = SIZE_MAX;   /* fails after the file was made, as above */
    nbep_output *o = NULL;
    assert_int_equal(nbep_output_create(path, &sc, 1, &o, &fx->d), NBEP_EIO);
    char text[64] = {0};
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(text, sizeof text, f));
    fclose(f);
    assert_string_equal(text, "an older run");
}

static void test_a_frame_with_a_non_finite_position_is_refused(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_output *o = NULL;
    nbep_test_tmp("output_nan.h5", path, sizeof path);
    assert_ok(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), &fx->d);
    assert_ok(nbep_output_frame(o, 0, DT, &fx->sc.state, &fx->d), &fx->d);
    fx->sc.state.pos[2].y = NAN;
    assert_int_equal(nbep_output_frame(o, 10, DT, &fx->sc.state, &fx->d), NBEP_ENUMERIC);
    assert_one_line_naming(&fx->d, path);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    hid_t f = open_ro(path);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, 1, N_SPHERES, 3);
    H5Fclose(f);
}

/* A periodic axis's count of periods crossed beyond /frames/image's int32 (a sphere run away
 * to DBL_MAX along z, 3e307 periods out): the frame is refused, one line naming the file and
 * the sphere, and the file keeps the frames before it (until 2026-12-03 the wrap left such a
 * position unwrapped, written as it was) */
static void test_a_frame_beyond_the_image_count_is_refused(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_output *o = NULL;
    fx->sc.periodic[2] = true;
    nbep_test_tmp("output_far_image.h5", path, sizeof path);
    assert_ok(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), &fx->d);
    assert_ok(nbep_output_frame(o, 0, DT, &fx->sc.state, &fx->d), &fx->d);
    fx->sc.state.pos[2].z = DBL_MAX;
    assert_int_equal(nbep_output_frame(o, 10, DT, &fx->sc.state, &fx->d), NBEP_ENUMERIC);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "step 10: sphere 2 has crossed the periodic box more "
                                         "than 2^31 times along an axis"));
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    hid_t f = open_ro(path);
    assert_int_equal(read_count(f, "/frames"), 1);
    assert_dataset(f, "/frames/position", H5T_IEEE_F64LE, 3, 1, N_SPHERES, 3);
    H5Fclose(f);
}

/* ---- crashes ------------------------------------------------------------------------------- */

/* Child codes: which step failed (the child cannot use cmocka's asserts). */
enum { CHILD_CREATE = 11, CHILD_FRAME, CHILD_STATS, CHILD_CLOSE, CHILD_PIPE };

/* In a child process: creates path, writes n_frames frames and some stats rows, then dies
 * without closing: by SIGKILL (kill9) or by _exit(0). */
static void child_write_and_die(fixture *fx, const char *path, int n_frames, bool kill9)
{
    nbep_output *o = NULL;
    if (nbep_output_create(path, &fx->sc, 2, &o, &fx->d) != NBEP_OK)
        _exit(CHILD_CREATE);
    nbep_step_stats rows[N_STATS];
    for (int r = 0; r < N_STATS; r++)
        rows[r] = stats_row(r);
    if (nbep_output_stats(o, rows, NULL, N_STATS, &fx->d) != NBEP_OK)
        _exit(CHILD_STATS);
    for (int k = 0; k < n_frames; k++) {
        fill_frame(&fx->sc.state, k);
        if (nbep_output_frame(o, (int64_t)k * FRAME_EVERY, DT, &fx->sc.state, &fx->d) != NBEP_OK)
            _exit(CHILD_FRAME);
    }
    if (kill9)
        raise(SIGKILL);
    _exit(0);
}

static void run_crashing_child(fixture *fx, const char *path, bool kill9)
{
    fflush(NULL);   /* or the child's stdio buffers would hold a copy of ours */
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0)
        child_write_and_die(fx, path, N_FRAMES, kill9);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    if (kill9) {
        assert_true(WIFSIGNALED(status));
        assert_int_equal(WTERMSIG(status), SIGKILL);
    } else {
        assert_true(WIFEXITED(status));
        assert_int_equal(WEXITSTATUS(status), 0);
    }
}

static void test_a_run_killed_between_frames_leaves_every_frame_written(void **state)
{
    fixture *fx = *state;
    char path[256];
    run_crashing_child(fx, nbep_test_tmp("output_kill9.h5", path, sizeof path), true);
    assert_frames(path, N_SPHERES, N_FRAMES, true);
    hid_t f = open_ro(path);
    assert_dataset(f, "/stats/checks", H5T_STD_U64LE, 1, N_STATS, 0, 0);
    assert_int_equal(read_count(f, "/frames"), N_FRAMES);
    assert_int_equal(read_count(f, "/stats"), N_STATS);
    assert_string_attr(f, "/", "format", "nbep-1");
    const bool has = exists(f, "/summary"); /* the run never got to its summary */
    H5Fclose(f);
    assert_false(has);
}

static void test_a_process_exiting_without_closing_leaves_three_frames(void **state)
{
    fixture *fx = *state;
    char path[256];
    run_crashing_child(fx, nbep_test_tmp("output_exit.h5", path, sizeof path), false);
    assert_frames(path, N_SPHERES, N_FRAMES, true);
}

static void test_the_chunk_index_holds_every_planned_frame_without_splitting(void **state)
{
    fixture *fx = *state;
    nbep_scene sc = fx->sc;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_state_init(&sc.state, 10000, 0, &d), NBEP_OK);
    sc.steps = 10000;
    sc.output_every = 10;   /* frames at 0, 10, ..., 10000: 1001 */
    char path[256];
    nbep_output *o = NULL;
    nbep_test_tmp("output_index_k.h5", path, sizeof path);
    assert_ok(nbep_output_create(path, &sc, 1, &o, &d), &d);
    assert_ok(nbep_output_close(&o, NULL, &d), &d);
    hid_t f = open_ro(path), fcpl = H5Fget_create_plist(f);
    unsigned k = 0;
    assert_true(H5Pget_istore_k(fcpl, &k) >= 0);
    H5Pclose(fcpl);
    H5Fclose(f);
    /* A v1 B-tree node holds up to 2K entries: one chunk per frame. */
    assert_true(2 * k >= 1001);
    nbep_state_fini(&sc.state);
    nbep_diag_fini(&d);
}

static void test_h5dump_reads_the_file_of_a_killed_run(void **state)
{
    fixture *fx = *state;
    if (system("command -v h5dump >/dev/null 2>&1") != 0)
        skip();
    char path[256], cmd[400];
    run_crashing_child(fx, nbep_test_tmp("output_kill9_dump.h5", path, sizeof path), true);
    snprintf(cmd, sizeof cmd, "h5dump -d /frames/step %s >/dev/null 2>&1", path);
    assert_int_equal(system(cmd), 0);
}

/* ---- info ---------------------------------------------------------------------------------- */

/* nbep_output_info's text for path (caller frees) and its status, without failing the test.
 * Text and status come back separately (no char ** out-parameter): GCC 12 at -O3 mistakes an
 * address-taken local here for a dangling pointer (a -Wdangling-pointer false positive). */
static char *info_try(const char *path, nbep_status *st, nbep_diag *d)
{
    FILE *f = tmpfile();
    assert_non_null(f);
    *st = nbep_output_info(path, f, d);
    long len = ftell(f);
    assert_true(len >= 0);
    char *buf = calloc((size_t)len + 1, 1);
    assert_non_null(buf);
    rewind(f);
    assert_int_equal(fread(buf, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    return buf;
}

/* nbep_output_info's text for path, or fails the test with its messages. Caller frees. */
static char *info_text(const char *path, nbep_diag *d)
{
    nbep_status st;
    char *text = info_try(path, &st, d);
    if (st != NBEP_OK)
        free(text);
    assert_ok(st, d);
    return text;
}

static void assert_has_line(const char *text, const char *line)
{
    const char *p = strstr(text, line);
    if (!p || (p != text && p[-1] != '\n') || (p[strlen(line)] != '\n'))
        fail_msg("no line \"%s\" in:\n%s", line, text);
}

static void test_info_reports_the_settings_frames_stats_and_summary(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_summary sum = known_summary();
    fx->sc.tc = 2.5e-6; /* the collision model's settings at e < 1 (since 2026-12-01) */
    fx->sc.carry_drop = 0.03;
    write_run(fx, nbep_test_tmp("output_info.h5", path, sizeof path), &sum);
    char *text = info_text(path, &fx->d);
    char *json = nbep_summary_to_json(&sum);
    json[strlen(json) - 1] = '\0';   /* the line without its newline */
    char summary_line[1024];
    snprintf(summary_line, sizeof summary_line, "summary:     %s", json);
    assert_has_line(text, "format:      nbep-1");
    assert_has_line(text, "algorithm:   predictive (neighbors all, order time)");
    assert_has_line(text, "spheres:     5");
    assert_has_line(text, "planes:      2");
    assert_has_line(text, "steps asked: 20");
    assert_has_line(text, "dt:          0.00125");
    assert_has_line(text, "threads:     3");
    assert_has_line(text, "seed:        424242");
    assert_has_line(text, "restitution: 0.85");
    assert_has_line(text, "contacts:    tc 2.5e-06, carry_drop 0.03");
    assert_has_line(text, "gravity:     [0.25, -1.5, -9.81]");
    assert_has_line(text, "box:         [-1, -2, 0] to [4, 5.5, 6.25]");
    assert_has_line(text, "overrides:   physics.restitution=0.85");
    assert_has_line(text, "             run.steps=20");
    assert_has_line(text, "frames:      3 (last: step 20, time 0.025)");
    assert_has_line(text, "stats rows:  20");
    assert_has_line(text, "status:      terminated (SIGTERM, SIGHUP, SIGUSR1 or SIGUSR2): step "
                          "1000 of 2500");
    assert_has_line(text, summary_line);
    free(json);
    free(text);
    /* a summary without a status (an nbep before 2026-11-30 wrote none; null here) is shown
     * as it is, the status unknown, against the file's own run.steps */
    sum.status = NBEP_SUMMARY_UNKNOWN;
    sum.steps_requested = (nbep_summary_count){.known = false};
    write_run(fx, nbep_test_tmp("output_info_older.h5", path, sizeof path), &sum);
    text = info_text(path, &fx->d);
    assert_has_line(text, "status:      unknown (the summary is older than its status key): "
                          "step 1000 of 20");
    free(text);
    sum.status = NBEP_SUMMARY_COMPLETED;
    fx->sc.restitution = 1.0; /* elastic: the model has nothing to say, and no line */
    write_run(fx, nbep_test_tmp("output_info_done.h5", path, sizeof path), &sum);
    text = info_text(path, &fx->d);
    assert_has_line(text, "status:      completed: step 1000 of 20");
    assert_null(strstr(text, "contacts:"));
    free(text);
}

/* SPEC contract 2: root attribute `periodic`, 3 x int, 0 or 1 per axis; nbep info names the
 * periodic axes. Two of three, so that an axis read or written as another is seen (every test
 * before had all three or none). */
static void test_periodic_axes_are_the_attribute_and_info_names_them(void **state)
{
    fixture *fx = *state;
    char path[256];
    fx->sc.periodic[0] = fx->sc.periodic[2] = true;
    /* one frame: write_run's second puts a sphere at z = DBL_MAX, a count of periods no
     * frame can hold (test_a_frame_beyond_the_image_count_is_refused) */
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(nbep_test_tmp("output_periodic_xz.h5", path, sizeof path),
                                 &fx->sc, 1, &o, &fx->d),
              &fx->d);
    fill_frame(&fx->sc.state, 0);
    assert_ok(nbep_output_frame(o, 0, DT, &fx->sc.state, &fx->d), &fx->d);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t a = H5Aopen(f, "periodic", H5P_DEFAULT);
    assert_true(a >= 0);
    int32_t periodic[3] = {-1, -1, -1};
    assert_true(H5Aread(a, H5T_NATIVE_INT32, periodic) >= 0);
    H5Aclose(a);
    H5Fclose(f);
    assert_int_equal(periodic[0], 1);
    assert_int_equal(periodic[1], 0);
    assert_int_equal(periodic[2], 1);
    char *text = info_text(path, &fx->d);
    assert_has_line(text, "periodic:    xz");
    free(text);
}

/* A periodic box's frames hold each position wrapped into the box and the state's image
 * counts plus the periods the wrap removed, frame by frame (the state's images are not the
 * frame's: the algorithm keeps positions a little outside at times). Periodic in x (period 5,
 * from -1) and z (6.25, from 0): sphere i of frame k at a point of the box (dyadic, so the
 * shifts are exact) moved m = (i + k) % 3 - 1 periods in x and -m in z, its state images
 * (k - i, 7, 2 k): the frame has the point and (k - i + m, 7, 2 k - m). */
static void test_periodic_frames_hold_wrapped_positions_and_the_images_added(void **state)
{
    fixture *fx = *state;
    char path[256];
    fx->sc.periodic[0] = fx->sc.periodic[2] = true;
    fx->sc.out_stats = false;
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(nbep_test_tmp("output_images.h5", path, sizeof path), &fx->sc,
                                 1, &o, &fx->d),
              &fx->d);
    nbep_state *s = &fx->sc.state;
    const nbep_vec3 lo = fx->sc.box_min;
    const double len_x = fx->sc.box_max.x - lo.x, len_z = fx->sc.box_max.z - lo.z;
    nbep_vec3 want_pos[N_FRAMES][N_SPHERES];
    int32_t want_img[N_FRAMES][N_SPHERES][3];
    for (int k = 0; k < N_FRAMES; k++) {
        for (size_t i = 0; i < N_SPHERES; i++) {
            const nbep_vec3 in = {lo.x + 0.25 + 0.75 * (double)i, 1.5 - 0.5 * (double)k,
                                  lo.z + 0.125 + 1.25 * (double)i};
            const int m = (int)((i + (size_t)k) % 3) - 1;
            s->pos[i] = nbep_vec3_make(in.x + m * len_x, in.y, in.z - m * len_z);
            const int32_t img[3] = {k - (int32_t)i, 7, 2 * k};
            memcpy(&s->image[3 * i], img, sizeof img);
            want_pos[k][i] = in;
            want_img[k][i][0] = img[0] + m;
            want_img[k][i][1] = img[1];
            want_img[k][i][2] = img[2] - m;
        }
        assert_ok(nbep_output_frame(o, (int64_t)k * FRAME_EVERY, DT, s, &fx->d), &fx->d);
    }
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    nbep_vec3 pos[N_FRAMES][N_SPHERES];
    int32_t img[N_FRAMES][N_SPHERES][3];
    hid_t f = open_ro(path);
    read_dataset(f, "/frames/position", H5T_NATIVE_DOUBLE, pos);
    read_dataset(f, "/frames/image", H5T_NATIVE_INT32, img);
    H5Fclose(f);
    assert_bits_equal(pos, want_pos, sizeof pos, "/frames/position");
    for (int k = 0; k < N_FRAMES; k++)
        for (size_t i = 0; i < N_SPHERES; i++)
            for (int a = 0; a < 3; a++)
                if (img[k][i][a] != want_img[k][i][a])
                    fail_msg("frame %d sphere %zu axis %d: image %d, not %d", k, i, a,
                             (int)img[k][i][a], (int)want_img[k][i][a]);
}

static void test_info_on_a_killed_run_says_it_has_no_summary(void **state)
{
    fixture *fx = *state;
    char path[256];
    run_crashing_child(fx, nbep_test_tmp("output_info_kill9.h5", path, sizeof path), true);
    char *text = info_text(path, &fx->d);
    assert_has_line(text, "frames:      3 (last: step 20, time 0.025)");
    assert_has_line(text, "status:      unknown (no summary: the run was killed, stopped by a "
                          "write error, or is still running)");
    assert_has_line(text, "summary:     none (run killed, stopped by a write error, or still "
                          "running)");
    free(text);
}

static void test_info_reads_a_run_while_it_is_being_written(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_info_live.h5", path, sizeof path);
    int to_child[2], to_parent[2];
    assert_int_equal(pipe(to_child), 0);
    assert_int_equal(pipe(to_parent), 0);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        /* Each side closes the ends it does not use, so that one side's death ends the other
         * side's read with end-of-file instead of blocking it forever. */
        close(to_child[1]), close(to_parent[0]);
        char c = 0;
        nbep_output *o = NULL;
        if (nbep_output_create(path, &fx->sc, 2, &o, &fx->d) != NBEP_OK)
            _exit(CHILD_CREATE);
        for (int k = 0; k < N_FRAMES; k++) {
            fill_frame(&fx->sc.state, k);
            if (nbep_output_frame(o, (int64_t)k * FRAME_EVERY, DT, &fx->sc.state, &fx->d))
                _exit(CHILD_FRAME);
            /* After two frames: tell the parent, wait for it to have looked. */
            if (k == 1 && (write(to_parent[1], &c, 1) != 1 || read(to_child[0], &c, 1) != 1))
                _exit(CHILD_PIPE);
        }
        nbep_summary sum = known_summary();
        if (nbep_output_close(&o, &sum, &fx->d) != NBEP_OK)
            _exit(CHILD_CLOSE);
        _exit(0);
    }
    close(to_child[0]), close(to_parent[1]);
    char c = 0, *live = NULL;
    ssize_t got = read(to_parent[0], &c, 1);
    nbep_status live_st = NBEP_EIO;
    if (got == 1)
        live = info_try(path, &live_st, &fx->d);
    ssize_t put = write(to_child[1], &c, 1);
    close(to_child[1]), close(to_parent[0]);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    assert_int_equal(got, 1);
    assert_int_equal(put, 1);
    if (live_st != NBEP_OK) {
        free(live);
        assert_ok(live_st, &fx->d);
    }
    assert_has_line(live, "frames:      2 (last: step 10, time 0.0125)");
    assert_has_line(live, "summary:     none (run killed, stopped by a write error, or still "
                          "running)");
    free(live);
    char *text = info_text(path, &fx->d);
    assert_has_line(text, "frames:      3 (last: step 20, time 0.025)");
    assert_non_null(strstr(text, "summary:     {\"format\": \"nbep-summary-1\""));
    free(text);
}

static void test_info_counts_only_the_complete_frames_of_a_run_killed_mid_frame(void **state)
{
    fixture *fx = *state;
    char path[256];
    run_crashing_child(fx, nbep_test_tmp("output_info_torn.h5", path, sizeof path), true);
    /* What a kill during a frame's first flush can leave: rows past the counts. */
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    const char *grown[] = {"/frames/step", "/frames/time", "/stats/step"};
    for (size_t k = 0; k < sizeof grown / sizeof *grown; k++) {
        hid_t ds = H5Dopen2(f, grown[k], H5P_DEFAULT);
        hsize_t rows = (k < 2 ? N_FRAMES : N_STATS) + 1;
        assert_true(H5Dset_extent(ds, &rows) >= 0);
        H5Dclose(ds);
    }
    H5Fclose(f);
    char *text = info_text(path, &fx->d);
    assert_has_line(text, "frames:      3 (last: step 20, time 0.025), and 1 incomplete (being "
                          "written, or its write was cut short: a kill, or a full disk)");
    assert_has_line(text, "stats rows:  20, and incomplete ones after them");
    free(text);
}

/* A count attribute past its dataset's rows (a damaged file: no writer leaves one) is said as
 * such, one line naming the file, the group, its count and the rows there are, instead of a
 * read of a row that is not there. */
static void test_info_refuses_a_count_past_the_rows_naming_both(void **state)
{
    fixture *fx = *state;
    char path[256];
    write_run(fx, nbep_test_tmp("output_info_overcount.h5", path, sizeof path), NULL);
    /* the count stays N_FRAMES, the rows it counts are cut to one fewer */
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t ds = H5Dopen2(f, "/frames/step", H5P_DEFAULT);
    hsize_t rows = N_FRAMES - 1;
    assert_true(ds >= 0 && H5Dset_extent(ds, &rows) >= 0);
    H5Dclose(ds);
    H5Fclose(f);
    nbep_status st;
    char *text = info_try(path, &st, &fx->d);
    free(text);
    assert_int_equal(st, NBEP_EUSAGE); /* exit 2: a file that is not what it should be */
    assert_one_line_naming(&fx->d, path);
    char want[128];
    snprintf(want, sizeof want, "/frames counts %d rows but /frames/step has %d", N_FRAMES,
             N_FRAMES - 1);
    if (!strstr(fx->d.msg[0], want))
        fail_msg("message \"%s\" does not say \"%s\"", fx->d.msg[0], want);
}

/* the wrong file named is the user's mistake too (exit 2), said as what the file is not */
static void test_info_rejects_a_file_that_is_not_hdf5(void **state)
{
    fixture *fx = *state;
    char path[256];
    FILE *f = fopen(nbep_test_tmp("output_text.h5", path, sizeof path), "w");
    assert_non_null(f);
    fputs("run: { steps = 1; };\n", f);
    fclose(f);
    assert_int_equal(nbep_output_info(path, stdout, &fx->d), NBEP_EUSAGE);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "not an HDF5 file"));
}

static void test_info_rejects_an_hdf5_file_without_the_nbep_1_format(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_plain.h5", path, sizeof path);
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(f >= 0);
    H5Fclose(f);
    assert_int_equal(nbep_output_info(path, stdout, &fx->d), NBEP_EUSAGE);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "not an nbep-1 file (root attribute format is missing)"));
}

/* A new HDF5 file at path holding only a root attribute `format` = value, a string of fixed
 * length padded with nulls, as other tools write strings (h5py's numpy bytes: no terminator). */
static void file_with_format(const char *path, const char *value)
{
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t t = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR);
    assert_true(H5Tset_size(t, strlen(value)) >= 0);
    assert_true(H5Tset_strpad(t, H5T_STR_NULLPAD) >= 0);
    hid_t a = H5Acreate2(f, "format", t, space, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(a >= 0 && H5Awrite(a, t, value) >= 0);
    H5Aclose(a);
    H5Sclose(space);
    H5Tclose(t);
    H5Fclose(f);
}

/* A root attribute `format` of fixed length is read whole: the message quotes it to its last
 * character. */
static void test_info_reads_a_fixed_length_format_whole(void **state)
{
    fixture *fx = *state;
    char path[256];
    file_with_format(nbep_test_tmp("output_fixed_format.h5", path, sizeof path), "other-format-2");
    assert_int_equal(nbep_output_info(path, stdout, &fx->d), NBEP_EUSAGE);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], "(root attribute format is \"other-format-2\")"));
}

/* An nbep-1 file without a part every run writes (its /spheres, or a root attribute) is no
 * readable run either: exit 2 as --help says, one line naming the file (until 2026-12-01 exit
 * 1, the status of a failed write; a review). */
static void test_info_rejects_an_nbep_1_file_missing_a_part(void **state)
{
    fixture *fx = *state;
    char path[256];
    file_with_format(nbep_test_tmp("output_no_spheres.h5", path, sizeof path), "nbep-1");
    assert_int_equal(nbep_output_info(path, stdout, &fx->d), NBEP_EUSAGE);
    assert_one_line_naming(&fx->d, path);
}

/* a name that is no file is the user's mistake (exit 2), said with the system's reason */
static void test_info_on_a_missing_file_fails_naming_it(void **state)
{
    fixture *fx = *state;
    const char *path = "build/tests/tmp/output_does_not_exist.h5";
    assert_int_equal(nbep_output_info(path, stdout, &fx->d), NBEP_EUSAGE);
    assert_one_line_naming(&fx->d, path);
    assert_non_null(strstr(fx->d.msg[0], strerror(ENOENT)));
}

/* ---- JSON ---------------------------------------------------------------------------------- */

/* SPEC's keys in SPEC's order; numbers as %.17g: 1000 / 1.5 = 666.66666666666663,
 * 0.25 / -1234.5 = -0.0002025111381125962. */
static const char known_json[] =
    "{\"format\": \"nbep-summary-1\", \"version\": \"" NBEP_VERSION "\", "
    "\"algorithm\": \"predictive\", \"threads\": 2, \"spheres\": 4096, \"planes\": 6, "
    "\"steps\": 1000, \"dt\": 0.001, \"setup_seconds\": 0.25, \"wall_seconds\": 1.5, "
    "\"steps_per_second\": 666.6666666666666, \"checks\": 123456789012, "
    "\"predictions\": 987654321, \"collisions\": 4242, \"sphere_collisions\": 4000, "
    "\"plane_collisions\": 242, \"quiet_steps\": 950, \"energy_initial\": -1234.5, "
    "\"energy_final\": -1234.25, \"energy_rel_drift\": -0.0002025111381125962, "
    "\"max_overlap\": 3e-14, \"max_overlap_rel\": 6e-13, "
    "\"peak_rss_bytes\": 52428800, \"pressure\": null, \"status\": \"terminated\", "
    "\"steps_requested\": 2500}\n";

static void test_json_of_a_known_summary_is_the_expected_text(void **state)
{
    (void)state;
    nbep_summary s = known_summary();
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_string_equal(json, known_json);
    free(json);
}

static void test_json_written_to_a_stream_is_one_line_and_counts_its_bytes(void **state)
{
    (void)state;
    nbep_summary s = known_summary();
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    int n = nbep_summary_write_json(&s, f);
    fclose(f);
    assert_int_equal(n, (int)strlen(known_json));
    assert_string_equal(buf, known_json);
    assert_ptr_equal(strchr(buf, '\n'), buf + len - 1);
    free(buf);
}

static void test_json_parses_with_spec_keys_in_spec_order(void **state)
{
    (void)state;
    if (system("command -v python3 >/dev/null 2>&1") != 0)
        skip();
    char path[256], cmd[1024];
    nbep_summary s = known_summary();
    FILE *f = fopen(nbep_test_tmp("output_summary.json", path, sizeof path), "w");
    assert_non_null(f);
    assert_true(nbep_summary_write_json(&s, f) > 0);
    fclose(f);
    /* An independent JSON parser; the keys as SPEC's "JSON summary" lists them, then those
     * added since (contract 2's pressure; status and steps_requested, README). */
    snprintf(cmd, sizeof cmd,
             "python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); "
             "sys.exit(list(d) != [\"format\", \"version\", \"algorithm\", \"threads\", "
             "\"spheres\", \"planes\", \"steps\", \"dt\", \"setup_seconds\", "
             "\"wall_seconds\", \"steps_per_second\", \"checks\", \"predictions\", "
             "\"collisions\", \"sphere_collisions\", \"plane_collisions\", "
             "\"quiet_steps\", \"energy_initial\", \"energy_final\", "
             "\"energy_rel_drift\", \"max_overlap\", \"max_overlap_rel\", "
             "\"peak_rss_bytes\", \"pressure\", \"status\", \"steps_requested\"] "
             "or d[\"steps_per_second\"] != 1000 / 1.5 or d[\"pressure\"] is not None "
             "or d[\"status\"] != \"terminated\" or d[\"steps_requested\"] != 2500)' %s",
             path);
    assert_int_equal(system(cmd), 0);
}

static void test_json_escapes_quotes_backslashes_and_control_characters(void **state)
{
    (void)state;
    nbep_summary s = known_summary();
    snprintf(s.algorithm, sizeof s.algorithm, "a\"b\\c\td");
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"algorithm\": \"a\\\"b\\\\c\\td\", \"threads\""));
    free(json);
}

/* Reals are written in the fewest digits that read back exactly (a double has one shortest
 * such text of at most 17 digits): 0.05, not jansson's 0.050000000000000003; a whole number
 * as 48000.0 (a real stays a real, and no exponent below 10^15); 17 digits where they are
 * needed; every value reads back bit for bit. */
static void test_json_writes_reals_in_their_shortest_exact_form(void **state)
{
    (void)state;
    static const struct {
        double v;
        const char *text;
    } cases[] = {
        {0.05, "0.05"},       {48000.0, "48000.0"}, {-1.0, "-1.0"},
        {1e20, "1e+20"},      {0.1 + 0.2, "0.30000000000000004"},
        {1.0 / 3.0, "0.3333333333333333"}, {2.5e-300, "2.5e-300"}, {123456789.125, "123456789.125"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        nbep_summary s = known_summary();
        s.dt = cases[k].v;
        char *json = nbep_summary_to_json(&s);
        assert_non_null(json);
        char want[64];
        snprintf(want, sizeof want, "\"dt\": %s, ", cases[k].text);
        if (!strstr(json, want))
            fail_msg("dt = %.17g: wanted %s in %s", cases[k].v, want, json);
        nbep_summary back;
        assert_true(nbep_summary_from_json(json, &back));
        assert_true(back.dt == cases[k].v);
        free(json);
    }
}

static void test_json_keeps_every_digit_of_a_double(void **state)
{
    (void)state;
    nbep_summary s = known_summary();
    s.energy_initial = 0.1 + 0.2;                /* 0.30000000000000004: needs 17 digits */
    s.energy_final = -4.9406564584124654e-324;   /* the smallest subnormal */
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    const char *a = strstr(json, "\"energy_initial\": "), *b = strstr(json, "\"energy_final\": ");
    assert_non_null(a);
    assert_non_null(b);
    assert_true(strtod(a + strlen("\"energy_initial\": "), NULL) == 0.1 + 0.2);
    assert_true(strtod(b + strlen("\"energy_final\": "), NULL) == -4.9406564584124654e-324);
    free(json);
}

/* The bytes of a file (NULL: none), in *len. */
static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char *buf = NULL;
    size_t cap = 0;
    *len = 0;
    for (;;) {
        if (*len == cap) {
            cap = cap ? 2 * cap : 65536;
            unsigned char *b = realloc(buf, cap);
            assert_non_null(b);
            buf = b;
        }
        size_t got = fread(buf + *len, 1, cap - *len, f);
        *len += got;
        if (got == 0)
            break;
    }
    fclose(f);
    return buf;
}

/* A resume is checked before anything is written: a run refused after the file was opened
 * for it (nbep_output_open_resume, then no nbep_output_resume_begin) leaves the file and its
 * sidecar byte for byte as they were; begun, the file is changed (its root `steps`). */
static void test_a_resume_closed_before_it_begins_leaves_the_file_as_it_was(void **state)
{
    fixture *fx = *state;
    const char *path = "build/tests/tmp/output_resume_refused.h5";
    const char *xmf = "build/tests/tmp/output_resume_refused.xmf";
    const nbep_summary summary = known_summary();
    write_run(fx, path, &summary);
    size_t len0, xlen0, len1, xlen1;
    unsigned char *before = slurp(path, &len0), *xbefore = slurp(xmf, &xlen0);
    assert_non_null(before);
    assert_non_null(xbefore);
    fx->sc.steps = 2 * N_STATS; /* past the last frame (step 20): something to resume */
    nbep_output *o = NULL;
    nbep_resume r;
    assert_ok(nbep_output_open_resume(path, &fx->sc, &o, &r, &fx->d), &fx->d);
    assert_int_equal(r.step, (N_FRAMES - 1) * FRAME_EVERY);
    nbep_resume_fini(&r);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    unsigned char *after = slurp(path, &len1), *xafter = slurp(xmf, &xlen1);
    assert_non_null(after);
    assert_non_null(xafter);
    assert_true(len1 == len0 && memcmp(after, before, len0) == 0);
    assert_true(xlen1 == xlen0 && memcmp(xafter, xbefore, xlen0) == 0);
    free(after);
    free(xafter);
    /* begun: the file is the resumed run's (steps = 40, no summary until its close) */
    assert_ok(nbep_output_open_resume(path, &fx->sc, &o, &r, &fx->d), &fx->d);
    nbep_resume_fini(&r);
    assert_ok(nbep_output_resume_begin(o, &fx->sc, 1, &fx->d), &fx->d);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    uint64_t steps = 0;
    hid_t f = open_ro(path);
    read_root_attr(f, "steps", H5T_STD_U64LE, 1, H5T_NATIVE_UINT64, &steps);
    H5Fclose(f);
    assert_int_equal(steps, 2 * N_STATS);
    free(before);
    free(xbefore);
}

/* Sphere i's lasting state at frame k, every field a value of its own (the records compared
 * bit for bit, padding included: zeroed first), and every index one a run of n spheres and
 * N_PLANES planes writes (a resume refuses others): faces met and contacts are planes or
 * other spheres. */
static void contact_value(int k, size_t i, size_t n, nbep_contact_rec *x)
{
    memset(x, 0, sizeof *x);
    const double u = (double)k + 1e-4 * (double)i;
    x->t_last = 0.5 + u;
    for (int c = 0; c < 3; c++)
        x->aeff[c] = -9.81 * (c + 1) + u;
    x->peak2 = 2.0 * u + 0.125;
    for (int f = 0; f < NBEP_CONTACT_FACES; f++) {
        x->face_t[f] = u - 0.01 * f;
        for (int c = 0; c < 3; c++) {
            x->face_n[f][c] = 0.1 * (f + 1) - 0.03 * c + 1e-7 * u;
            x->face_p[f][c] = u * (c + 1) - f;
        }
        /* a plane, another sphere, or none */
        x->face_who[f] = f == 0 ? (int32_t)((i + (size_t)k) % N_PLANES)
                         : f == 1 ? (int32_t)(-1 - (int64_t)((i + 1 + (size_t)k) % n))
                                  : INT32_MIN;
    }
    x->rest_n = (uint8_t)((i + (size_t)k) % (NBEP_CONTACT_MAX + 1));
    for (int c = 0; c < x->rest_n; c++)
        x->rest_who[c] = c % 2 ? (int32_t)(c % N_PLANES)
                               : (int32_t)(-1 - (int64_t)((i + 2 + (size_t)c) % n));
    x->slow = (uint32_t)(i * 3 + (size_t)k);
    x->has_last = (uint8_t)((i + (size_t)k) & 1);
    x->rest_still = (uint8_t)(i % 3 == 0);
    for (int c = 0; c < NBEP_CONTACT_MAX; c++)
        x->rest_current[c] = (uint8_t)((i >> c) & 1);
}

/* The events view's contacts: frame *ctx's records of spheres [lo, hi). */
typedef struct contacts_of {
    int frame;
    size_t n;
} contacts_of;

static void contacts_at(const void *ctx, size_t lo, size_t hi, nbep_contact_rec *out)
{
    const contacts_of *c = ctx;
    for (size_t i = lo; i < hi; i++)
        contact_value(c->frame, i, c->n, &out[i - lo]);
}

/* Each frame's lasting state (/checkpoint/contacts, beyond SPEC) lands in the row of its
 * frame's parity, whole, for more spheres than the writer takes a batch at a time (1024):
 * after frames 0, 1 and 2 the rows hold frames 2 and 1 bit for bit and the tags name them;
 * a frame written without the state (frame 3) leaves its row named by none, and a resume from
 * frame 2 gets frame 2's records. */
static void test_contact_rows_hold_the_last_two_frames_whole(void **state)
{
    fixture *fx = *state;
    nbep_diag d;
    nbep_diag_init(&d);
    const size_t n = 2 * 1024 + 37;
    nbep_scene sc = fx->sc;
    assert_int_equal(nbep_state_init(&sc.state, n, N_PLANES, &d), NBEP_OK);
    nbep_state *s = &sc.state;
    for (size_t i = 0; i < n; i++) {
        s->acc[i] = sc.gravity;
        s->radius[i] = 0.01;
        s->mass[i] = 1.0;
        s->pos[i] = nbep_vec3_make(0.1 + 1e-3 * (double)i, 0.2, 0.3);
        s->vel[i] = nbep_vec3_make(0.0, 0.0, -1.0 + 1e-4 * (double)i);
    }
    for (size_t p = 0; p < N_PLANES; p++) {
        s->plane_normal[p] = fx->sc.state.plane_normal[p];
        s->plane_offset[p] = fx->sc.state.plane_offset[p];
    }
    sc.out_stats = false;
    double *ev_time = calloc(n, sizeof *ev_time);
    uint32_t *partner = calloc(n, sizeof *partner);
    uint8_t *kind = calloc(n, sizeof *kind); /* NBEP_EVENT_NONE: a stale slot */
    int32_t *rest = malloc(n * sizeof *rest);
    assert_true(ev_time && partner && kind && rest);
    for (size_t i = 0; i < n; i++)
        rest[i] = -1;
    char path[256];
    nbep_test_tmp("output_contacts.h5", path, sizeof path);
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(path, &sc, 1, &o, &d), &d);
    contacts_of ctx = {0, n};
    nbep_events_view ev = {ev_time, partner, kind, rest, contacts_at, &ctx};
    for (int k = 0; k < 3; k++) {
        ctx.frame = k;
        assert_ok(nbep_output_frame_events(o, (int64_t)k * FRAME_EVERY, DT, s, &ev, &d), &d);
    }
    assert_ok(nbep_output_close(&o, NULL, &d), &d);
    nbep_contact_rec *want = malloc(n * sizeof *want), *got = malloc(2 * n * sizeof *got);
    assert_true(want && got);
    hid_t f = open_ro(path);
    int64_t tags[2] = {0, 0};
    read_dataset(f, "/checkpoint/contacts_frame", H5T_NATIVE_INT64, tags);
    assert_int_equal(tags[0], 2);
    assert_int_equal(tags[1], 1);
    /* the file's record type, as this machine lays it out: nbep_contact_rec's fields */
    hid_t ds = H5Dopen2(f, "/checkpoint/contacts", H5P_DEFAULT);
    hid_t ft = H5Dget_type(ds), mt = H5Tget_native_type(ft, H5T_DIR_ASCEND);
    assert_true(ds >= 0 && ft >= 0 && mt >= 0);
    assert_int_equal(H5Tget_size(mt), sizeof(nbep_contact_rec));
    memset(got, 0, 2 * n * sizeof *got);
    assert_true(H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, got) >= 0);
    H5Tclose(mt);
    H5Tclose(ft);
    H5Dclose(ds);
    H5Fclose(f);
    for (int row = 0; row < 2; row++) {
        ctx.frame = 2 - row; /* row 0 frame 2, row 1 frame 1 */
        contacts_at(&ctx, 0, n, want);
        for (size_t i = 0; i < n; i++)
            if (memcmp(&got[(size_t)row * n + i], &want[i], sizeof *want) != 0)
                fail_msg("contacts row %d (frame %d): sphere %zu differs", row, 2 - row, i);
    }
    /* resumed from its last frame (2): that frame's records */
    sc.steps = 4 * FRAME_EVERY;
    nbep_resume r;
    assert_ok(nbep_output_open_resume(path, &sc, &o, &r, &d), &d);
    assert_int_equal(r.step, 2 * FRAME_EVERY);
    assert_non_null(r.contacts);
    ctx.frame = 2;
    contacts_at(&ctx, 0, n, want);
    for (size_t i = 0; i < n; i++)
        if (memcmp(&r.contacts[i], &want[i], sizeof *want) != 0)
            fail_msg("resumed contacts: sphere %zu differs", i);
    nbep_resume_fini(&r);
    /* frame 3 without the state: its row (1) is no frame's, frame 2's stays */
    assert_ok(nbep_output_resume_begin(o, &sc, 1, &d), &d);
    ev.contacts = NULL;
    assert_ok(nbep_output_frame_events(o, 3 * FRAME_EVERY, DT, s, &ev, &d), &d);
    assert_ok(nbep_output_close(&o, NULL, &d), &d);
    f = open_ro(path);
    read_dataset(f, "/checkpoint/contacts_frame", H5T_NATIVE_INT64, tags);
    H5Fclose(f);
    assert_int_equal(tags[0], 2);
    assert_int_equal(tags[1], -1);
    free(want);
    free(got);
    free(ev_time);
    free(partner);
    free(kind);
    free(rest);
    nbep_state_fini(&sc.state);
    nbep_diag_fini(&d);
}

/* A resume of path refused with status want and one line holding says, the file left byte for
 * byte as it was (the resume checks everything before it writes). */
static void assert_resume_refused(fixture *fx, const char *path, nbep_status want,
                                  const char *says)
{
    size_t len0, len1;
    unsigned char *before = slurp(path, &len0);
    assert_non_null(before);
    fx->sc.steps = 2 * N_STATS; /* past the last frame: something to resume, were it a run's */
    nbep_output *o = NULL;
    nbep_resume r;
    assert_int_equal(nbep_output_open_resume(path, &fx->sc, &o, &r, &fx->d), want);
    assert_null(o);
    assert_int_equal(fx->d.n_errors, 1);
    assert_non_null(strstr(fx->d.msg[0], says));
    assert_non_null(strstr(fx->d.msg[0], path));
    unsigned char *after = slurp(path, &len1);
    assert_non_null(after);
    assert_true(len1 == len0 && memcmp(after, before, len0) == 0);
    free(before);
    free(after);
}

/* One writer of a file at a time (a job resubmitted while the first still runs, an array job
 * whose tasks all name one file): while another holds PATH.lock, a new file there and a resume
 * of it are refused as bad usage (exit 2) with one line naming both, and nothing is made or
 * changed: an older file stays byte for byte, no PATH.partial. Until 2026-12-01 the second run
 * renamed its file over the first's, both ending with exit 0. */
static void test_a_file_another_writer_holds_is_neither_made_nor_resumed(void **state)
{
    fixture *fx = *state;
    char path[256], lock[300], partial[300];
    nbep_test_tmp("output_held.h5", path, sizeof path);
    snprintf(lock, sizeof lock, "%s.lock", path);
    snprintf(partial, sizeof partial, "%s.partial", path);
    const nbep_summary summary = known_summary();
    write_run(fx, path, &summary);
    assert_no_file(lock); /* the writer's lock went with it */
    size_t len0, len1;
    unsigned char *before = slurp(path, &len0);
    assert_non_null(before);

    bool busy = true;
    const int held = nbep_lock_take(lock, &busy); /* "another run" */
    assert_true(held >= 0);
    assert_false(busy);
    nbep_output *o = NULL;
    /* NBEP_EBUSY (exit 2): the sweep tells it apart from a file it cannot use (sweep.c) */
    assert_int_equal(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), NBEP_EBUSY);
    assert_null(o);
    assert_one_line_naming(&fx->d, path);
    char says[700];
    snprintf(says, sizeof says,
             "nbep: %s: another nbep run is writing this file (it holds %s); wait for it to "
             "end, or give this run another output",
             path, lock);
    assert_string_equal(fx->d.msg[0], says);
    assert_no_file(partial);
    nbep_diag_clear(&fx->d);
    assert_resume_refused(fx, path, NBEP_EBUSY, "another nbep run is writing this file");
    unsigned char *after = slurp(path, &len1);
    assert_true(len1 == len0 && memcmp(after, before, len0) == 0);
    free(after);
    struct stat st;
    assert_int_equal(stat(lock, &st), 0); /* the holder's, not removed by those refused */
    nbep_lock_drop(held, lock);

    /* free again: a writer holds the lock for the handle's life and removes it at the end */
    assert_ok(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), &fx->d);
    busy = false;
    assert_int_equal(nbep_lock_take(lock, &busy), -1);
    assert_true(busy);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    assert_no_file(lock);
    free(before);
}

/* A lock file a killed run left (SIGKILL, the OOM killer: no one removed it) holds nothing:
 * the next run takes it. */
static void test_a_lock_file_left_by_a_killed_run_does_not_hold_the_file(void **state)
{
    fixture *fx = *state;
    char path[256], lock[300];
    nbep_test_tmp("output_stale_lock.h5", path, sizeof path);
    snprintf(lock, sizeof lock, "%s.lock", path);
    FILE *f = fopen(lock, "w");
    assert_non_null(f);
    fclose(f);
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(path, &fx->sc, 1, &o, &fx->d), &fx->d);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    assert_no_file(lock);
}

/* A file closed (or killed) before its first frame was complete (its /frames count 0) has
 * nothing to resume from: refused as bad usage (exit 2, as a file cut short before HDF5 could
 * open it), with a line that says so and how to go on, and the file left as it was. */
static void test_a_file_without_a_complete_frame_is_refused_as_bad_usage(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_resume_no_frame.h5", path, sizeof path);
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(path, &fx->sc, 3, &o, &fx->d), &fx->d);
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    hid_t f = open_ro(path);
    assert_int_equal(read_count(f, "/frames"), 0);
    H5Fclose(f);
    assert_resume_refused(fx, path, NBEP_EUSAGE, "has no complete frame to resume from (run "
                                                 "without --resume to start it afresh)");
}

/* A file whose frames lack velocities (output.fields = ["position"]) cannot be resumed: a deck
 * error that says why (the frames a resume starts from need both), the file left as it was (a
 * coverage run showed no test took this path). */
static void test_a_file_without_velocities_is_refused_as_a_deck_error(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_resume_no_velocity.h5", path, sizeof path);
    fx->sc.out_velocity = false;
    const nbep_summary summary = known_summary();
    write_run(fx, path, &summary);
    fx->sc.out_velocity = true; /* the deck resumed with asks for them, as a resume must */
    assert_resume_refused(fx, path, NBEP_EDECK,
                          "cannot be resumed: its frames lack positions or velocities "
                          "(output.fields)");
}

/* /frames/totals with every field of a run's, one of another type (energy_initial an integer,
 * of the same size and place): HDF5 would convert it and read 0 without a word, and the
 * resumed run's summary would say energy_initial 0 (as with a field missing, test_resume.sh);
 * refused as a deck error naming the field, the file left as it was. */
static void test_totals_with_a_field_of_another_type_are_refused_naming_it(void **state)
{
    fixture *fx = *state;
    char path[256];
    nbep_test_tmp("output_resume_totals_type.h5", path, sizeof path);
    const nbep_summary summary = known_summary();
    write_run(fx, path, &summary);
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t ds = H5Dopen2(f, "/frames/totals", H5P_DEFAULT), run_type = H5Dget_type(ds);
    assert_true(ds >= 0 && run_type >= 0);
    const size_t size = H5Tget_size(run_type);
    const int n_fields = H5Tget_nmembers(run_type);
    hid_t other = H5Tcreate(H5T_COMPOUND, size);
    bool changed = false;
    for (int k = 0; k < n_fields; k++) {
        char *name = H5Tget_member_name(run_type, (unsigned)k);
        hid_t ft = H5Tget_member_type(run_type, (unsigned)k);
        const bool it = strcmp(name, "energy_initial") == 0;
        changed |= it;
        assert_true(H5Tinsert(other, name, H5Tget_member_offset(run_type, (unsigned)k),
                              it ? H5T_STD_U64LE : ft) >= 0);
        H5Tclose(ft);
        H5free_memory(name);
    }
    assert_true(changed);
    unsigned char *rows = calloc(N_FRAMES, size);
    assert_non_null(rows);
    assert_true(H5Dread(ds, run_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) >= 0);
    H5Dclose(ds);
    assert_true(H5Ldelete(f, "/frames/totals", H5P_DEFAULT) >= 0);
    hsize_t dims[1] = {N_FRAMES}, max[1] = {H5S_UNLIMITED}, chunk[1] = {16};
    hid_t space = H5Screate_simple(1, dims, max), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    assert_true(H5Pset_chunk(dcpl, 1, chunk) >= 0);
    ds = H5Dcreate2(f, "/frames/totals", other, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    assert_true(ds >= 0 && H5Dwrite(ds, other, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) >= 0);
    H5Dclose(ds);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Tclose(other);
    H5Tclose(run_type);
    H5Fclose(f);
    free(rows);
    assert_resume_refused(fx, path, NBEP_EDECK, "/frames/totals has no field energy_initial");
}

/* The sidecar, rewritten while the run goes at its first 8 frames, its doublings and every
 * 30 s, lists every frame once the file is closed: 9 frames written at once (the ninth not
 * due) are 9 grids, the last step 80's. */
static void test_the_closed_runs_sidecar_lists_every_frame(void **state)
{
    fixture *fx = *state;
    char path[256];
    enum { FRAMES = 9 };
    fx->sc.steps = (FRAMES - 1) * FRAME_EVERY;
    fx->sc.out_stats = false;
    nbep_output *o = NULL;
    assert_ok(nbep_output_create(nbep_test_tmp("output_sidecar_all.h5", path, sizeof path),
                                 &fx->sc, 1, &o, &fx->d),
              &fx->d);
    for (int k = 0; k < FRAMES; k++) {
        fill_frame(&fx->sc.state, k);
        assert_ok(nbep_output_frame(o, (int64_t)k * FRAME_EVERY, DT, &fx->sc.state, &fx->d),
                  &fx->d);
    }
    assert_ok(nbep_output_close(&o, NULL, &fx->d), &fx->d);
    size_t len;
    unsigned char *bytes = slurp(nbep_test_tmp("output_sidecar_all.xmf", path, sizeof path), &len);
    assert_non_null(bytes);
    char *x = calloc(len + 1, 1); /* the text, terminated */
    assert_non_null(x);
    memcpy(x, bytes, len);
    free(bytes);
    size_t grids = 0;
    for (const char *p = x; (p = strstr(p, "<Grid Name=\"step ")) != NULL; p++)
        grids++;
    assert_int_equal(grids, FRAMES);
    assert_non_null(strstr(x, "<Grid Name=\"step 80\""));
    free(x);
}

static int make_dirs(void)
{
    const char *dirs[] = {"build", "build/tests", "build/tests/tmp"};
    for (size_t k = 0; k < sizeof dirs / sizeof *dirs; k++)
        if (mkdir(dirs[k], 0777) != 0 && errno != EEXIST)
            return -1;
    return 0;
}

int main(void)
{
    if (make_dirs() != 0) {
        perror("test_output: cannot create build/tests/tmp");
        return 1;
    }
    nbep_output_library_init();
#define T(name) cmocka_unit_test_setup_teardown(name, setup, teardown)
    const struct CMUnitTest tests[] = {
        T(test_every_spec_path_exists_with_its_type_and_shape),
        T(test_sphere_and_plane_arrays_read_back_bit_for_bit),
        T(test_frames_read_back_bit_for_bit_with_their_steps_and_times),
        T(test_frame_and_stats_datasets_are_chunked_and_extendable),
        T(test_a_huge_frame_is_split_into_equal_chunks_of_at_most_4_mib),
        T(test_stats_rows_read_back_in_order_across_batches),
        T(test_root_attributes_hold_the_settings_the_deck_and_the_build),
        T(test_a_deck_larger_than_an_object_header_is_stored_whole),
        T(test_summary_attribute_is_the_json_text),
        T(test_closing_without_a_summary_leaves_no_summary_group),
        T(test_velocity_not_asked_for_is_not_created),
        T(test_position_not_asked_for_is_not_created),
        T(test_stats_not_asked_for_leave_no_stats_group),
        T(test_a_scene_without_spheres_or_planes_still_records_frames),
        T(test_closing_releases_every_hdf5_id),
        T(test_closing_a_null_handle_does_nothing),
        T(test_a_path_in_a_missing_directory_fails_as_usage_naming_the_path),
        T(test_a_path_naming_a_directory_fails_and_leaves_the_directory),
        T(test_a_failure_after_the_file_was_created_leaves_no_file),
        T(test_a_failed_create_keeps_an_older_file_at_the_path),
        T(test_a_file_another_writer_holds_is_neither_made_nor_resumed),
        T(test_a_lock_file_left_by_a_killed_run_does_not_hold_the_file),
        T(test_a_frame_with_a_non_finite_position_is_refused),
        T(test_a_frame_beyond_the_image_count_is_refused),
        T(test_a_run_killed_between_frames_leaves_every_frame_written),
        T(test_a_process_exiting_without_closing_leaves_three_frames),
        T(test_the_chunk_index_holds_every_planned_frame_without_splitting),
        T(test_h5dump_reads_the_file_of_a_killed_run),
        T(test_info_reports_the_settings_frames_stats_and_summary),
        T(test_periodic_axes_are_the_attribute_and_info_names_them),
        T(test_periodic_frames_hold_wrapped_positions_and_the_images_added),
        T(test_the_closed_runs_sidecar_lists_every_frame),
        T(test_a_resume_closed_before_it_begins_leaves_the_file_as_it_was),
        T(test_contact_rows_hold_the_last_two_frames_whole),
        T(test_a_file_without_a_complete_frame_is_refused_as_bad_usage),
        T(test_a_file_without_velocities_is_refused_as_a_deck_error),
        T(test_totals_with_a_field_of_another_type_are_refused_naming_it),
        T(test_info_on_a_killed_run_says_it_has_no_summary),
        T(test_info_reads_a_run_while_it_is_being_written),
        T(test_info_counts_only_the_complete_frames_of_a_run_killed_mid_frame),
        T(test_info_refuses_a_count_past_the_rows_naming_both),
        T(test_info_reads_a_fixed_length_format_whole),
        T(test_info_rejects_a_file_that_is_not_hdf5),
        T(test_info_rejects_an_hdf5_file_without_the_nbep_1_format),
        T(test_info_on_a_missing_file_fails_naming_it),
        T(test_info_rejects_an_nbep_1_file_missing_a_part),
        T(test_json_of_a_known_summary_is_the_expected_text),
        T(test_json_written_to_a_stream_is_one_line_and_counts_its_bytes),
        T(test_json_parses_with_spec_keys_in_spec_order),
        T(test_json_escapes_quotes_backslashes_and_control_characters),
        T(test_json_writes_reals_in_their_shortest_exact_form),
        T(test_json_keeps_every_digit_of_a_double),
    };
#undef T
    return cmocka_run_group_tests_name("output", tests, NULL, NULL);
}
