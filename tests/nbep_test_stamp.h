/* A root stamp (versions.h's nbep_stamp_at) where a stamp is taken by pointer (undo.h): a
 * compound literal, which lives to the end of the enclosing block. */
#ifndef NBEP_TEST_STAMP_H
#define NBEP_TEST_STAMP_H

#include "nbep/versions.h"

#define STAMP_AT(t_, key_, item_)                                                                  \
    (&(const nbep_stamp){.t = (t_), .depth = 1, .level = {{(key_), (item_), 0}}})

#endif
