/* Reading a run's HDF5 file back in tests (include after cmocka.h). */
#ifndef NBEP_TEST_H5_H
#define NBEP_TEST_H5_H

#include <hdf5.h>
#include <stdlib.h>

/* Dataset `name` of an open file: its extent in dims (up to 3, the rest left as they were)
 * and, when buf is not NULL, its values as `type` into buf. */
static inline void nbep_test_h5_read(hid_t file, const char *name, hid_t type, void *buf,
                                     hsize_t *dims)
{
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    assert_true(ds >= 0);
    hid_t sp = H5Dget_space(ds);
    assert_true(H5Sget_simple_extent_dims(sp, dims, NULL) >= 1);
    if (buf)
        assert_true(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    H5Sclose(sp);
    H5Dclose(ds);
}

/* Dataset `name` of the run written to path: *n doubles, malloc'd. */
static inline double *nbep_test_h5_doubles(const char *path, const char *name, size_t *n)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    hsize_t dims[3] = {1, 1, 1};
    nbep_test_h5_read(file, name, H5T_NATIVE_DOUBLE, NULL, dims);
    *n = (size_t)(dims[0] * dims[1] * dims[2]);
    double *buf = malloc((*n ? *n : 1) * sizeof *buf);
    assert_non_null(buf);
    nbep_test_h5_read(file, name, H5T_NATIVE_DOUBLE, buf, dims);
    H5Fclose(file);
    return buf;
}

#endif
