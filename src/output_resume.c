/* `nbep run DECK --resume RUN.h5` (output.h): reopens a run for appending after its last
 * complete frame, checking that deck and file agree, and reads that frame (and its event
 * slots) back; the writer (output.c) then goes on as after nbep_output_create. */
#include <assert.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include <hdf5.h>
#include <hdf5_hl.h>

#include "build_info.h"
#include "nbep/feq.h"
#include "output_impl.h"

void nbep_resume_fini(nbep_resume *r)
{
    if (!r)
        return;
    free(r->pos);
    free(r->vel);
    free(r->event_time);
    free(r->event_partner);
    free(r->event_kind);
    free(r->rest);
    free(r->image);
    free(r->contacts);
    memset(r, 0, sizeof *r);
}

/* Whether `who` names a face sphere i can meet in a scene of n spheres and np planes: plane
 * who, or sphere -1 - who, not i itself (none: INT32_MIN, where none_ok). */
static bool face_named(int32_t who, size_t i, size_t n, size_t np, bool none_ok)
{
    if (who == INT32_MIN)
        return none_ok;
    if (who >= 0)
        return (size_t)who < np;
    const size_t j = (size_t)(-1 - (int64_t)who);
    return j < n && j != i;
}

static bool all_finite(const double *v, size_t k)
{
    for (size_t m = 0; m < k; m++)
        if (!isfinite(v[m]))
            return false;
    return true;
}

/* The first sphere whose position or velocity read from a frame is not finite, or n when
 * none. (Not the deck's span: a run's spheres fly past it, in an open scene or along an axis
 * with no walls, and such a file was refused for a day.) */
static size_t resumed_state_fault(const nbep_vec3 *pos, const nbep_vec3 *vel, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!all_finite(&pos[i].x, 3) || !all_finite(&vel[i].x, 3))
            return i;
    return n;
}

/* What in sphere i's event slot and resting plane no run of n spheres and np planes writes
 * (a partner, plane or kind out of range, a time not finite), or NULL. */
static const char *slot_fault(const nbep_resume *r, size_t i, size_t np)
{
    const uint8_t kind = r->event_kind[i];
    const uint32_t partner = r->event_partner[i];
    if (kind > NBEP_EVENT_HORIZON)
        return "an event of no kind there is";
    if ((kind == NBEP_EVENT_SPHERE || kind == NBEP_EVENT_PLANE || kind == NBEP_EVENT_HORIZON) &&
        !isfinite(r->event_time[i]))
        return "an event time that is not finite";
    if (kind == NBEP_EVENT_SPHERE && (partner >= r->n || partner == i))
        return "an event with a sphere that is not there";
    if (kind == NBEP_EVENT_PLANE && partner >= np)
        return "an event with a plane that is not there";
    if (r->rest[i] != -1 && !(r->rest[i] >= 0 && (size_t)r->rest[i] < np))
        return "a resting plane that is not there";
    return NULL;
}

/* The same for sphere i's lasting state x: a contact or a face met out of range, more
 * contacts than a sphere holds, a value not finite. */
static const char *contact_fault(const nbep_contact_rec *x, size_t i, size_t n, size_t np)
{
    if (!all_finite(x->aeff, 3) || !all_finite(x->face_t, NBEP_CONTACT_FACES) ||
        !all_finite(&x->face_n[0][0], 3 * NBEP_CONTACT_FACES) ||
        !all_finite(&x->face_p[0][0], 3 * NBEP_CONTACT_FACES) || !isfinite(x->t_last) ||
        !isfinite(x->peak2))
        return "lasting state that is not finite";
    for (int k = 0; k < NBEP_CONTACT_FACES; k++)
        if (!face_named(x->face_who[k], i, n, np, true))
            return "a face met that is not there";
    if (x->rest_n > NBEP_CONTACT_MAX)
        return "more contacts than a sphere holds";
    for (int k = 0; k < x->rest_n; k++)
        if (!face_named(x->rest_who[k], i, n, np, false))
            return "a contact that is not there";
    return NULL;
}

/* The first thing in r's checkpoint (event slots, lasting state) that no run of its spheres
 * and np planes writes: a file damaged or made by hand, whose indices the run would follow
 * out of its arrays. Its sphere in *at and what in *what; false when all is well. */
static bool checkpoint_fault(const nbep_resume *r, size_t np, size_t *at, const char **what)
{
    for (size_t i = 0; i < r->n; i++) {
        *at = i;
        *what = slot_fault(r, i, np);
        if (!*what && r->contacts)
            *what = contact_fault(&r->contacts[i], i, r->n, np);
        if (*what)
            return true;
    }
    return false;
}

/* NBEP_EDECK, one line naming it, for the first dataset that every run file holds (or holds
 * in a group the file has: /stats, /checkpoint) and this file lacks; NBEP_EIO where the look
 * fails; else NBEP_OK. Such a file is damaged or edited by hand: a resume refuses it at once,
 * exit 2 as the README's exit table has it for a file that is not what it should be (until
 * 2026-12-04 the read that met the gap failed it as an I/O fault, exit 1, a review).
 * H5LTpath_valid checks each group along the path, where H5Lexists fails on a missing one. */
static nbep_status missing_part(hid_t file, const char *path, nbep_diag *d)
{
    static const char *const always[] = {"/spheres/radius", "/planes/offset", "/frames/step",
                                         "/frames/time"};
    const char *names[4 + STATS_N_COLUMNS + N_CK_COLUMNS];
    size_t n = 0;
    for (size_t k = 0; k < sizeof always / sizeof always[0]; k++)
        names[n++] = always[k];
    const htri_t stats = H5Lexists(file, "/stats", H5P_DEFAULT),
                 ck = H5Lexists(file, "/checkpoint", H5P_DEFAULT);
    for (size_t k = 0; stats > 0 && k < STATS_N_COLUMNS; k++)
        names[n++] = nbep__stats_columns[k].name;
    for (size_t k = 0; ck > 0 && k < N_CK_COLUMNS; k++)
        names[n++] = nbep__ck_columns[k].name;
    if (stats < 0 || ck < 0) {
        HDF5_FAIL(d, path, "look for /stats and /checkpoint");
        return NBEP_EIO;
    }
    for (size_t k = 0; k < n; k++) {
        const htri_t has = H5LTpath_valid(file, names[k], 1);
        if (has < 0) {
            HDF5_FAIL(d, path, "look for %s", names[k]);
            return NBEP_EIO;
        }
        if (has == 0)
            NBEP_FAIL(d, NBEP_EDECK,
                      "nbep: %s has no %s, which every run writes there: the file is damaged, "
                      "or no run wrote it (run without --resume to start afresh)",
                      path, names[k]);
    }
    return NBEP_OK;
}

void nbep_resume_apply(nbep_resume *r, nbep_state *s)
{
    assert(r->n == s->n);
    if (r->pos)
        memcpy(s->pos, r->pos, r->n * sizeof *s->pos);
    if (r->vel)
        memcpy(s->vel, r->vel, r->n * sizeof *s->vel);
    if (r->image)
        memcpy(s->image, r->image, 3 * r->n * sizeof *s->image);
    free(r->pos);
    free(r->vel);
    free(r->image);
    r->pos = r->vel = NULL;
    r->image = NULL;
}

/* Opens dataset name and cuts it to `rows` rows. */
static int open_cut(nbep_output *o, const char *name, hsize_t rows, hid_t *out, nbep_diag *d)
{
    hsize_t dims[H5S_MAX_RANK]; /* any rank a file may hold */
    *out = H5Dopen2(o->file, name, H5P_DEFAULT);
    hid_t space = *out < 0 ? H5I_INVALID_HID : H5Dget_space(*out);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_dims(space, dims, NULL);
    nbep__output_close_id(&space);
    if (rank < 1) {
        HDF5_FAIL(d, o->path, "open %s", name);
        return -1;
    }
    dims[0] = rows;
    if (H5Dset_extent(*out, dims) < 0) {
        HDF5_FAIL(d, o->path, "cut %s to %llu rows", name, (unsigned long long)rows);
        return -1;
    }
    return 0;
}

/* Whether the file's /summary says its run completed: 1, also where it says nothing of how the
 * run ended (a summary before 2026-11-30: taken as completed, as a sweep takes it) or cannot
 * be read as a summary; 0 where it has none (killed) or says interrupted, terminated or
 * failed; -1 on a read error. */
static int run_ended(hid_t file, const char *path, nbep_diag *d)
{
    char *json;
    if (nbep__output_summary_json(file, path, &json, d) < 0)
        return -1;
    nbep_summary s;
    const int rc = json && (!nbep_summary_from_json(json, &s) || nbep_summary_ended(&s));
    free(json);
    return rc;
}

/* What in a frame's totals at step `step` no run writes (a sum not finite, an overlap below 0,
 * more quiet steps than steps, a count past 2^62), or NULL. A count past 2^62 no run reaches
 * (centuries of stepping), and the summary's JSON integers (signed 64-bit) could not hold it
 * once added to: until 2026-11-30 a count of 2^63 ran the whole resumed part and then failed
 * at its summary, exit 1. */
static const char *totals_fault(const nbep_run_totals *t, int64_t step)
{
    const double sums[] = {t->energy_initial, t->max_overlap, t->max_overlap_rel, t->virial,
                           t->kinetic_energy};
    const uint64_t counts_max = UINT64_C(1) << 62;
    if (!all_finite(sums, sizeof sums / sizeof *sums))
        return "a sum not finite";
    if (!(t->max_overlap >= 0.0) || !(t->max_overlap_rel >= 0.0))
        return "an overlap below 0";
    if (t->quiet_steps > (uint64_t)step)
        return "more quiet steps than steps";
    if (t->checks > counts_max || t->predictions > counts_max ||
        t->sphere_collisions > counts_max || t->plane_collisions > counts_max)
        return "a count past 2^62";
    return NULL;
}

/* The run's totals at frame row `last` (/frames/totals) into r (has_totals), where the file has
 * them, and whether the run appends to them (o->resume.totals: a row for each of the `frames`
 * kept). NBEP_EDECK (one line) for totals no run wrote: a field missing, or totals_fault. */
static nbep_status read_totals(nbep_output *o, const char *path, hsize_t frames, hsize_t last,
                               nbep_resume *r, nbep_diag *d)
{
    const htri_t has = H5Lexists(o->file, "/frames/totals", H5P_DEFAULT);
    hsize_t rows = 0;
    if (has < 0)
        HDF5_FAIL(d, path, "look for /frames/totals");
    if (has < 0 ||
        (has && nbep__output_dataset_rows(o->file, path, "/frames/totals", &rows, d) < 0))
        return NBEP_EIO;
    o->resume.totals = has && rows >= frames; /* a row for each frame kept: the run appends */
    r->has_totals = has && last < rows;
    if (!r->has_totals)
        return NBEP_OK;
    hid_t type = nbep__output_totals_type();
    char missing[NBEP_FIELD_NAME_MAX] = "";
    int rc = type < 0 ? -1 : nbep__output_fields_missing(o->file, path, "/frames/totals", type,
                                                         missing, d);
    if (type < 0)
        HDF5_FAIL(d, path, "make the type of /frames/totals");
    if (rc == 0)
        rc = nbep__output_read_row(o->file, path, "/frames/totals", last, 1, type, &r->totals, d);
    nbep__output_close_id(&type);
    if (rc < 0)
        return NBEP_EIO;
    const char *fault = missing[0] ? NULL : totals_fault(&r->totals, r->step);
    if (missing[0])
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: its /frames/totals has no field %s of a run's (a field "
                      "missing or of another type): the file is damaged, or no run of this "
                      "deck wrote it (run without --resume to start afresh)",
                      path, missing);
    else if (fault)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: its totals at step %lld are not a run's (%s): the file is "
                      "damaged, or no run of this deck wrote it (run without --resume to start "
                      "afresh)",
                      path, (long long)r->step, fault);
    return missing[0] || fault ? NBEP_EDECK : NBEP_OK;
}

/* Opens the `count` attribute of group into *out (kept open for the writer). */
static int open_count(nbep_output *o, const char *group, hid_t *out, nbep_diag *d)
{
    hid_t g = H5Gopen2(o->file, group, H5P_DEFAULT);
    *out = g < 0 ? H5I_INVALID_HID : H5Aopen(g, "count", H5P_DEFAULT);
    nbep__output_close_id(&g);
    if (*out < 0) {
        HDF5_FAIL(d, o->path, "open the count attribute of %s", group);
        return -1;
    }
    return 0;
}

/* The same run? What the file's frames and event slots were made under must be what the deck
 * makes, bit for bit: the sphere and plane counts, each sphere's radius, mass and acceleration
 * and each plane (the slots are predictions from them: a slot predicted under another gravity
 * or wall is a contact that does not happen), and dt (a step's time is the step times dt, and
 * the slots' times are absolute: resumed with another dt, the run began its clock at another
 * time than its spheres' and its predictions came out in its past, spheres passing through each
 * other). Restitution and the other response settings may change: they act only when an event
 * comes. -2 when they do not match (the reason added to d), -1 when the file cannot be read. */
static int same_run(hid_t file, const char *path, const nbep_scene *sc, nbep_diag *d)
{
    const nbep_state *s = &sc->state;
    hsize_t n = 0, np = 0;
    double dt;
    if (nbep__output_dataset_rows(file, path, "/spheres/radius", &n, d) < 0 ||
        nbep__output_dataset_rows(file, path, "/planes/offset", &np, d) < 0 ||
        nbep__output_read_attr(file, path, "dt", H5T_NATIVE_DOUBLE, &dt, d) < 0)
        return -1;
    int32_t per[3] = {0, 0, 0};
    const htri_t has_per = H5Aexists(file, "periodic");
    if (n == s->n && has_per > 0 &&
        nbep__output_read_attr(file, path, "periodic", H5T_NATIVE_INT32, per, d) == 0 &&
        ((per[0] != 0) != sc->periodic[0] || (per[1] != 0) != sc->periodic[1] ||
         (per[2] != 0) != sc->periodic[2])) {
        /* the walls differ because the periodic axes do: said so, not as planes the user never
         * wrote, nor as other normals where as many walls stand on other axes (until
         * 2026-12-01, a new user's find and a review) */
        static const char *const tf[2] = {"false", "true"};
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s was run with box.periodic = [%s, %s, %s] but %s makes [%s, %s, "
                      "%s]; resume with the deck (and --set options) that made it",
                      path, tf[per[0] != 0], tf[per[1] != 0], tf[per[2] != 0], sc->deck_path,
                      tf[sc->periodic[0]], tf[sc->periodic[1]], tf[sc->periodic[2]]);
        return -2;
    }
    if (n != s->n || np != s->n_planes) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s holds %llu spheres and %llu planes but %s makes %zu and %zu; "
                      "resume with the deck (and --set options) that made it",
                      path, (unsigned long long)n, (unsigned long long)np, sc->deck_path, s->n,
                      s->n_planes);
        return -2;
    }
    if (memcmp(&dt, &sc->dt, sizeof dt) != 0) {
        char was[NBEP_REAL_TEXT_MAX], now[NBEP_REAL_TEXT_MAX];
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s was run with run.dt = %s but %s makes %s; a resumed run keeps "
                      "the dt of the run it continues (a frame's time is its step times dt)",
                      path, nbep_format_real(dt, false, was), sc->deck_path,
                      nbep_format_real(sc->dt, false, now));
        return -2;
    }
    /* cells mode: output.every, whose multiples are the steps at which it rebuilds its lists
     * and from which alone it continues bit for bit (files made before 2026-11-30 lack it and
     * are not checked: a changed output.every then resumed from a frame that was no rebuild
     * point of the run that wrote it, and matched neither deck's uninterrupted run) */
    const htri_t has_every = H5Aexists(file, "output_every");
    uint64_t every = 0;
    if (has_every < 0 ||
        (has_every &&
         nbep__output_read_attr(file, path, "output_every", H5T_NATIVE_UINT64, &every, d) < 0)) {
        if (has_every < 0)
            HDF5_FAIL(d, path, "read its attributes");
        return -1;
    }
    if (has_every && every != sc->output_every && nbep_scene_cells_engine(sc)) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s was written with output.every = %llu but %s makes %llu; "
                      "run.neighbors = \"cells\" rebuilds its lists at the multiples of "
                      "output.every and resumes bit for bit only with the same",
                      path, (unsigned long long)every, sc->deck_path,
                      (unsigned long long)sc->output_every);
        return -2;
    }
    /* the box, which on a periodic axis no wall records (files made before 2026-11-27 lack
     * it, and are not checked for it) */
    const htri_t has_box = H5Aexists(file, "box_min");
    nbep_vec3 lo, hi;
    if (has_box < 0 ||
        (has_box &&
         (nbep__output_read_attr(file, path, "box_min", H5T_NATIVE_DOUBLE, &lo, d) < 0 ||
          nbep__output_read_attr(file, path, "box_max", H5T_NATIVE_DOUBLE, &hi, d) < 0))) {
        if (has_box < 0)
            HDF5_FAIL(d, path, "read its attributes");
        return -1;
    }
    if (has_box && !(sc->has_box && memcmp(&lo, &sc->box_min, sizeof lo) == 0 &&
                     memcmp(&hi, &sc->box_max, sizeof hi) == 0)) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s was run in another box than %s makes (box.min, box.max); "
                      "resume with the deck (and --set options) that made it",
                      path, sc->deck_path);
        return -2;
    }
    const struct {
        const char *name, *what;
        const void *want;
        size_t count; /* doubles */
    } sets[] = {
        {"/spheres/radius", "radii", s->radius, s->n},
        {"/spheres/mass", "masses", s->mass, s->n},
        {"/spheres/acceleration", "accelerations (physics.gravity)", s->acc, 3 * s->n},
        {"/planes/normal", "normals", s->plane_normal, 3 * s->n_planes},
        {"/planes/offset", "offsets", s->plane_offset, s->n_planes},
    };
    const size_t room = 3 * (s->n > s->n_planes ? s->n : s->n_planes);
    double *buf = malloc((room ? room : 1) * sizeof *buf);
    if (!buf) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to read %s", path);
        return -1;
    }
    int rc = 0;
    for (size_t k = 0; k < sizeof sets / sizeof *sets && rc == 0; k++) {
        /* its size first: a damaged file's longer dataset must not be read into buf */
        hid_t ds = H5Dopen2(file, sets[k].name, H5P_DEFAULT);
        hid_t space = ds < 0 ? H5I_INVALID_HID : H5Dget_space(ds);
        const hssize_t got = space < 0 ? -1 : H5Sget_simple_extent_npoints(space);
        nbep__output_close_id(&space);
        if (got < 0) {
            HDF5_FAIL(d, path, "read %s", sets[k].name);
            rc = -1;
        } else if ((size_t)got != sets[k].count) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: %s holds %lld values where %s makes %zu; resume with the "
                          "deck (and --set options) that made it",
                          path, sets[k].name, (long long)got, sc->deck_path, sets[k].count);
            rc = -2;
        } else if (got > 0 &&
                   H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
            HDF5_FAIL(d, path, "read %s", sets[k].name);
            rc = -1;
        } else if (got > 0 && memcmp(buf, sets[k].want, sets[k].count * sizeof *buf) != 0) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: the %s of %s differ from what %s makes; resume with the "
                          "deck (and --set options) that made it",
                          path, sets[k].what, sets[k].name, sc->deck_path);
            rc = -2;
        }
        nbep__output_close_id(&ds);
    }
    free(buf);
    return rc;
}

/* The words note_resume puts after a line's build for what a part changed: ", KEY VALUE" (the
 * overrides that may follow are ", a=1; b=2", with an '=' in their first word). */
static const char *const changed_keys[] = {"algorithm", "restitution", "neighbors", "order"};

const char *nbep_output_resume_changes(const nbep_output *o)
{
    return o->resume.changed[0] ? o->resume.changed + 2 : NULL; /* past its ", " */
}

bool nbep_output_resume_other_algorithm(const nbep_output *o)
{
    return o->resume.other_algorithm;
}

/* Whether a line of `resumed` (the resumes' lines) notes a change among changed_keys[first]
 * to changed_keys[last - 1]: its first change, past its build's ") , ", is one of them (a line
 * names its changes in the order of changed_keys). */
static bool resumed_notes(const char *resumed, size_t first, size_t last)
{
    for (const char *line = resumed; line && *line;) {
        const size_t len = strcspn(line, "\n");
        const char *build = strstr(line, " (commit ");
        const char *end =
            build && build < line + len ? memchr(build, ')', (size_t)(line + len - build)) : NULL;
        if (end && strncmp(end + 1, ", ", 2) == 0)
            for (size_t k = first; k < last; k++) {
                const size_t kl = strlen(changed_keys[k]);
                if (strncmp(end + 3, changed_keys[k], kl) == 0 && end[3 + kl] == ' ')
                    return true;
            }
        line += len + (line[len] != '\0');
    }
    return false;
}

bool nbep_output_resumed_changed(const char *resumed)
{
    return resumed_notes(resumed, 0, sizeof changed_keys / sizeof *changed_keys);
}

/* Adds this resume's line to the root attribute `resumed` (made with the first): the step it
 * continues from, the threads, this build, the algorithm, restitution, neighbors and order
 * where they are not the root's (a deck edited in place may change them: the root says how
 * the first part was made) and the overrides, so that `nbep info` tells the parts of a run apart (the root's
 * `threads` and `overrides` stay the first part's: a sweep knows its runs by those
 * overrides). */
static int note_resume(hid_t file, const char *path, const nbep_scene *sc, int threads,
                       int64_t step, char changed[static RESUME_CHANGED_MAX],
                       bool *other_algorithm, nbep_diag *d)
{
    char *was = NULL;
    const htri_t had = H5Aexists(file, "resumed");
    if (had < 0 || (had && nbep__output_read_string_attr(file, path, "resumed", &was, d) < 0)) {
        if (had < 0)
            HDF5_FAIL(d, path, "read the root attribute resumed");
        return -1;
    }
    /* what the first part ran with, where this part differs */
    char *algo = NULL;
    changed[0] = '\0';
    double e0 = sc->restitution;
    if (nbep__output_read_string_attr(file, path, "algorithm", &algo, d) < 0 ||
        nbep__output_read_attr(file, path, "restitution", H5T_NATIVE_DOUBLE, &e0, d) < 0) {
        free(algo);
        free(was);
        return -1;
    }
    const bool first_other = strcmp(algo, sc->algorithm) != 0;
    /* the first part's, or a resumed one's (a naive part between two predictive ones): a part
     * whose line names its algorithm ran another than the first part, so one of the two is
     * not this part's */
    *other_algorithm = first_other || resumed_notes(was, 0, 1);
    if (first_other)
        snprintf(changed, RESUME_CHANGED_MAX, ", %s %s", changed_keys[0], sc->algorithm);
    if (e0 != sc->restitution) { /* (not memcmp: -0 is 0, the same physics) */
        char e[NBEP_REAL_TEXT_MAX];
        const size_t at = strlen(changed);
        snprintf(changed + at, RESUME_CHANGED_MAX - at, ", %s %s", changed_keys[1],
                 nbep_format_real(sc->restitution, false, e));
    }
    free(algo);
    /* a predictive part's way of finding pairs and reacting (run.neighbors, run.order), where
     * the root (a predictive first part's) says another or none (until 2026-11-30 a part that
     * switched to grid or step order said nothing of it) */
    if (strcmp(sc->algorithm, "predictive") == 0) {
        const char *now[2] = {nbep_scene_neighbors_name(sc), nbep_scene_order_name(sc)};
        const char *const *key = changed_keys + 2; /* neighbors, order */
        for (int k = 0; k < 2; k++) {
            char *root = NULL;
            const htri_t has = H5Aexists(file, key[k]);
            if (has < 0 ||
                (has && nbep__output_read_string_attr(file, path, key[k], &root, d) < 0)) {
                if (has < 0)
                    HDF5_FAIL(d, path, "read the root attribute %s", key[k]);
                free(was);
                return -1;
            }
            if (!root || strcmp(root, now[k]) != 0) {
                const size_t at = strlen(changed);
                snprintf(changed + at, RESUME_CHANGED_MAX - at, ", %s %s", key[k], now[k]);
            }
            free(root);
        }
    }
    const char *ov = sc->overrides ? sc->overrides : "";
    const size_t len = (was ? strlen(was) : 0) + 2 * strlen(ov) + strlen(NBEP_VERSION) +
                       strlen(NBEP_BUILD_COMMIT) + strlen(changed) + 128;
    char *text = malloc(len);
    if (!text) {
        free(was);
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
        return -1;
    }
    snprintf(text, len, "%s%sstep %" PRId64 ": %d thread%s, nbep %s (commit %s)%s%s",
             was ? was : "", was && was[0] ? "\n" : "", step, threads, threads == 1 ? "" : "s",
             NBEP_VERSION, NBEP_BUILD_COMMIT, changed, ov[0] ? ", " : "");
    size_t at = strlen(text);
    for (const char *c = ov; *c; c++) { /* one per line becomes "a=1; b=2" */
        if (*c != '\n') {
            text[at++] = *c;
        } else if (c[1]) {
            text[at++] = ';';
            text[at++] = ' ';
        }
    }
    text[at] = '\0';
    free(was);
    int rc = 0;
    if ((had && H5Adelete(file, "resumed") < 0) ||
        nbep__output_write_string_attr(file, path, "resumed", text, d) < 0) {
        HDF5_FAIL(d, path, "write the root attribute resumed");
        rc = -1;
    }
    free(text);
    return rc;
}

/* The frame a resumed run continues from, among the file's `frames` complete ones (their steps
 * in steps[]): the last, or in cells mode the last at a multiple of output.every, the only
 * frames from which the run continues bit for bit (algo_predictive.c, cells_steps: its
 * rebuilds fall at those steps); the frames after it (a stop's own frame, written off that
 * grid) are dropped, and written again as the run passes their steps. 0 when none. */
static hsize_t resume_frames(const nbep_scene *sc, const int64_t *steps, hsize_t frames)
{
    while (frames > 0 && !nbep_scene_resume_point(sc, steps[frames - 1]))
        frames--;
    return frames;
}

/* A resume writes beside its file as well as in it: the XDMF sidecar (a new one renamed over
 * the old) and the lock, beside the file a link leads to. A folder that takes no new files
 * is refused before the file is touched (exit 2 for EACCES or EROFS, as a new run's folder:
 * until 2026-12-05 the frames were appended and /summary dropped, and the sidecar's failure
 * at the end said exit 1). */
static nbep_status resume_folder_takes_files(const char *path, nbep_diag *d)
{
    char *target = nbep_link_target(path);
    const char *named[2] = {path, target};
    for (int k = 0; k < 2 && named[k]; k++) {
        char *dir = nbep_path_dir(named[k]);
        const int err = dir ? nbep_dir_takes_files(dir) : ENOMEM;
        if (err) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: cannot resume it: its folder %s takes no new files (%s), "
                          "and a resume writes its XDMF sidecar and lock there",
                          path, dir ? dir : "?", strerror(err));
            free(dir);
            free(target);
            return nbep_status_of_open(err);
        }
        free(dir);
    }
    free(target);
    return NBEP_OK;
}

nbep_status nbep_output_open_resume(const char *path, const nbep_scene *sc, nbep_output **out,
                                    nbep_resume *r, nbep_diag *d)
{
    nbep_resume res = {0};
    nbep_status st =
        nbep__output_run_openable(path, R_OK | W_OK, "open the run to resume it", NULL, d);
    if (st != NBEP_OK || (st = resume_folder_takes_files(path, d)) != NBEP_OK)
        return st;
    st = NBEP_EIO;
    const size_t n = sc->state.n;
    nbep_output *o = nbep__output_new(path, n, d);
    if (!o)
        return NBEP_ENOMEM;
    if ((st = nbep__output_lock(o, true, d)) != NBEP_OK)
        goto fail;
    st = NBEP_EIO;

    hid_t fapl = nbep__output_fapl(true);
    o->file = fapl < 0 ? H5I_INVALID_HID : H5Fopen(path, H5F_ACC_RDWR, fapl);
    if (o->file < 0) /* HDF5's reason (a lock another writer holds), before a close clears it */
        HDF5_FAIL(d, path, "open the run to resume it");
    nbep__output_close_id(&fapl);
    if (o->file < 0) { /* cut short, or another run's: bad usage, as a file of another kind */
        st = NBEP_EUSAGE;
        goto fail;
    }
    const nbep_status part = missing_part(o->file, path, d);
    if (part != NBEP_OK) {
        st = part;
        goto fail;
    }
    int same = same_run(o->file, path, sc, d);
    if (same < 0) {
        st = same == -2 ? NBEP_EDECK : NBEP_EIO;
        goto fail;
    }
    uint64_t frames;
    hsize_t more;
    int rows_rc = nbep__output_complete_rows(o->file, path, "/frames", "/frames/step", &frames,
                                             &more, d);
    if (rows_rc < 0) { /* -2: a count past its rows, a damaged file (exit 2, until 2026-12-04 1) */
        st = rows_rc == -2 ? NBEP_EDECK : NBEP_EIO;
        goto fail;
    }
    if (frames == 0) { /* killed before its first frame was complete: nothing to resume from,
                        * which a run without --resume starts afresh (bad usage, as a file cut
                        * short before HDF5 could open it) */
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s has no complete frame to resume from (run without --resume "
                      "to start it afresh)",
                      path);
        st = NBEP_EUSAGE;
        goto fail;
    }
    if (H5Lexists(o->file, "/frames/position", H5P_DEFAULT) <= 0 ||
        H5Lexists(o->file, "/frames/velocity", H5P_DEFAULT) <= 0) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s cannot be resumed: its frames lack positions or velocities "
                      "(output.fields)",
                      path);
        st = NBEP_EDECK;
        goto fail;
    }
    /* the file's frames hold both (above); a deck asking for fewer would have the resumed
     * frames hold what the earlier ones do after all (until 2026-11-30 accepted, named in
     * `resumed`, and ignored) */
    if (!sc->out_position || !sc->out_velocity) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s has positions and velocities in its frames but the deck asks "
                      "for %s (output.fields); resume with the deck (and --set options) that "
                      "made it",
                      path,
                      sc->out_position   ? "positions only"
                      : sc->out_velocity ? "velocities only"
                                         : "neither");
        st = NBEP_EDECK;
        goto fail;
    }
    /* every frame's step and time (the sidecar lists them all), which choose the frame */
    if (!nbep__output_xmf_room(o, (size_t)frames)) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
        st = NBEP_ENOMEM;
        goto fail;
    }
    for (hsize_t k = 0; k < frames; k++)
        if (nbep__output_read_row(o->file, path, "/frames/step", k, 1, H5T_NATIVE_INT64,
                                  &o->xmf_step[k], d) < 0 ||
            nbep__output_read_row(o->file, path, "/frames/time", k, 1, H5T_NATIVE_DOUBLE,
                                  &o->xmf_time[k], d) < 0)
            goto fail;
    /* Each frame's time is its step times dt, bitwise (nbep__output_frame writes it so, and
     * the file's dt is the deck's: same_run), and the steps rise. A frame otherwise (a NaN
     * time, a step edited) no run writes: refused as damaged (until 2026-12-05 resumed, its
     * time kept in the file and the sidecar). */
    for (hsize_t k = 0; k < frames; k++) {
        const int64_t step = o->xmf_step[k];
        const double t = (double)step * sc->dt;
        const bool unordered = step < 0 || (k > 0 && step <= o->xmf_step[k - 1]);
        if (unordered || memcmp(&t, &o->xmf_time[k], sizeof t) != 0) {
            char b0[NBEP_REAL_TEXT_MAX];
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: its frame %llu is at step %lld, time %s, which no run "
                          "writes%s: the file is damaged, or no run wrote it",
                          path, (unsigned long long)k, (long long)step,
                          nbep_format_real(o->xmf_time[k], false, b0),
                          unordered ? " (the steps of its frames rise)"
                                    : " (the time of a frame is its step times run.dt)");
            st = NBEP_EDECK;
            goto fail;
        }
    }
    const uint64_t complete = frames;
    frames = resume_frames(sc, o->xmf_step, frames);
    if (frames == 0) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s has no frame at a multiple of output.every (%llu) to resume "
                      "from in run.neighbors = \"cells\"",
                      path, (unsigned long long)sc->output_every);
        st = NBEP_EDECK;
        goto fail;
    }
    hsize_t last = frames - 1;
    res.step = o->xmf_step[last];
    res.last_step = o->xmf_step[complete - 1];
    /* The frame resumed from stays where the uninterrupted run writes one too: at a multiple
     * of output.every (run.steps lies past it, below). A stop's own frame off that grid
     * (SIGTERM's, or a shorter run's last; one on the grid of the file's own output.every, where
     * the deck changes it, stays) is the run's checkpoint until the resumed run writes
     * its first frame, which takes its row (nbep_output_frame_events: a kill before then
     * finds it in place), so the file ends as the uninterrupted run's (until 2026-11-30 it
     * stayed outside cells mode: one frame more than that run's, and h5diff told them apart).
     * Only the last frame can be off the grid (a file before then may have more in a row). */
    uint64_t every = sc->output_every; /* the file's, where it says (a deck may change it) */
    if (H5Aexists(o->file, "output_every") > 0 &&
        nbep__output_read_attr(o->file, path, "output_every", H5T_NATIVE_UINT64, &every, d) < 0)
        goto fail;
    hsize_t kept = frames;
    while (kept > 1 && o->xmf_step[kept - 1] % (int64_t)sc->output_every != 0 &&
           o->xmf_step[kept - 1] % (int64_t)(every ? every : 1) != 0)
        kept--;
    res.kept_step = o->xmf_step[kept - 1];
    /* past the file's last frame, not only the one resumed from: a cells run resumed from an
     * earlier frame to a step before its last would cut the frames it already has. A run that
     * reached run.steps but did not end as completed (a signal during its last step, which it
     * finished; a kill before its summary) resumes to that step, at no step where it resumes
     * from it, so that its summary says completed (until 2026-11-30 it was refused, and a
     * sweep ran such a run again from step 0) */
    const int ended = run_ended(o->file, path, d);
    if (ended < 0)
        goto fail;
    if (res.step < 0 || res.last_step < 0 || sc->steps < (uint64_t)res.last_step ||
        (sc->steps == (uint64_t)res.last_step && ended)) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: nothing to resume: its last frame is at step %lld and "
                      "run.steps is %llu (ask for more steps: -n, --set run.steps=)",
                      path, (long long)res.last_step, (unsigned long long)sc->steps);
        st = NBEP_EDECK;
        goto fail;
    }
    /* A predictive run at e < 1 carries state that no frame keeps: each sphere's last
     * collision (physics.tc's clock), and under accelerations the held spheres, their lasting
     * contacts past one plane, their response counts and the settling windows (algo_predictive.c,
     * pred_contacts). Files made since 2026-11-30 keep it for their last two frames
     * (/checkpoint/contacts, read below); from one without it for the frame (made before) a
     * resume starts them afresh, and its frames part from the uninterrupted run's (a
     * 300-sphere pile resumed at step 1000 with 55 spheres held, from step 1001 on; a cooling
     * gas with physics.tc = 0.3, from its first step). Said (run.c), not refused: the physics
     * stays right, and long granular runs are resumed for it. Where the deck changes the
     * restitution there is no uninterrupted run to match. */
    double e_file = sc->restitution;
    if (nbep__output_read_attr(o->file, path, "restitution", H5T_NATIVE_DOUBLE, &e_file, d) < 0)
        goto fail;
    res.restitution_kept = e_file == sc->restitution;
    res.n = n;
    res.pos = malloc((n ? n : 1) * sizeof *res.pos);
    res.vel = malloc((n ? n : 1) * sizeof *res.vel);
    if (!res.pos || !res.vel) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
        st = NBEP_ENOMEM;
        goto fail;
    }
    if (nbep__output_read_row(o->file, path, "/frames/position", last, 3 * (hsize_t)n,
                              H5T_NATIVE_DOUBLE, res.pos, d) < 0 ||
        nbep__output_read_row(o->file, path, "/frames/velocity", last, 3 * (hsize_t)n,
                              H5T_NATIVE_DOUBLE, res.vel, d) < 0)
        goto fail;
    /* No run writes a position or velocity that is not finite: a file that holds one was
     * changed or damaged (until 2026-12-01 a NaN there aborted the resumed run at its
     * summary's assertion, and left the file without its /summary). A finite state whose
     * energy is beyond doubles is refused by nbep_sim_create. */
    const size_t bad = resumed_state_fault(res.pos, res.vel, n);
    if (bad < n) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: its frame at step %lld holds sphere %zu at (%g, %g, %g) moving "
                      "at (%g, %g, %g), which no run writes: the file was changed or damaged; "
                      "resume a copy made before, or run afresh",
                      path, (long long)res.step, bad, res.pos[bad].x, res.pos[bad].y,
                      res.pos[bad].z, res.vel[bad].x, res.vel[bad].y, res.vel[bad].z);
        st = NBEP_EDECK;
        goto fail;
    }
    /* A periodic box: the image counts of that frame (SPEC /frames/image) */
    o->resume.image = nbep_scene_any_periodic(sc);
    if (o->resume.image) {
        res.image = malloc((n ? 3 * n : 1) * sizeof *res.image);
        if (!res.image) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
            st = NBEP_ENOMEM;
            goto fail;
        }
        if (H5Lexists(o->file, "/frames/image", H5P_DEFAULT) <= 0) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s has no /frames/image but %s has a periodic box; resume with "
                          "the deck (and --set options) that made it",
                          path, sc->deck_path);
            st = NBEP_EDECK;
            goto fail;
        }
        if (nbep__output_read_row(o->file, path, "/frames/image", last, 3 * (hsize_t)n,
                                  H5T_NATIVE_INT32, res.image, d) < 0)
            goto fail;
    }
    if (nbep__output_periodic(o, sc, d) < 0) {
        st = NBEP_ENOMEM;
        goto fail;
    }
    /* The run's totals at that frame, for its summary (a file made before 2026-11-30 has
     * none: the resumed run's summary then counts its own part, as it did) */
    st = read_totals(o, path, frames, last, &res, d);
    if (st != NBEP_OK)
        goto fail;
    /* a read that fails below is an I/O error, said by it (until 2026-12-02 these paths
     * returned read_totals's OK with the resume emptied, and the run aborted on an assertion,
     * exit 134, a sweep at each try: a file missing /stats/step, say) */
    st = NBEP_EIO;
    /* The event slots, where the file has them; the run uses them only when its algorithm
     * imports event slots (the algorithm table, sim.c), so a deck of another algorithm
     * continues from positions and velocities alone. */
    htri_t has_ck = H5Lexists(o->file, "/checkpoint", H5P_DEFAULT);
    o->resume.checkpoint = has_ck > 0;
    if (has_ck > 0) {
        /* a file that a part without event slots continued before 2026-11-30 holds fewer rows
         * than frames: where the frame resumed from has none, the run starts from positions
         * and velocities, as from a file without /checkpoint, and the missing rows are
         * written as stale slots (nbep_output_resume_begin) */
        hsize_t rows = 0;
        if (nbep__output_dataset_rows(o->file, path, nbep__ck_columns[0].name, &rows, d) < 0)
            goto fail;
        o->resume.ck_rows = rows < frames ? rows : frames;
        has_ck = last < rows;
    }
    if (has_ck > 0) {
        res.has_events = true;
        res.event_time = malloc((n ? n : 1) * sizeof *res.event_time);
        res.event_partner = malloc((n ? n : 1) * sizeof *res.event_partner);
        res.event_kind = malloc((n ? n : 1) * sizeof *res.event_kind);
        res.rest = malloc((n ? n : 1) * sizeof *res.rest);
        void *cols[N_CK_COLUMNS] = {res.event_time, res.event_partner, res.event_kind, res.rest};
        if (!res.event_time || !res.event_partner || !res.event_kind || !res.rest) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
            st = NBEP_ENOMEM;
            goto fail;
        }
        for (int c = 0; c < N_CK_COLUMNS; c++)
            if (nbep__output_read_row(o->file, path, nbep__ck_columns[c].name, last, n,
                                 *nbep__ck_columns[c].mem_type, cols[c], d) < 0)
                goto fail;
        const int rc = nbep__output_contacts_read(o, last, &res.contacts, d);
        if (rc < 0) {
            st = rc == -2 ? NBEP_EDECK : st;
            goto fail;
        }
        size_t at;
        const char *what;
        if (checkpoint_fault(&res, sc->state.n_planes, &at, &what)) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: its checkpoint at step %lld gives sphere %zu %s: the file "
                          "is damaged, or no run of this deck wrote it (run without --resume to "
                          "start afresh)",
                          path, (long long)res.step, at, what);
            st = NBEP_EDECK;
            goto fail;
        }
    }
    o->resume.stats = H5Lexists(o->file, "/stats", H5P_DEFAULT) > 0;
    if (o->resume.stats != sc->out_stats) { /* rows for every step, or none: not half */
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s %s /stats but the deck %s them (output.stats); resume with the "
                      "deck (and --set options) that made it",
                      path, o->resume.stats ? "has" : "has no", sc->out_stats ? "asks for" : "does not ask for");
        st = NBEP_EDECK;
        goto fail;
    }
    if (o->resume.stats) {
        uint64_t rows;
        rows_rc = nbep__output_complete_rows(o->file, path, "/stats", "/stats/step", &rows,
                                             &more, d);
        if (rows_rc < 0) {
            st = rows_rc == -2 ? NBEP_EDECK : NBEP_EIO;
            goto fail;
        }
        /* One row per step from step 1: the rows up to the frame's step stay. Every row of a
         * counted frame's steps is on disk (the rows' flush returns before a count is
         * written, nbep__output_commit), but a kill within the counts' flush can leave
         * /frames's count written and /stats's not: such rows, past the count, are kept. Fewer
         * rows than that, or a last row of another step, no run leaves: refused as damaged
         * (until 2026-12-05 the missing rows were skipped, the table jumping a stretch of
         * steps, and a review's edited count was resumed so). */
        const uint64_t need = (uint64_t)res.step;
        int64_t last_step = res.step;
        if (rows + more >= need && need > 0 &&
            nbep__output_read_row(o->file, path, "/stats/step", need - 1, 1, H5T_NATIVE_INT64,
                                  &last_step, d) < 0)
            goto fail;
        if (rows + more < need || last_step != res.step) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: its frame at step %lld follows %llu rows of /stats, but "
                          "/stats holds %llu%s: the file is damaged, or no run wrote it",
                          path, (long long)res.step, (unsigned long long)need,
                          (unsigned long long)(rows + more),
                          rows + more < need ? "" : ", the last of them of another step");
            st = NBEP_EDECK;
            goto fail;
        }
        o->resume.stats_keep = need;
        o->resume.wall = H5Lexists(o->file, "/stats/wall_impulse", H5P_DEFAULT) > 0;
    }
    /* nothing is written until nbep_output_resume_begin: a run refused after this (its
     * algorithm's own checks) leaves the file as it was */
    o->resume.pending = true;
    o->resume.dropped = frames < complete;
    o->resume.from = res.step;
    o->resume.trim = kept;
    o->n_frames = frames;
    nbep__output_room(o, sc);
    *out = o;
    *r = res;
    return NBEP_OK;
fail:
    nbep__output_release(&o);
    nbep_resume_fini(&res);
    return st;
}

nbep_status nbep_output_resume_begin(nbep_output *o, const nbep_scene *sc, int threads,
                                     nbep_diag *d)
{
    if (!o->resume.pending)
        return NBEP_OK;
    const char *path = o->path;
    /* the room first: a disk with none left refuses the resume before it changes the file */
    if (nbep__output_reserve(o, "the resume", d) < 0)
        return NBEP_EIO;
    const hsize_t frames = o->n_frames;
    const uint64_t keep = o->resume.stats_keep;
    /* A run killed while it wrote a frame can leave that frame's chunks past the file's end
     * of allocation (the superblock's, written at each flush): the extents and chunk indexes
     * that name them reached the disk, the new end of allocation did not. Cutting the rows
     * below frees those chunks, which HDF5 then refused as lying outside the file ("addr
     * overflow" at the next flush, exit 1, until 2026-11-30). The end of allocation is first
     * raised to the file's size, so they lie inside it. */
    if (H5Fincrement_filesize(o->file, 0) < 0) {
        HDF5_FAIL(d, path, "take in the space a cut-short write left past its end");
        return NBEP_EIO;
    }
    /* The counts first, made durable, then the rows cut: a kill between the two leaves counts
     * at or below the rows (readable, as any file whose last write was cut short), where the
     * other order left counts above them (a file nothing could read: frames kept in cells
     * mode are fewer than the complete ones). */
    if (open_count(o, "/frames", &o->frames_count, d) < 0 ||
        (o->resume.stats && open_count(o, "/stats", &o->stats_count, d) < 0))
        return NBEP_EIO;
    const uint64_t n_frames = frames, n_stats = keep;
    if (H5Awrite(o->frames_count, H5T_NATIVE_UINT64, &n_frames) < 0 ||
        (o->resume.stats && H5Awrite(o->stats_count, H5T_NATIVE_UINT64, &n_stats) < 0) ||
        H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        HDF5_FAIL(d, path, "lower the count attributes to the frame resumed from");
        return NBEP_EIO;
    }
    /* Continue appending after the frame resumed from: cut everything written past it. */
    if ((o->resume.image && open_cut(o, "/frames/image", frames, &o->frame_img, d) < 0) ||
        open_cut(o, "/frames/step", frames, &o->frame_step, d) < 0 ||
        open_cut(o, "/frames/time", frames, &o->frame_time, d) < 0 ||
        open_cut(o, "/frames/position", frames, &o->frame_pos, d) < 0 ||
        open_cut(o, "/frames/velocity", frames, &o->frame_vel, d) < 0 ||
        (o->resume.totals && open_cut(o, "/frames/totals", frames, &o->frame_tot, d) < 0))
        return NBEP_EIO;
    if (o->resume.totals && (o->tot_type = nbep__output_totals_type()) < 0) {
        HDF5_FAIL(d, path, "make the type of /frames/totals");
        return NBEP_EIO;
    }
    if (o->resume.checkpoint) {
        for (int c = 0; c < N_CK_COLUMNS; c++)
            if (open_cut(o, nbep__ck_columns[c].name, frames, &o->ck[c], d) < 0)
                return NBEP_EIO;
        if (o->resume.ck_rows < frames &&
            nbep__output_ck_stale(o, o->resume.ck_rows, frames, d) < 0)
            return NBEP_EIO;
    }
    o->xmf = true; /* resumed runs have positions */
    o->sidecar = nbep__output_writes_sidecar(o->xmf, path);
    if (o->resume.stats) {
        for (int c = 0; c < STATS_N_COLUMNS; c++)
            if (open_cut(o, nbep__stats_columns[c].name, keep, &o->stats[c], d) < 0)
                return NBEP_EIO;
        o->n_planes = sc->state.n_planes;
        if (o->resume.wall && open_cut(o, "/stats/wall_impulse", keep, &o->stats_wall, d) < 0)
            return NBEP_EIO;
        o->n_stats = keep;
    }
    o->resume.pending = false;
    /* The summary described the run as it ended; it goes, and is written again at the new
     * end (nbep_output_close), so that a resumed run cut short has none, as a run does */
    const htri_t had = H5Lexists(o->file, "/summary", H5P_DEFAULT);
    if (had < 0 || (had > 0 && H5Ldelete(o->file, "/summary", H5P_DEFAULT) < 0)) {
        HDF5_FAIL(d, path, "reset /summary");
        return NBEP_EIO;
    }
    hid_t steps_attr = H5Aopen(o->file, "steps", H5P_DEFAULT);
    if (steps_attr < 0 || H5Awrite(steps_attr, H5T_NATIVE_UINT64, &sc->steps) < 0) {
        HDF5_FAIL(d, path, "update the root attribute steps");
        nbep__output_close_id(&steps_attr);
        return NBEP_EIO;
    }
    nbep__output_close_id(&steps_attr);
    if (note_resume(o->file, path, sc, threads, o->resume.from, o->resume.changed,
                    &o->resume.other_algorithm, d) < 0 ||
        nbep__output_commit(o, frames, d) < 0)
        return NBEP_EIO;
    nbep__output_sidecar_stale(o);
    /* frames dropped: the sidecar listed them; it lists what the file holds */
    return o->resume.dropped ? nbep__output_xmf_write(o, true, d) : NBEP_OK;
}
