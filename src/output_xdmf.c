/* XDMF sidecar of a run file (output_xdmf.h). The layout, per frame k of F (N spheres):
 *
 *   <Grid Name="step S" GridType="Uniform">            inside a Temporal Collection
 *     <Time Value="t_k"/>
 *     <Topology TopologyType="Polyvertex" NumberOfElements="N" NodesPerElement="1"/>
 *     <Geometry GeometryType="XYZ">  HyperSlab start (k,0,0) stride (1,1,1) count (1,N,3)
 *                                    of RUN.h5:/frames/position, declared (F,N,3)
 *     <Attribute radius|mass Scalar Node>   RUN.h5:/spheres/radius|mass (N)
 *     <Attribute velocity Vector Node>      the same hyperslab of /frames/velocity
 *
 * Polyvertex without a connectivity array: readers (ParaView's XDMF2 and XDMF3 readers,
 * VisIt) number the points 0..N-1 themselves, which is what one vertex per sphere means.
 * XDMF 2.0 rather than 3.0 because every XDMF reader in use accepts it.
 *
 * The sidecar is rewritten whole at every call (its size grows by about 1.5 kB per frame), to
 * "SIDECAR.tmp" then renamed: readers never see a half-written file. */
#include "nbep/output_xdmf.h"
#include "nbep/summary.h"

#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The comment at a sidecar's top that names its run (xml_head writes it, nbep_xdmf_run_of
 * reads it): RUN_NOTE, the run file's name, ": N spheres, ...". The name as it is, but for
 * '%' written "%25" and a '-' after a '-' written "%2D" (note_name): "--" may not stand in an
 * XML comment, and entities are not read in one (until 2026-12-01 the name was XML-escaped
 * there, "a&amp;b.h5", and a run named run--e0.9.h5 had a sidecar that XML parsers refuse). */
#define RUN_NOTE "<!-- nbep run "
#define RUN_NOTE_SPHERES " spheres, "

char *nbep_xdmf_path(const char *h5_path)
{
    size_t len = strlen(h5_path);
    bool h5 = len >= 3 && strcmp(h5_path + len - 3, ".h5") == 0;
    size_t stem = h5 ? len - 3 : len;
    char *p = malloc(stem + sizeof ".xmf");
    if (p) {
        memcpy(p, h5_path, stem);
        memcpy(p + stem, ".xmf", sizeof ".xmf");
    }
    return p;
}

bool nbep_xdmf_run_of(const char *path, char *name, size_t len)
{
    name[0] = '\0';
    char head[1024];
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    const size_t n = fread(head, 1, sizeof head - 1, f);
    fclose(f);
    head[n] = '\0';
    if (!strstr(head, "<Xdmf"))
        return false;
    const char *at = strstr(head, RUN_NOTE);
    const char *end = at ? strstr(at, RUN_NOTE_SPHERES) : NULL;
    if (!end)
        return true;
    at += strlen(RUN_NOTE);
    while (end > at && end[-1] >= '0' && end[-1] <= '9')
        end--; /* back over the count to the ": " before it */
    if (end - at >= 3 && end[-2] == ':' && end[-1] == ' ' &&
        !memchr(at, '\n', (size_t)(end - at))) {
        const char *stop = end - 2;
        size_t w = 0;
        for (const char *r = at; r < stop && w + 1 < len; r++) {
            unsigned hex = 0;
            if (*r == '%' && stop - r >= 3 && sscanf(r + 1, "%2x", &hex) == 1 &&
                (hex == '%' || hex == '-')) {
                name[w++] = (char)hex;
                r += 2;
            } else {
                name[w++] = *r;
            }
        }
        name[w] = '\0';
    }
    return true;
}

/* The part of a path after its last '/'. */
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

bool nbep_xdmf_can_name(const char *h5_path)
{
    const char *base = base_name(h5_path);
    for (const unsigned char *r = (const unsigned char *)base; *r; r++)
        if (*r < 0x20) /* XML 1.0 has no characters below the space but TAB, LF, CR */
            return false;
    return nbep_utf8_valid(base);
}

char *nbep_xdmf_other_run(const char *h5_path)
{
    /* the one other name whose sidecar this is: x for x.h5, x.h5 for x */
    const size_t len = strlen(h5_path);
    char *other = malloc(len + sizeof ".h5"), *xmf = nbep_xdmf_path(h5_path), name[1024];
    if (other && nbep_ends_with(h5_path, ".h5")) {
        memcpy(other, h5_path, len - 3);
        other[len - 3] = '\0';
    } else if (other) {
        memcpy(other, h5_path, len);
        memcpy(other + len, ".h5", sizeof ".h5");
    }
    /* there, and the sidecar names it (not a stale one whose run is gone, nor this run's own
     * beside a folder x); read only as a regular file: a FIFO there would block the read (a
     * review, 2026-12-02) */
    struct stat sb;
    const bool theirs = other && xmf && *base_name(other) && access(other, F_OK) == 0 &&
                        stat(xmf, &sb) == 0 && S_ISREG(sb.st_mode) &&
                        nbep_xdmf_run_of(xmf, name, sizeof name) &&
                        strcmp(name, base_name(other)) == 0;
    free(xmf);
    if (!theirs) {
        free(other);
        return NULL;
    }
    return other;
}

/* The base name of a path for the comment that names the run (RUN_NOTE), into a malloc'd
 * string. */
static char *note_name(const char *path)
{
    const char *base = base_name(path);
    char *out = malloc(3 * strlen(base) + 1);
    if (!out)
        return NULL;
    char *w = out;
    for (const char *r = base; *r; r++) {
        if (*r == '%' || (*r == '-' && r > base && r[-1] == '-')) {
            w += sprintf(w, "%%%02X", (unsigned)(unsigned char)*r);
        } else {
            *w++ = *r;
        }
    }
    *w = '\0';
    return out;
}

/* The base name of a path, XML-escaped for an element's text, into a malloc'd string. */
static char *xml_base_name(const char *path)
{
    const char *base = base_name(path);
    char *out = malloc(6 * strlen(base) + 1);   /* "&quot;" is the longest escape */
    if (!out)
        return NULL;
    char *w = out;
    for (const char *r = base; *r; r++) {
        const char *esc = *r == '&'    ? "&amp;"
                          : *r == '<'  ? "&lt;"
                          : *r == '>'  ? "&gt;"
                          : *r == '"'  ? "&quot;"
                          : *r == '\'' ? "&apos;"
                                       : NULL;
        if (esc) {
            strcpy(w, esc);
            w += strlen(esc);
        } else {
            *w++ = *r;
        }
    }
    *w = '\0';
    return out;
}

/* Where the XML goes: a file, or (f NULL) nowhere, only counted: nbep_xdmf_bytes sizes the
 * sidecar with the very calls that write it. */
typedef struct xml_out {
    FILE *f;
    double bytes;
} xml_out;

static void out(xml_out *o, const char *fmt, ...) NBEP_PRINTF(2, 3);
static void out(xml_out *o, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int k = o->f ? vfprintf(o->f, fmt, ap) : vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (k > 0)
        o->bytes += k;
}

/* One frame's slice of a (F, N, 3) dataset: start (k, 0, 0), stride 1, count (1, N, 3). */
static void hyperslab(xml_out *o, const char *indent, const char *h5, const char *dataset,
                      size_t k, size_t n_frames, size_t n)
{
    out(o, "%s<DataItem ItemType=\"HyperSlab\" Dimensions=\"1 %zu 3\" Type=\"HyperSlab\">\n",
        indent, n);
    out(o, "%s  <DataItem Dimensions=\"3 3\" NumberType=\"Int\" Format=\"XML\">"
           "%zu 0 0 1 1 1 1 %zu 3</DataItem>\n",
        indent, k, n);
    out(o, "%s  <DataItem Dimensions=\"%zu %zu 3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"HDF\">%s:/frames/%s</DataItem>\n",
        indent, n_frames, n, h5, dataset);
    out(o, "%s</DataItem>\n", indent);
}

static void scalar(xml_out *o, const char *h5, const char *name, size_t n)
{
    out(o, "        <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n", name);
    out(o, "          <DataItem Dimensions=\"%zu\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"HDF\">%s:/spheres/%s</DataItem>\n",
        n, h5, name);
    out(o, "        </Attribute>\n");
}

static void xml_head(xml_out *o, const char *note, size_t n, size_t n_frames)
{
    out(o, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
           RUN_NOTE "%s: %zu" RUN_NOTE_SPHERES "%zu frames (written by nbep) -->\n"
           "<Xdmf Version=\"2.0\">\n  <Domain>\n"
           "    <Grid Name=\"spheres\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
        note, n, n_frames);
}

/* Frame k of n_frames, at step *step (NULL: named by its index) and time t. */
static void xml_frame(xml_out *o, const char *h5, size_t n, size_t n_frames, size_t k,
                      const int64_t *step, double t, bool has_velocity)
{
    if (step)
        out(o, "      <Grid Name=\"step %" PRId64 "\" GridType=\"Uniform\">\n", *step);
    else
        out(o, "      <Grid Name=\"frame %zu\" GridType=\"Uniform\">\n", k);
    /* %.17g: the exact double, so that readers order and label frames as the file does */
    out(o, "        <Time Value=\"%.17g\"/>\n", t);
    out(o, "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" "
           "NodesPerElement=\"1\"/>\n",
        n);
    out(o, "        <Geometry GeometryType=\"XYZ\">\n");
    hyperslab(o, "          ", h5, "position", k, n_frames, n);
    out(o, "        </Geometry>\n");
    scalar(o, h5, "radius", n);
    scalar(o, h5, "mass", n);
    if (has_velocity) {
        out(o, "        <Attribute Name=\"velocity\" AttributeType=\"Vector\" "
               "Center=\"Node\">\n");
        hyperslab(o, "          ", h5, "velocity", k, n_frames, n);
        out(o, "        </Attribute>\n");
    }
    out(o, "      </Grid>\n");
}

static void xml_tail(xml_out *o)
{
    out(o, "    </Grid>\n  </Domain>\n</Xdmf>\n");
}

static void write_xml(FILE *f, const char *h5, const char *note, size_t n, size_t n_frames,
                      const int64_t *steps, const double *times, bool has_velocity)
{
    xml_out o = {.f = f};
    xml_head(&o, note, n, n_frames);
    for (size_t k = 0; k < n_frames; k++)
        xml_frame(&o, h5, n, n_frames, k, steps ? &steps[k] : NULL, times[k], has_velocity);
    xml_tail(&o);
}

/* Frames measured one by one up to this many; past it, this many spread evenly over the run
 * stand for all (a frame's text differs from the next only in the digits of its index, step
 * and time: a few bytes of some 1500). */
#define BYTES_SAMPLED_FRAMES 256

double nbep_xdmf_bytes(const char *h5_path, size_t n_spheres, uint64_t steps, uint64_t every,
                       double dt, bool has_velocity)
{
    if (every == 0)
        return 0.0;
    /* frames at steps 0, every, 2 every, ... and at the last step (nbep_output_frames) */
    const uint64_t n_frames = steps / every + 1 + (steps % every ? 1 : 0);
    char *escaped = xml_base_name(h5_path), *note = note_name(h5_path);
    const char *h5 = escaped ? escaped : base_name(h5_path); /* no memory: near enough */
    xml_out o = {.f = NULL};
    xml_head(&o, note ? note : h5, n_spheres, (size_t)n_frames);
    xml_tail(&o);
    const uint64_t sampled = n_frames < BYTES_SAMPLED_FRAMES ? n_frames : BYTES_SAMPLED_FRAMES;
    xml_out frames = {.f = NULL};
    for (uint64_t i = 0; i < sampled; i++) {
        const uint64_t k = sampled == 1 ? 0 : (uint64_t)((double)i * (double)(n_frames - 1) /
                                                         (double)(sampled - 1));
        const int64_t step = (int64_t)(k + 1 < n_frames ? k * every : steps);
        xml_frame(&frames, h5, n_spheres, (size_t)n_frames, (size_t)k, &step,
                  (double)step * dt, has_velocity);
    }
    free(escaped);
    free(note);
    return o.bytes + (sampled ? frames.bytes / (double)sampled * (double)n_frames : 0.0);
}

double nbep_xdmf_bytes_bound(const char *h5_path, size_t n_spheres, size_t n_frames,
                             bool has_velocity)
{
    char *escaped = xml_base_name(h5_path), *note = note_name(h5_path);
    const char *h5 = escaped ? escaped : base_name(h5_path); /* no memory: near enough */
    xml_out o = {.f = NULL}, frame = {.f = NULL};
    xml_head(&o, note ? note : h5, n_spheres, n_frames);
    xml_tail(&o);
    /* the longest a frame's text can be: an index of n_frames' digits, a step of 20 characters
     * and a time of 24 (%.17g of a negative double with a three-digit exponent) */
    const int64_t longest_step = INT64_MIN;
    xml_frame(&frame, h5, n_spheres, n_frames, n_frames, &longest_step,
              -2.2250738585072014e-308, has_velocity);
    free(escaped);
    free(note);
    return o.bytes + frame.bytes * (double)n_frames;
}

/* Every frame while the sidecar is this short: the first frames are what users open first. */
#define EVERY_FRAME_UP_TO 8

bool nbep_xdmf_due(size_t n_frames, double seconds_since_last)
{
    return n_frames <= EVERY_FRAME_UP_TO || (n_frames & (n_frames - 1)) == 0 ||
           seconds_since_last >= NBEP_XDMF_REWRITE_SECONDS;
}

nbep_status nbep_xdmf_write(const char *h5_path, size_t n_spheres, size_t n_frames,
                            const int64_t *steps, const double *times, bool has_velocity,
                            nbep_diag *d)
{
    char *xmf = nbep_xdmf_path(h5_path);
    char *tmp = xmf ? malloc(strlen(xmf) + sizeof ".tmp") : NULL;
    char *h5 = xml_base_name(h5_path), *note = note_name(h5_path);
    nbep_status st = NBEP_ENOMEM;
    if (!xmf || !tmp || !h5 || !note) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: no memory for the XDMF sidecar of %zu frames", h5_path,
                      n_frames);
        goto done;
    }
    sprintf(tmp, "%s.tmp", xmf);
    st = NBEP_EIO;
    FILE *f = fopen(tmp, "w");
    if (!f) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot write the XDMF sidecar: %s", tmp,
                      strerror(errno));
        goto done;
    }
    write_xml(f, h5, note, n_spheres, n_frames, steps, times, has_velocity);
    int err = ferror(f) ? (errno ? errno : EIO) : 0;
    if (fclose(f) != 0 && !err)
        err = errno ? errno : EIO;
    if (err || rename(tmp, xmf) != 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot write the XDMF sidecar: %s", xmf,
                      strerror(err ? err : errno));
        remove(tmp);
        goto done;
    }
    st = NBEP_OK;
done:
    free(h5);
    free(note);
    free(tmp);
    free(xmf);
    return st;
}
