/* Names of the counters, from the one X-macro list in stats.h. */
#include "nbep/stats.h"

const char *const nbep_counter_names[NBEP_COUNTER_COUNT] = {
#define NBEP_X_NAME(name, key) key,
    NBEP_COUNTER_LIST(NBEP_X_NAME)
#undef NBEP_X_NAME
};
