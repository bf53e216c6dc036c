/* Aligned allocation, the spin-wait pause, sleeping on a word and the text of a byte count,
 * shared by every module. */
#define _GNU_SOURCE /* syscall() for futexes, F_OFD_SETLK */
#include "nbep/compiler.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>

#include <sched.h>
#include <stdbool.h>
#include <stdint.h>
#ifdef __linux__
#include <linux/futex.h>
#include <malloc.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#ifdef __linux__
#include <sys/mman.h>
#endif

void *nbep_alloc_aligned(size_t n, size_t size)
{
    if (size != 0 && n > SIZE_MAX / size)
        return NULL;
    size_t bytes = n * size;
    if (bytes > SIZE_MAX - NBEP_HUGE) /* no such memory; the roundings below would wrap */
        return NULL;
    /* aligned_alloc wants a multiple of the alignment; never ask for 0 bytes. */
    bytes = (bytes + NBEP_CACHELINE - 1) / NBEP_CACHELINE * NBEP_CACHELINE;
    if (bytes == 0)
        bytes = NBEP_CACHELINE;
    /* a large array: from a huge page's start, its room a whole number of them; on huge
     * pages (nbep_huge_pages) those it fills, and its last too where that makes at most a
     * sixteenth of it more resident (an array of n doubles at n = 256000 is 2048000 bytes,
     * 49 kB short of a huge page); the rest of its room is never touched, never resident */
    const size_t room = (bytes + NBEP_HUGE - 1) / NBEP_HUGE * NBEP_HUGE;
    const size_t huge = room - bytes <= bytes / 16 ? room : bytes / NBEP_HUGE * NBEP_HUGE;
    void *p = huge ? aligned_alloc(NBEP_HUGE, room) : aligned_alloc(NBEP_CACHELINE, bytes);
    if (p && huge)
        nbep_huge_pages(p, huge);
    if (p)
        memset(p, 0, bytes);
    return p;
}

void nbep_memory_init(void)
{
#if defined(__GLIBC__) && defined(M_MMAP_THRESHOLD)
    /* glibc serves a large allocation from a fresh mapping only up to a threshold that it
     * raises when such a mapping is freed (the HDF5 library frees some as a run resumes): past
     * it, from its heap, whose pages the freed blocks left resident as small pages, where a
     * request for huge ones comes too late. A fixed threshold also gives the freed ones back
     * at once. */
    (void)mallopt(M_MMAP_THRESHOLD, (int)(NBEP_HUGE / 2));
#endif
}

void nbep_huge_pages(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    const uintptr_t lo = ((uintptr_t)p + NBEP_HUGE - 1) / NBEP_HUGE * NBEP_HUGE,
                    hi = ((uintptr_t)p + bytes) / NBEP_HUGE * NBEP_HUGE;
    if (hi > lo) /* a refusal (no such pages here) leaves small pages, which work as well */
        (void)madvise((void *)lo, hi - lo, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

void nbep_free_aligned(void *p)
{
    free(p);
}

bool nbep_room_grow(void **p, size_t *cap, size_t n, size_t elem)
{
    if (n < *cap)
        return true;
    const size_t grown = *cap ? 2 * *cap : 64;
    if (grown > SIZE_MAX / elem)
        return false;
    void *q = realloc(*p, grown * elem);
    if (!q)
        return false;
    *p = q;
    *cap = grown;
    return true;
}

static char *suffixed(const char *path, const char *suffix)
{
    char *p = malloc(strlen(path) + strlen(suffix) + 1);
    if (p)
        strcat(strcpy(p, path), suffix);
    return p;
}

const char *nbep_fmt_exact(double v, char *buf)
{
    for (int digits = 6; digits <= 17; digits++) {
        snprintf(buf, 32, "%.*g", digits, v);
        if (!isfinite(v) || strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

char *nbep_partial_path(const char *path)
{
    return suffixed(path, ".partial");
}

bool nbep_ends_with(const char *name, const char *suffix)
{
    const size_t n = strlen(name), k = strlen(suffix);
    return n >= k && strcmp(name + n - k, suffix) == 0;
}

char *nbep_lock_path(const char *path)
{
    return suffixed(path, ".lock");
}

/* Open file description locks (Linux 3.15) belong to the descriptor, not the process: closing
 * another descriptor of the same file (HDF5's, a summary's) does not let them go, and two in
 * one process exclude each other. Elsewhere the process's own (POSIX) locks. */
#ifdef F_OFD_SETLK
#define LOCK_CMD F_OFD_SETLK
#else
#define LOCK_CMD F_SETLK
#endif

bool nbep_lock_names(int fd, const char *path)
{
    struct stat held, named;
    return fstat(fd, &held) == 0 && stat(path, &named) == 0 && held.st_dev == named.st_dev &&
           held.st_ino == named.st_ino;
}

int nbep_lock_take(const char *path, bool *busy)
{
    *busy = false;
    /* A holder that ends removes the name (nbep_lock_drop with remove): a descriptor opened on
     * the old file before that and locked after holds a file no one else will open, so the
     * lock stands only if the name still leads to the file it holds; otherwise again (a few
     * times: each retry follows a holder's end). */
    for (int tries = 0; tries < 16; tries++) {
        int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
        short type = F_WRLCK;
        /* another user's lock file (0644 under umask 022, in a folder a group shares): read
         * only, a read lock, which a holder's write lock excludes and which excludes a writer
         * (until 2026-12-01 the run went on unguarded, and replaced a file another user's run
         * was writing). Two such readers do not exclude each other: the file's owner's lock is
         * the one that guards. */
        if (fd < 0 && (errno == EACCES || errno == EPERM)) {
            fd = open(path, O_RDONLY | O_CLOEXEC);
            type = F_RDLCK;
        }
        if (fd < 0)
            return -1;
        struct flock fl = {.l_type = type, .l_whence = SEEK_SET, .l_start = 0, .l_len = 0};
        if (fcntl(fd, LOCK_CMD, &fl) != 0) {
            *busy = errno == EACCES || errno == EAGAIN;
            close(fd);
            return -1;
        }
        if (nbep_lock_names(fd, path))
            return fd;
        close(fd);
    }
    return -1;
}

int nbep_file_reserve(int fd, int64_t from, int64_t len)
{
    return fallocate(fd, FALLOC_FL_KEEP_SIZE, (off_t)from, (off_t)len) == 0 ? 0 : errno;
}

void nbep_file_unreserve_fd(int fd, int64_t end)
{
    struct stat sb;
    /* cut to its own size: the blocks past it go (a hole punched there frees nothing on
     * ext4, which punches within the size only) */
    if (fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && end > (int64_t)sb.st_size)
        (void)ftruncate(fd, sb.st_size);
}

void nbep_file_unreserve(const char *path, int64_t end)
{
    int fd = open(path, O_WRONLY | O_CLOEXEC);
    if (fd < 0)
        return;
    nbep_file_unreserve_fd(fd, end);
    close(fd);
}

void nbep_lock_drop(int fd, const char *remove_path)
{
    if (fd < 0)
        return;
    /* while still held: whoever opens the name next opens a new file. Only the lock's own
     * file, empty as the lock left it: a file put at its name since (another run's output
     * renamed there) or a user's file it found there is not the lock's to remove */
    struct stat sb;
    if (remove_path && nbep_lock_names(fd, remove_path) && fstat(fd, &sb) == 0 && sb.st_size == 0)
        unlink(remove_path);
    close(fd);
}

char *nbep_path_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path)) : strdup(".");
}

char *nbep_link_target(const char *path)
{
    struct stat sb;
    return lstat(path, &sb) == 0 && S_ISLNK(sb.st_mode) ? realpath(path, NULL) : NULL;
}

int nbep_dir_takes_files(const char *dir)
{
    if (access(dir, W_OK | X_OK) != 0)
        return errno;
    static const char name[] = "/.nbep-probe-XXXXXX";
    const size_t n = strlen(dir);
    char *probe = malloc(n + sizeof name);
    if (!probe)
        return ENOMEM;
    memcpy(probe, dir, n);
    memcpy(probe + n, name, sizeof name);
    const int fd = mkostemp(probe, O_CLOEXEC);
    /* a probe's name too long for a folder near PATH_MAX says nothing of the run's own file,
     * whose name staged_name_fits checks: access()'s answer stands */
    const int err = fd >= 0 ? 0 : errno == ENAMETOOLONG ? 0 : errno;
    if (fd >= 0) {
        close(fd);
        unlink(probe);
    }
    free(probe);
    return err;
}

const char *nbep_format_bytes(double bytes, char buf[NBEP_BYTES_TEXT_MAX])
{
    static const char *const unit[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
    const size_t last = sizeof unit / sizeof *unit - 1;
    size_t u = 0;
    /* 999.5 and above print as 1e+03 at 3 figures: the next unit's 1 */
    while (u < last && fabs(bytes) >= 999.5) {
        bytes /= 1000.0;
        u++;
    }
    snprintf(buf, NBEP_BYTES_TEXT_MAX, "%.3g %s", bytes, unit[u]);
    return buf;
}

const char *nbep_format_duration(double seconds, char buf[NBEP_DURATION_TEXT_MAX])
{
    /* each bound is where the rounded figure would print as the next unit's 100 (1000 days);
     * a NaN fails every test and takes the last line */
    if (seconds < 99.5)
        snprintf(buf, NBEP_DURATION_TEXT_MAX, "%.0f s", seconds > 0.0 ? seconds : 0.0);
    else if (seconds < 99.5 * 60.0)
        snprintf(buf, NBEP_DURATION_TEXT_MAX, "%.0f min", seconds / 60.0);
    else if (seconds < 99.95 * 3600.0)
        snprintf(buf, NBEP_DURATION_TEXT_MAX, "%.1f h", seconds / 3600.0);
    else if (seconds < 999.5 * 86400.0)
        snprintf(buf, NBEP_DURATION_TEXT_MAX, "%.0f days", seconds / 86400.0);
    else
        snprintf(buf, NBEP_DURATION_TEXT_MAX, "over 1000 days");
    return buf;
}

double nbep_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void nbep_spin_pause(unsigned k)
{
    /* Yield every 1024 spins: with more threads than cores a pure spin would burn the
     * waiting thread's whole time slice while the thread it waits for cannot run. */
    if (k % 1024 == 0) {
        sched_yield();
        return;
    }
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

void nbep_word_wait(const void *word, unsigned expected)
{
#ifdef __linux__
    /* the kernel compares *word with expected and sleeps only if equal, atomically with
     * respect to a wake: a change made before the wake is never slept through */
    syscall(SYS_futex, word, FUTEX_WAIT_PRIVATE, expected, NULL, NULL, 0);
#else
    (void)word;
    (void)expected;
    sched_yield();
#endif
}

void nbep_word_wake_all(const void *word)
{
#ifdef __linux__
    syscall(SYS_futex, word, FUTEX_WAKE_PRIVATE, INT32_MAX, NULL, NULL, 0);
#else
    (void)word;
#endif
}

void nbep_peak_rss_reset(void)
{
#ifdef __linux__
    malloc_trim(0); /* what an earlier run freed goes back first: it is not this run's */
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (f) {
        fputs("5", f);
        fclose(f);
    }
#endif
}

uint64_t nbep_peak_rss(void)
{
#ifdef __linux__
    FILE *f = fopen("/proc/self/status", "r");
    if (f) {
        char line[256];
        unsigned long long kib = 0;
        bool found = false;
        while (!found && fgets(line, sizeof line, f))
            found = sscanf(line, "VmHWM: %llu kB", &kib) == 1;
        fclose(f);
        if (found)
            return (uint64_t)kib * 1024u;
    }
#endif
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0;
    return (uint64_t)ru.ru_maxrss * 1024u; /* Linux reports KiB */
}
