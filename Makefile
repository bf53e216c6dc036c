# nbep: N-Body Event Prediction. `make` builds bin/nbep; `make check` runs every test.

# ---- switches ----------------------------------------------------------------------------
OMP ?= 1
MPI ?= auto
VALGRIND ?= 0
PREFIX ?= /usr/local
CC ?= gcc
WERROR ?=
SAN ?=

# ---- machinery ---------------------------------------------------------------------------
VERSION := 0.1.0
PKGS := gsl libconfig hdf5 jansson
PKG_CFLAGS := $(shell pkg-config --cflags $(PKGS))
# HDF5's high-level library (H5LT) comes with it but has no pkg-config entry of its own
PKG_LIBS := $(shell pkg-config --libs $(PKGS)) -lhdf5_hl

BUILD := build
CSTD := -std=c11 -D_POSIX_C_SOURCE=200809L
WARN := -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes $(WERROR)
OPT := -O3 -g -ffp-contract=off -fno-trapping-math
CFLAGS_ALL := $(CSTD) $(OPT) $(WARN) -MMD -MP -Iinclude -Isrc -I$(BUILD) $(PKG_CFLAGS) $(CFLAGS)
LDLIBS_ALL := $(PKG_LIBS) -lm $(LDLIBS)

ifeq ($(OMP),1)
CFLAGS_ALL += -fopenmp
LDLIBS_ALL += -fopenmp
else
# a serial build: the algorithms' OpenMP pragmas are meant to be ignored then
CFLAGS_ALL += -Wno-unknown-pragmas
endif
ifeq ($(MPI),auto)
MPI := $(shell pkg-config --exists ompi-c && echo 1 || echo 0)
endif
ifeq ($(MPI),1)
MPI_CFLAGS := $(shell pkg-config --cflags ompi-c) -DNBEP_HAVE_MPI=1
LDLIBS_ALL += $(shell pkg-config --libs ompi-c)
endif
ifeq ($(SAN),address)
CFLAGS_ALL += -fsanitize=address,undefined -fno-omit-frame-pointer
LDLIBS_ALL += -fsanitize=address,undefined
endif
ifeq ($(SAN),thread)
CFLAGS_ALL += -fsanitize=thread
LDLIBS_ALL += -fsanitize=thread
endif

LIB_SRC := $(filter-out src/main.c,$(wildcard src/*.c))
LIB_OBJ := $(LIB_SRC:src/%.c=$(BUILD)/%.o)
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TEST_SH := $(wildcard tests/test_*.sh)
BENCH_SRC := $(wildcard tests/bench/bench_*.c)
BENCH_BIN := $(BENCH_SRC:tests/bench/%.c=$(BUILD)/bench/%)
BUILD_INFO := $(BUILD)/build_info.h
# the deck parser's fuzz harness, replayed on the tests' decks (tests/fuzz/replay.c): built from
# the sources scripts/fuzz.sh links, without OpenMP
FUZZ_SRC := $(shell grep -v -e '^\#' -e '^[[:space:]]*$$' tests/fuzz/sources)
FUZZ_REPLAY := $(BUILD)/tests/fuzz_replay
# bin/nbep with a copy of the event loop that follows what each event touches (README, Threads
# on dense scenes): built by check too, so that a change to the loop's hooks cannot leave it
# broken unseen
PARALLELISM := $(BUILD)/bench/bench_parallelism
# the same with a copy whose leader notes where its time goes (README, Threads on dense scenes)
LEADER := $(BUILD)/bench/bench_leader
# the same with a copy whose events also do the optimistic scheme's bookkeeping (README,
# Threads on dense scenes): tests/test_optimistic_model.sh checks its bound
VERSIONS := $(BUILD)/bench/bench_versions
# the same with a copy of the scheduled loop that counts what ends its windows on slabs (README,
# Micro-benchmarks): tests/test_optimistic_model.sh runs it
WINDOWS := $(BUILD)/bench/bench_windows

# One job a core unless -j is given: a serial build takes over a minute on 2 cores (the slowest
# file, evloop.c, 5 s alone), about half that in parallel. Only at the top: a make
# that `make pgo` runs shares its parent's jobs (it cannot see a -j its parent set here).
ifeq ($(MAKELEVEL)$(filter -j%,$(MAKEFLAGS)),0)
MAKEFLAGS += -j$(shell nproc 2>/dev/null || echo 1)
endif

.PHONY: all run check test valgrind bench bench-programs install clean tsan asan mutate mutate-sample check-programs pgo
all: bin/nbep

$(BUILD) $(BUILD)/tests $(BUILD)/bench bin:
	@mkdir -p $@

# Regenerated only when its text changes, so objects do not rebuild needlessly. The commit gets
# "-modified" when tracked files differ from it (a build of changed sources: --version and the
# run file's build_commit say so, where they named the commit alone until 2026-11-30).
$(BUILD_INFO): FORCE | $(BUILD)
	@c=$$(git rev-parse --short HEAD 2>/dev/null) && \
	  { git diff --quiet HEAD -- 2>/dev/null || c=$$c-modified; } || c=unknown; \
	printf '#define NBEP_VERSION "%s"\n#define NBEP_BUILD_FLAGS "%s"\n#define NBEP_BUILD_COMMIT "%s"\n' \
	  '$(VERSION)' '$(strip $(CC) $(OPT) $(CFLAGS)) OMP=$(OMP) MPI=$(MPI)' "$$c" > $@.tmp
	@cmp -s $@.tmp $@ && rm -f $@.tmp || mv $@.tmp $@
FORCE:

$(BUILD)/%.o: src/%.c $(BUILD_INFO) | $(BUILD)
	$(CC) $(CFLAGS_ALL) -c $< -o $@
$(BUILD)/sweep.o: CFLAGS_ALL += $(MPI_CFLAGS)

$(BUILD)/libnbep.a: $(LIB_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

bin/nbep: $(BUILD)/main.o $(BUILD)/libnbep.a | bin
	$(CC) $(CFLAGS_ALL) $^ -o $@ $(LDLIBS_ALL)

# The same program linked inside a build folder (make pgo builds its own in build/pgo, and
# compares it with build/nbep, the plain build's).
$(BUILD)/nbep: $(BUILD)/main.o $(BUILD)/libnbep.a
	$(CC) $(CFLAGS_ALL) $^ -o $@ $(LDLIBS_ALL)

$(BUILD)/tests/%: tests/%.c tests/nbep_test.h $(BUILD)/libnbep.a | $(BUILD)/tests
	$(CC) $(CFLAGS_ALL) -Itests $< $(BUILD)/libnbep.a -o $@ $(LDLIBS_ALL) \
	  $(shell pkg-config --libs cmocka) -lpthread $(TEST_WRAP)

# test_memory_plan counts what the code allocates: malloc and its kin wrapped in that binary
$(BUILD)/tests/test_memory_plan: TEST_WRAP := $(foreach f,malloc calloc realloc free \
  nbep_alloc_aligned,-Wl,--wrap=$(f))

# test_ways_clock sees the seconds that choose a step's threads on their way to pred_ways.c
$(BUILD)/tests/test_ways_clock: TEST_WRAP := $(foreach f,nbep__pred_ways_choose_crew \
  nbep__pred_ways_choose nbep__pred_ways_note,-Wl,--wrap=$(f))

$(BUILD)/bench/%: tests/bench/%.c tests/bench/bench_util.h $(BUILD)/libnbep.a | $(BUILD)/bench
	$(CC) $(CFLAGS_ALL) -Itests $< $(BUILD)/libnbep.a -o $@ $(LDLIBS_ALL)

run: bin/nbep
	bin/nbep run inputs/paper-box.deck --summary -

# bin/nbep built with GCC's profile-guided and link-time optimisation (README, Building for
# production runs): an instrumented build runs short training scenes, then the build that uses
# their profile is checked to write the same frames, bit for bit, as the plain build/nbep
# before it replaces bin/nbep. A later `make` after a source change builds the plain one again.
pgo: $(BUILD)/nbep
	+bash scripts/pgo.sh

# Every test binary and shell test (those drive bin/nbep as a user would), one a core at a time
# (NBEP_TEST_JOBS), then with VALGRIND=1 the test binaries again under memcheck (make valgrind;
# CI runs both, one after the other: memcheck alone takes longer than the 10 minutes a check
# should take).
check: bin/nbep $(TEST_BIN) $(FUZZ_REPLAY) $(PARALLELISM) $(LEADER) $(VERSIONS) $(WINDOWS)
	@python3 scripts/mutate.py --stale
	@bash scripts/run-tests.sh $(TEST_BIN) $(TEST_SH)
ifeq ($(VALGRIND),1)
	@bash scripts/run-tests.sh --valgrind $(TEST_BIN)
endif
test: check

# The test binaries under memcheck alone (check runs them so too with VALGRIND=1).
valgrind: $(TEST_BIN)
	@bash scripts/run-tests.sh --valgrind $(TEST_BIN)

# Every program make check runs, built but not run (scripts/mutate.py builds these per mutant).
check-programs: bin/nbep $(TEST_BIN) $(FUZZ_REPLAY) $(PARALLELISM) $(LEADER) $(VERSIONS) \
		$(WINDOWS)

$(FUZZ_REPLAY): tests/fuzz/replay.c tests/fuzz/fuzz_scene.c tests/fuzz/sources $(FUZZ_SRC) \
		$(wildcard include/nbep/*.h src/*.h) | $(BUILD)/tests
	$(CC) $(CSTD) -O1 -g $(WARN) -Wno-unknown-pragmas -Iinclude -Isrc $(PKG_CFLAGS) \
		$(CFLAGS) tests/fuzz/replay.c tests/fuzz/fuzz_scene.c $(FUZZ_SRC) -o $@ \
		$(PKG_LIBS) -lm $(LDLIBS)

# Mutation testing (README "Tests"): scripted small bugs in a scratch copy, each against the
# tests that should catch it; not part of check (it takes tens of minutes).
mutate:
	python3 scripts/mutate.py $(MUTATE_ARGS)

# A random sample of mechanical mutants of the core (an operator changed at a site drawn at
# random), each against every unit test: the tests' kill rate on bugs nobody chose.
mutate-sample:
	python3 scripts/mutate-sample.py $(SAMPLE_ARGS)

bench: bin/nbep $(BENCH_BIN)
	bash scripts/bench.sh

# What scripts/bench.sh needs, built and not run (then `scripts/bench.sh --quick` runs alone).
bench-programs: bin/nbep $(BENCH_BIN)

# Dense fluids (N = 32000, phi = 0.30 and 0.50, periodic): predictive cells beside EDMD when
# EDMD_DIR names a checkout of FSmallenburg/EDMD (built in build/bench-dense, never committed).
.PHONY: bench-dense
bench-dense: bin/nbep
	bash scripts/bench-dense.sh

# The same fluids counted instead of timed: instructions and simulated cache misses per
# collision, nbep beside EDMD, under valgrind's cachegrind (scripts/bench-dense.sh, COUNT).
.PHONY: bench-dense-count
bench-dense-count: bin/nbep
	COUNT=1 bash scripts/bench-dense.sh

# A freely cooling granular gas (the dense fluid resumed at e = 0.9 from its melt): one
# thread against the team loop, and the temperature against Haff's law (NS, PHI, E, THREADS,
# REPS, S in the environment; scripts/bench-cooling.py).
.PHONY: bench-cooling
bench-cooling: bin/nbep
	/usr/bin/python3 scripts/bench-cooling.py

# The paper's step (run.order = "step", approximate) against the exact time order on crowded
# scenes (fluids at phi 0.30 and 0.50, a pile), cells mode beside them; BENCH_ORDER_ARGS.
.PHONY: bench-order
bench-order: bin/nbep
	/usr/bin/python3 scripts/bench-order.py $(BENCH_ORDER_ARGS)

# The hopper (inputs/hopper.deck, no box) with 400 spheres: grid against cells mode, 1 and 2
# threads, medians of 3; BENCH_HOPPER_ARGS = COUNT STEPS REPEATS.
.PHONY: bench-hopper
bench-hopper: bin/nbep
	sh scripts/bench-hopper.sh $(BENCH_HOPPER_ARGS)

# The granular pile (inputs/pile.deck) poured and settled, e = 0.5 against 1, 1 and 2 threads:
# collisions per step, spheres held and wall time over the run (over an hour per e = 0.5 run;
# BENCH_PILE_ARGS, e.g. "--count 300 --steps 2400" for a smaller pile, with BENCH_PILE_PLOT
# naming its figure elsewhere than README's).
BENCH_PILE_PLOT ?= docs/figures/bench-pile.png
.PHONY: bench-pile
bench-pile: bin/nbep
	/usr/bin/python3 scripts/bench-pile.py --jobs 2 --plot $(BENCH_PILE_PLOT) $(BENCH_PILE_ARGS)

# Accuracy against cost of the three algorithms over dt, and of the contact-time solvers
# (docs/accuracy.md); ACC_ARGS=--quick for a smoke run.
.PHONY: accuracy
accuracy: bin/nbep $(BUILD)/bench/bench_contact
	bash scripts/accuracy.sh $(ACC_ARGS)

# ThreadSanitizer needs an instrumented OpenMP runtime: clang + libomp + Archer (scripts/).
tsan: $(BUILD_INFO)
	bash scripts/tsan.sh
# NBEP_TEST_SAN: the shell tests skip the checks that measure the sanitizer (tests/lib.sh);
# a test runs about three times as long, so each gets valgrind's time limit. UBSan stops the
# program at its first report (it printed and went on, so a test that read only the exit
# status passed over an index past an array: a mutant of jam_lock's walk, 2026-12-04).
asan:
	$(MAKE) clean && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 NBEP_TEST_SAN=address \
	  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	  NBEP_TEST_TIMEOUT=1800 $(MAKE) SAN=address VALGRIND=0 check

install: bin/nbep
	install -d $(DESTDIR)$(PREFIX)/bin
	install -m 755 bin/nbep $(DESTDIR)$(PREFIX)/bin/nbep

clean:
	rm -rf $(BUILD) bin

-include $(LIB_OBJ:.o=.d) $(BUILD)/main.d
# Test and benchmark binaries compile and link in one step; their .d files sit beside them, so
# editing a header they include (tests/nbep_test_scene.h, include/nbep/...) rebuilds them.
-include $(TEST_BIN:=.d) $(BENCH_BIN:=.d)
