/* Compiler-specific attributes and small portable helpers, kept in one place (STYLE 2). */
#ifndef NBEP_COMPILER_H
#define NBEP_COMPILER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define NBEP_CACHELINE 64

#if defined(__GNUC__)
#define NBEP_MUST_CHECK __attribute__((warn_unused_result))
#define NBEP_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#define NBEP_UNLIKELY(x) __builtin_expect(!!(x), 0)
/* A hint to fetch the cache line holding *p for reading; no effect on results. */
#define NBEP_PREFETCH(p) __builtin_prefetch((p), 0, 3)
/* The same, for writing: the line is fetched ready to be written (from another core's cache,
 * without a second trip to take it over). */
#define NBEP_PREFETCH_W(p) __builtin_prefetch((p), 1, 3)
/* Inlined whatever the compiler's estimate. A helper made only of NBEP_PREFETCH needs it: GCC
 * 12 takes prefetches for no effect, so a helper it does not inline is found pure, and a call
 * to a pure function returning nothing is deleted with its prefetches. Also for a kernel that
 * must be specialised at each call (its flags constant there). */
#define NBEP_ALWAYS_INLINE __attribute__((always_inline))
/* Never inlined: a rare path kept out of its caller's common one (so that the common one
 * saves no registers the rare one needs). */
#define NBEP_NOINLINE __attribute__((noinline))
#else
#define NBEP_MUST_CHECK
#define NBEP_PRINTF(fmt, args)
#define NBEP_UNLIKELY(x) (x)
#define NBEP_PREFETCH(p) ((void)(p))
#define NBEP_PREFETCH_W(p) ((void)(p))
#define NBEP_ALWAYS_INLINE
#define NBEP_NOINLINE
#endif

/* A function built twice, for CPUs with fused multiply-add and for the rest, the right one
 * chosen when the program starts: its fma() calls become one instruction instead of a call
 * into libm. fma is correctly rounded either way and ffp-contract stays off, so both give the
 * same bits. GCC on x86-64 only; elsewhere a plain function. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define NBEP_FMA_CLONES __attribute__((target_clones("fma", "default")))
/* The same with AVX2 (four doubles a vector, gathers): for loops the compiler vectorises (the
 * build's -fno-trapping-math lets it turn their selects into vector blends). */
#define NBEP_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
/* The same with AVX-512 too (sixteen floats a vector), for short loops of a fixed length. */
#define NBEP_AVX512_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define NBEP_FMA_CLONES
#define NBEP_AVX2_CLONES
#define NBEP_AVX512_CLONES
#endif

/* n rounded up to a multiple of 8: a record's payload after its 8-byte-aligned header. */
static inline size_t nbep_round8(size_t n)
{
    return (n + 7) / 8 * 8;
}

/* Allocates n * size bytes aligned to a cache line, zero-filled; NULL on failure or overflow.
 * Free with nbep_free_aligned (NULL-safe). An array that fills a huge page (NBEP_HUGE) or
 * nearly is aligned to one and asks for them (nbep_huge_pages). */
void *nbep_alloc_aligned(size_t n, size_t size);
void nbep_free_aligned(void *p);

/* Room for one more element of `elem` bytes past the n in *p (room for *cap of them), the room
 * doubled from 64 as needed (realloc); false, nothing changed, when no memory could be had. The
 * slabs' logs and queues (undo.c, warp.c) grow so, several times an event: the look inline, the
 * growth out of line (a call each time cost the optimistic scheduler about 25 instructions an
 * event of its 340: docs/optimistic-design.md, *Ties in time*). */
bool nbep_room_grow(void **p, size_t *cap, size_t n, size_t elem);
static inline bool nbep_room_for_one(void **p, size_t *cap, size_t n, size_t elem)
{
    return n < *cap || nbep_room_grow(p, cap, n, elem);
}

/* Asks the kernel to back the whole huge pages within [p, p + bytes) by huge pages
 * (transparent huge pages, madvise mode; nothing where it has none): the engines' arrays are
 * read at random, one sphere here and one there, and with small pages nearly each miss of the
 * caches at N = 256000 was also a miss of the TLB. No effect on results. */
#define NBEP_HUGE ((size_t)2 << 20)
void nbep_huge_pages(void *p, size_t bytes);
/* Once, before the run's arrays are made (main): every allocation of NBEP_HUGE / 2 bytes or
 * more from a fresh mapping (glibc), whose pages nbep_huge_pages can still ask for. */
void nbep_memory_init(void);

/* Seconds on the monotonic clock (for durations only). */
double nbep_now(void);

/* v in the fewest significant digits (6 at least, as %g, up to 17) that read back as v, in
 * buf (32 bytes), which it returns: a deck's value named in an error as %g rounded it, and
 * "must be in [0, 1] (got 1)" was said of 1.0000000001 (until 2026-12-01). */
const char *nbep_fmt_exact(double v, char *buf);
/* nbep_fmt_exact into a buffer of the enclosing statement's block: for printf's arguments */
#define NBEP_G(v) nbep_fmt_exact((v), (char[32]){0})

/* The 8 bytes an HDF5 file begins with (nbep's files have no user block before them): a deck
 * that is one is refused as such, and a summary is not written over one. */
#define NBEP_HDF5_SIGNATURE "\x89HDF\r\n\x1a\n"
#define NBEP_HDF5_SIGNATURE_LEN 8

/* Whether name ends with suffix. */
bool nbep_ends_with(const char *name, const char *suffix);

/* "PATH.partial" (malloc'd; NULL without memory): the name a file is written under before it
 * is renamed to path once complete, so that a kill or a refusal never leaves a half-written
 * file at path nor removes an older one (the run's file, its summary, a sweep's tables). */
char *nbep_partial_path(const char *path);
/* "PATH.lock" (malloc'd; NULL without memory): the lock a run holds while it writes the file at
 * path (nbep_lock_take), removed at its end. */
char *nbep_lock_path(const char *path);

/* An exclusive lock on the file at path (made if missing, left in place), for a writer that
 * must be the only one (a sweep's folder, a run's output): its descriptor, which holds the
 * lock until nbep_lock_drop or the process's end, however it ends. -1 without it: *busy when
 * another descriptor holds it (in this process or another), else false (a file system without
 * locks, a folder that takes no new file: the caller goes on unguarded). */
int nbep_lock_take(const char *path, bool *busy);
/* Reserves on its disk the len bytes of file fd from offset `from`, its size unchanged
 * (fallocate's FALLOC_FL_KEEP_SIZE): writes that later extend the file into them find room.
 * 0, else the errno: ENOSPC or EDQUOT where the disk or the quota has no room, EOPNOTSUPP,
 * ENOSYS or EINVAL where the file system cannot reserve (NFS, some parallel ones). */
int nbep_file_reserve(int fd, int64_t from, int64_t len);
/* Gives back what nbep_file_reserve reserved past the end of the file at path (up to offset
 * `end`; the file cut to its own size, its bytes unchanged). Nothing where end is not past
 * it. */
void nbep_file_unreserve(const char *path, int64_t end);
/* The same for the file open on fd (writable). */
void nbep_file_unreserve_fd(int fd, int64_t end);
/* Lets the lock go: removes the file at remove_path first, when not NULL (the lock's name,
 * for a lock beside a file of the user's) and it is still the lock's own, empty file, and
 * closes fd. Nothing for fd < 0. */
void nbep_lock_drop(int fd, const char *remove_path);
/* Whether path names the file open on fd (a lock taken on a file whose name its holder has
 * since removed guards nothing: nbep_lock_take tries again). */
bool nbep_lock_names(int fd, const char *path);

/* The directory part of path, malloc'd: "." for a bare name, "/" for a name in the root
 * ("a/b/c.h5": "a/b"); NULL without memory. */
char *nbep_path_dir(const char *path);
/* The file a symbolic link at path leads to (realpath, malloc'd), for the files a run keeps
 * beside the one it writes (a resume's lock and sidecar are the target's); NULL where path is
 * no link, the link leads nowhere, or without memory: the caller then uses path itself. */
char *nbep_link_target(const char *path);

/* 0 when a new file can be made in the folder dir, else the errno that making one fails with
 * (EACCES, EROFS, ENOENT...), for the checks that say before a run or a sweep begins whether
 * its files can be made. access() asks only the permission bits, which root passes in any
 * folder: in /proc, or on a file system that takes no new files without being mounted
 * read-only, `nbep check -o /proc/x.h5` passed what `nbep run` refused (ENOENT making its
 * .partial) until 2026-12-04. So once access() passes, an empty file with a name of its own
 * is made there and removed at once. */
int nbep_dir_takes_files(const char *dir);

/* A byte count as people read it (`nbep check`'s memory and output, the sweep's, the errors
 * of a scene too large): 3 significant figures in decimal units, B, kB, MB, GB, TB, PB and EB
 * (powers of 1000, as disks and `df -H` count), the unit chosen so that the figure is below
 * 1000 once rounded ("86.1 GB", "999 kB", "1 MB", "512 B"). Writes buf and returns it; every
 * size nbep prints goes through it. */
#define NBEP_BYTES_TEXT_MAX 24
const char *nbep_format_bytes(double bytes, char buf[NBEP_BYTES_TEXT_MAX]);

/* A time to go as people read it, the unit chosen so that the figure stays below 100 (days
 * below 1000): "42 s", "52 min", "27.3 h", "12 days", and "over 1000 days" past that or for a
 * NaN (a run stuck at 1e-12 steps a second said "ETA 540260248143089 s" until 2026-11-30).
 * Writes buf and returns it. */
#define NBEP_DURATION_TEXT_MAX 24
const char *nbep_format_duration(double seconds, char buf[NBEP_DURATION_TEXT_MAX]);

/* The process's peak resident memory in bytes since the last nbep_peak_rss_reset (Linux:
 * VmHWM of /proc/self/status, which writing 5 to /proc/self/clear_refs resets), else since it
 * started (getrusage's ru_maxrss); 0 when neither can be read. A sweep's rank runs one run
 * after another, and a lifetime peak gave a small run the memory of a large one before it. */
uint64_t nbep_peak_rss(void);
void nbep_peak_rss_reset(void);

/* One step of a spin-wait: a CPU pause, and sched_yield() every 1024th call so that more
 * threads than cores still make progress (STYLE 6). k counts the calls of one wait from 1. */
void nbep_spin_pause(unsigned k);

/* Sleeping on a 32-bit word (Linux futexes; elsewhere a yield): nbep_word_wait returns once
 * *word may differ from `expected` (at once if it already does; spuriously at times: callers
 * look again), nbep_word_wake_all wakes every thread waiting on word. The word is read and
 * written through C11 atomics only; these add no ordering of their own. */
void nbep_word_wait(const void *word, unsigned expected);
void nbep_word_wake_all(const void *word);

#endif
