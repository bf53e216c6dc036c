/* /checkpoint/contacts: the lasting state of a dissipative predictive run's spheres
 * (nbep_contact_rec), kept for its last two frames, so that `--resume` continues it bit for
 * bit as it does an elastic run from its event slots (output.h).
 *
 * Layout (beyond SPEC): /checkpoint/contacts, a compound dataset of shape (2, N) whose fields
 * are nbep_contact_rec's, and /checkpoint/contacts_frame, i64 (2): the frame row each of its
 * two rows holds, -1 for none. Frame row f goes to row f % 2. Two, not one a frame: the state
 * is some 250 bytes a sphere, five times a frame's positions and velocities, and a resume
 * mostly starts from the file's last frame or, in cells mode, from the one before it
 * (the last frame is then a stop's own, off output.every's grid, and that frame and its
 * predecessor lie in different rows). Writing frame f overwrites the row of frame f - 2: a
 * kill while it is written leaves frame f - 1 and its row whole (the count attribute,
 * output.c), and the row of f - 2 is first marked -1 and that mark flushed, since a cells
 * resume can reach back past f - 1 (to the last frame at a multiple of output.every, two or
 * more back where an earlier part ran with another output.every): until 2026-11-30 the row
 * kept frame f - 2's tag while frame f's records reached the disk, and a cells resume from
 * f - 2 after a kill there took that mixture for frame f - 2's state, silently (a 300-sphere
 * pile then overlapped by 4 % of a radius). A frame written without
 * that state (a naive part, or a part whose deck made it elastic) marks its row -1. A resume
 * takes a row only where contacts_frame names the frame it starts from; otherwise (a file
 * made before this existed) it starts the state afresh and says so (run.c). */
#include <stdlib.h>
#include <string.h>

#include "output_impl.h"

#define CONTACTS "/checkpoint/contacts"
#define CONTACTS_FRAME "/checkpoint/contacts_frame"
/* Records per write: about 250 kB of buffer whatever the run's size. */
#define CONTACT_BATCH 1024

/* An array member of n values of base (2-D when n2 > 0); negative on failure. */
static hid_t array_of(hid_t base, hsize_t n, hsize_t n2)
{
    hsize_t dims[2] = {n, n2};
    return H5Tarray_create2(base, n2 ? 2 : 1, dims);
}

/* The record's HDF5 type, native (the file's too: HDF5 keeps its byte order and converts on
 * a machine of the other); negative on failure. */
static hid_t contact_type(void)
{
    const hsize_t nf = NBEP_CONTACT_FACES, nc = NBEP_CONTACT_MAX;
    hid_t t = H5Tcreate(H5T_COMPOUND, sizeof(nbep_contact_rec));
    hid_t v3 = array_of(H5T_NATIVE_DOUBLE, 3, 0), fd = array_of(H5T_NATIVE_DOUBLE, nf, 0);
    hid_t fv = array_of(H5T_NATIVE_DOUBLE, nf, 3), fi = array_of(H5T_NATIVE_INT32, nf, 0);
    hid_t ci = array_of(H5T_NATIVE_INT32, nc, 0), cu = array_of(H5T_NATIVE_UINT8, nc, 0);
    bool ok = t >= 0 && v3 >= 0 && fd >= 0 && fv >= 0 && fi >= 0 && ci >= 0 && cu >= 0;
#define MEMBER(name, type)                                                                         \
    ok = ok && H5Tinsert(t, #name, HOFFSET(nbep_contact_rec, name), (type)) >= 0
    MEMBER(t_last, H5T_NATIVE_DOUBLE);
    MEMBER(aeff, v3);
    MEMBER(peak2, H5T_NATIVE_DOUBLE);
    MEMBER(face_t, fd);
    MEMBER(face_n, fv);
    MEMBER(face_p, fv);
    MEMBER(face_who, fi);
    MEMBER(rest_who, ci);
    MEMBER(slow, H5T_NATIVE_UINT32);
    MEMBER(has_last, H5T_NATIVE_UINT8);
    MEMBER(rest_n, H5T_NATIVE_UINT8);
    MEMBER(rest_still, H5T_NATIVE_UINT8);
    MEMBER(rest_current, cu);
#undef MEMBER
    hid_t parts[] = {v3, fd, fv, fi, ci, cu};
    for (size_t k = 0; k < sizeof parts / sizeof parts[0]; k++)
        nbep__output_close_id(&parts[k]);
    if (!ok)
        nbep__output_close_id(&t);
    return t;
}

/* Opens (or, when make, creates) the two datasets into o->contacts[0..1], and their record's
 * type into o->contacts_type; -1 on failure. */
static int contacts_open(nbep_output *o, bool make, nbep_diag *d)
{
    hid_t type = o->contacts_type = contact_type();
    if (type < 0) {
        HDF5_FAIL(d, o->path, "make the type of %s", CONTACTS);
        return -1;
    }
    int rc = -1;
    if (!make) {
        o->contacts[0] = H5Dopen2(o->file, CONTACTS, H5P_DEFAULT);
        o->contacts[1] = H5Dopen2(o->file, CONTACTS_FRAME, H5P_DEFAULT);
        if (o->contacts[0] < 0 || o->contacts[1] < 0)
            HDF5_FAIL(d, o->path, "open %s", CONTACTS);
        else
            rc = 0;
        goto done;
    }
    hsize_t dims[2] = {2, o->n_spheres}, two[1] = {2};
    hid_t space = H5Screate_simple(2, dims, NULL), tags = H5Screate_simple(1, two, NULL);
    const int64_t none[2] = {-1, -1};
    if (space >= 0 && tags >= 0) {
        o->contacts[0] = H5Dcreate2(o->file, CONTACTS, type, space, H5P_DEFAULT, H5P_DEFAULT,
                                    H5P_DEFAULT);
        o->contacts[1] = H5Dcreate2(o->file, CONTACTS_FRAME, H5T_STD_I64LE, tags, H5P_DEFAULT,
                                    H5P_DEFAULT, H5P_DEFAULT);
    }
    if (o->contacts[0] < 0 || o->contacts[1] < 0 ||
        H5Dwrite(o->contacts[1], H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, none) < 0)
        HDF5_FAIL(d, o->path, "create %s", CONTACTS);
    else
        rc = 0;
    nbep__output_close_id(&space);
    nbep__output_close_id(&tags);
done:
    if (rc < 0) {
        nbep__output_close_id(&o->contacts[0]);
        nbep__output_close_id(&o->contacts[1]);
        nbep__output_close_id(&o->contacts_type);
    }
    return rc;
}

/* The two datasets open: 1 (made first where the file has none and `make`), 0 where the file
 * has none (and not make), or -1 with HDF5's reason in d. Looks at the file once a handle. */
static int contacts_ready(nbep_output *o, bool make, nbep_diag *d)
{
    if (o->contacts[0] >= 0)
        return 1;
    const htri_t has = H5Lexists(o->file, CONTACTS, H5P_DEFAULT);
    if (has < 0) {
        HDF5_FAIL(d, o->path, "look for %s", CONTACTS);
        return -1;
    }
    if (!has && !make)
        return 0;
    return contacts_open(o, !has, d) < 0 ? -1 : 1;
}

/* contacts_frame[slot] = row. */
static int tag_slot(nbep_output *o, hsize_t slot, int64_t row, nbep_diag *d)
{
    hsize_t start[1] = {slot}, one[1] = {1};
    hid_t mem = H5Screate_simple(1, one, NULL), file = H5Dget_space(o->contacts[1]);
    int rc = -1;
    if (mem >= 0 && file >= 0 &&
        H5Sselect_hyperslab(file, H5S_SELECT_SET, start, NULL, one, NULL) >= 0 &&
        H5Dwrite(o->contacts[1], H5T_NATIVE_INT64, mem, file, H5P_DEFAULT, &row) >= 0)
        rc = 0;
    else
        HDF5_FAIL(d, o->path, "write %s", CONTACTS_FRAME);
    nbep__output_close_id(&mem);
    nbep__output_close_id(&file);
    return rc;
}

int nbep__output_contacts_write(nbep_output *o, hsize_t f, const nbep_events_view *ev,
                                nbep_diag *d)
{
    const hsize_t slot = f % 2;
    const bool lasting = ev && ev->contacts;
    const int ready = contacts_ready(o, lasting, d);
    if (ready <= 0)
        return ready;
    if (!lasting) /* a frame without the state: its row holds none */
        return tag_slot(o, slot, -1, d);
    /* the row's old frame unnamed, on disk, before any record of this one can reach it (see
     * the top: a resume may still look for that frame) */
    if (tag_slot(o, slot, -1, d) < 0)
        return -1;
    if (H5Dflush(o->contacts[1]) < 0) {
        HDF5_FAIL(d, o->path, "flush %s", CONTACTS_FRAME);
        return -1;
    }
    if (!o->contacts_buf && !(o->contacts_buf = malloc(CONTACT_BATCH * sizeof *o->contacts_buf))) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the contacts' rows",
                      o->path);
        return -1;
    }
    hid_t file = H5Dget_space(o->contacts[0]), mem = H5I_INVALID_HID;
    int rc = file >= 0 ? 0 : -1;
    if (rc < 0)
        HDF5_FAIL(d, o->path, "write %s", CONTACTS);
    for (size_t lo = 0; rc == 0 && lo < o->n_spheres; lo += CONTACT_BATCH) {
        const size_t hi = o->n_spheres - lo < CONTACT_BATCH ? o->n_spheres : lo + CONTACT_BATCH;
        ev->contacts(ev->contacts_ctx, lo, hi, o->contacts_buf);
        hsize_t start[2] = {slot, lo}, count[2] = {1, hi - lo};
        mem = H5Screate_simple(2, count, NULL);
        if (mem < 0 || H5Sselect_hyperslab(file, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
            H5Dwrite(o->contacts[0], o->contacts_type, mem, file, H5P_DEFAULT,
                     o->contacts_buf) < 0) {
            HDF5_FAIL(d, o->path, "write row %llu of %s", (unsigned long long)slot, CONTACTS);
            rc = -1;
        }
        nbep__output_close_id(&mem);
    }
    nbep__output_close_id(&file);
    return rc == 0 ? tag_slot(o, slot, (int64_t)f, d) : -1;
}

int nbep__output_contacts_read(nbep_output *o, hsize_t f, nbep_contact_rec **out, nbep_diag *d)
{
    *out = NULL;
    const int ready = contacts_ready(o, false, d);
    if (ready <= 0)
        return ready;
    int64_t tags[2];
    hid_t file = H5Dget_space(o->contacts[0]);
    hsize_t dims[2] = {0, 0};
    if (file < 0 || H5Sget_simple_extent_dims(file, dims, NULL) != 2 || dims[0] != 2 ||
        dims[1] != o->n_spheres ||
        H5Dread(o->contacts[1], H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, tags) < 0) {
        HDF5_FAIL(d, o->path, "read %s", CONTACTS);
        nbep__output_close_id(&file);
        return -1;
    }
    const hsize_t slot = f % 2;
    if (tags[slot] != (int64_t)f) { /* no state kept for that frame: none to give */
        nbep__output_close_id(&file);
        return 0;
    }
    char missing[NBEP_FIELD_NAME_MAX];
    if (nbep__output_fields_missing(o->file, o->path, CONTACTS, o->contacts_type, missing, d) <
            0 ||
        missing[0]) {
        nbep__output_close_id(&file);
        if (!missing[0])
            return -1;
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: its %s has no field %s of a run's (a field missing or of "
                      "another type): the file is damaged, or no run of this deck wrote it (run "
                      "without --resume to start afresh)",
                      o->path, CONTACTS, missing);
        return -2;
    }
    nbep_contact_rec *rec = malloc((o->n_spheres ? o->n_spheres : 1) * sizeof *rec);
    hid_t mem = H5I_INVALID_HID;
    hsize_t start[2] = {slot, 0}, count[2] = {1, o->n_spheres};
    int rc = -1;
    if (!rec) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory to read %s", o->path,
                      CONTACTS);
    } else if (o->n_spheres == 0) {
        rc = 0;
    } else if ((mem = H5Screate_simple(2, count, NULL)) < 0 ||
               H5Sselect_hyperslab(file, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
               H5Dread(o->contacts[0], o->contacts_type, mem, file, H5P_DEFAULT, rec) < 0) {
        HDF5_FAIL(d, o->path, "read row %llu of %s", (unsigned long long)slot, CONTACTS);
    } else {
        rc = 0;
    }
    nbep__output_close_id(&mem);
    nbep__output_close_id(&file);
    if (rc < 0) {
        free(rec);
        return -1;
    }
    *out = rec;
    return 0;
}

double nbep__output_contacts_bytes(size_t n)
{
    return 2.0 * (double)n * (double)sizeof(nbep_contact_rec) + 16.0;
}
