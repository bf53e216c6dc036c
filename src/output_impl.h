/* Internals shared by the output module's files (output.c: the run format; output_sweep.c:
 * the sweep table). The only place besides them that sees hdf5.h. */
#ifndef NBEP_OUTPUT_IMPL_H
#define NBEP_OUTPUT_IMPL_H

#include <hdf5.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

/* Adds "nbep: PATH: cannot WHAT: REASON", REASON being HDF5's innermost (most specific) error,
 * or the system's text for file-open failures, on one line. Call right after the failing HDF5
 * call: any later HDF5 call (even a close) clears the error stack. */
void nbep__output_hdf5_fail(nbep_diag *d, const char *file, int line, const char *path,
                            const char *what_fmt, ...) NBEP_PRINTF(5, 6);
#define HDF5_FAIL(d, path, ...) nbep__output_hdf5_fail((d), __FILE__, __LINE__, (path), __VA_ARGS__)

/* Releases an id (ignoring errors: failure paths) and sets it invalid. */
void nbep__output_close_id(hid_t *id);
/* A variable-length UTF-8 string type (caller closes), or a negative id. */
hid_t nbep__output_utf8_string_type(void);

#endif
