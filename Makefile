# tessera - build, run, test. Dependencies come through pkg-config.
# `make WERROR=1` (as CI does) turns warnings into errors.

CC  ?= gcc
CXX ?= g++
PKGS := libdrm libudev libseat libsystemd libinput libevdev json-c assimp libxxhash libwebsockets \
        libturbojpeg ompi-c
# OpenImageIO is linked into the image module only, never into an executable (wall/dump_module.h:
# its 260 libraries cost every process start 0.33 s of CPU)
IMAGE_PKGS := OpenImageIO
TEST_PKGS := criterion

BUILD := build
WERROR ?= 0
OPT ?= -O2
SAN ?=
# UNROBUST=1: the fast, non-robust kernels (engine/accel/intersect.h: TESSERA_UNROBUST), only ever
# in their own tree (make unrobust: build-unrobust/tessera)
UNROBUST ?= 0

# generic x86-64 baseline: SIMD paths are chosen at run time, never -march=native
WARN := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes
ifeq ($(WERROR),1)
WARN += -Werror
endif
CPPFLAGS := -D_POSIX_C_SOURCE=200809L -I. $(shell pkg-config --cflags $(PKGS) $(IMAGE_PKGS) 2>/dev/null)
ifeq ($(UNROBUST),1)
CPPFLAGS += -DTESSERA_UNROBUST
endif
CFLAGS := -std=c11 $(OPT) -g $(WARN) -ffp-contract=off -fno-math-errno -pthread $(SAN)
CXXFLAGS := -std=c++17 $(OPT) -g -Wall -Wextra $(if $(filter 1,$(WERROR)),-Werror) -pthread $(SAN)
LDLIBS := $(shell pkg-config --libs $(PKGS) 2>/dev/null) -ldl -lm -pthread
IMAGE_LDLIBS := $(shell pkg-config --libs $(IMAGE_PKGS) 2>/dev/null)
TEST_LDLIBS := $(shell pkg-config --libs $(TEST_PKGS) 2>/dev/null)

# the engine in layers (docs/layers.md): every .c below engine/ but the kernels' one source,
# which is compiled once per instruction set (ISA_OBJ)
ENGINE_SRC := $(sort $(filter-out engine/accel/isa/%,$(shell find engine -name '*.c')))
WALL_SRC := $(wildcard wall/*.c)
# the seat (libseat): who may open the DRM card and the input devices; wall/ and input/ both use it
SEAT_SRC := $(wildcard seat/*.c)
WALL_CXX := $(wildcard wall/*.cpp)
INPUT_SRC := $(wildcard input/*.c)
# the remote view (remote/README.md): HTTP + WebSocket server, the page, JPEG frames, remote input
REMOTE_SRC := $(wildcard remote/*.c)
# a wall of several machines (cluster/cluster.h): OpenMPI, the frame and display syncs
CLUSTER_SRC := $(wildcard cluster/*.c)
METRICS_SRC := $(wildcard metrics/*.c)
# the hard cases of numerical robustness, shared by tests/test_robust.c and `tessera robust`
ROBUST_SRC := $(wildcard tools/robust/*.c)
CLI_SRC := $(wildcard app/*.c)
# tools/gen_assembly/README.md: the assembly generator, a program of its own (libm only)
GEN_ASSEMBLY_SRC := $(wildcard tools/gen_assembly/*.c)
# the tile counter's cost per tile at many thread counts (tools/scaling_model.sh)
TILE_CONTENTION_SRC := tools/scaling/tile_contention.c
TEST_SRC := $(wildcard tests/*.c)

# traversal kernels: one source compiled per instruction set, picked at run time
# (engine/accel/kernels.c); no FMA anywhere, so every ISA gives bit-identical results
ISA_OBJ := $(BUILD)/engine/accel/isa/traverse_sse2.o $(BUILD)/engine/accel/isa/traverse_avx2.o \
           $(BUILD)/engine/accel/isa/traverse_avx512.o
ISA_FLAGS_sse2 := -DTESS_ISA_SSE2
ISA_FLAGS_avx2 := -DTESS_ISA_AVX2 -mavx2 -mno-fma
ISA_FLAGS_avx512 := -DTESS_ISA_AVX512 -mavx512f -mavx512vl -mavx512dq -mavx512bw -mno-fma

LIB_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(ENGINE_SRC) $(WALL_SRC) $(SEAT_SRC) $(INPUT_SRC) $(REMOTE_SRC) $(CLUSTER_SRC) $(METRICS_SRC) $(ROBUST_SRC)) \
           $(ISA_OBJ) $(BUILD)/remote/page_html.o $(BUILD)/wall/dump_module_blob.o
CLI_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(CLI_SRC))
GEN_ASSEMBLY_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(GEN_ASSEMBLY_SRC))
TILE_CONTENTION_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(TILE_CONTENTION_SRC))
TEST_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(TEST_SRC))
LIB := $(BUILD)/libtessera.a
TEST_BIN := $(BUILD)/tessera_tests

.PHONY: all deps run test test-unit test-isa-caps test-asan test-fault test-tsan bench bench-remote bench-cluster bench-ao bench-particles bench-parts report-volumes report-remote bench-pipeline bench-wall scaling-model clean check-headers unrobust \
        gen-assembly ply-replicate bench-massive bench-sbvh

all: tessera

deps:
	@sh tools/deps.sh

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/engine/accel/isa/traverse_%.o: engine/accel/isa/traverse.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) $(ISA_FLAGS_$*) -MMD -MP -c $< -o $@

# the remote view's page built into the binary (remote/page.h)
$(BUILD)/gen/remote/page_html.c: remote/page.html tools/embed_page.sh
	@mkdir -p $(dir $@)
	sh tools/embed_page.sh remote/page.html $@
$(BUILD)/remote/page_html.o: $(BUILD)/gen/remote/page_html.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -MMD -MP -c $< -o $@

# the image module (wall/dump_module.h): dump_oiio.cpp with its own copies of err.c and
# srgb8.c, position-independent, every symbol hidden but its entry; embedded in libtessera.a
# by dump_module_blob.S (so each tree's executables carry their own tree's module)
IMAGE_MODULE := $(BUILD)/wall/dump_oiio.so
IMAGE_MODULE_OBJ := $(patsubst %.cpp,$(BUILD)/pic/%.o,$(WALL_CXX)) $(BUILD)/pic/engine/base/err.o $(BUILD)/pic/engine/base/srgb8.o
$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@
$(BUILD)/pic/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(CPPFLAGS) $(CXXFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@
# (-z defs: every symbol resolved at link time; not under a sanitizer, whose runtime the
# executable brings)
$(IMAGE_MODULE): $(IMAGE_MODULE_OBJ)
	$(CXX) -shared $(LDFLAGS) -pthread $(SAN) $(if $(SAN),,-Wl,-z,defs) -o $@ $^ $(IMAGE_LDLIBS) -lm
$(BUILD)/wall/dump_module_blob.o: wall/dump_module_blob.S $(IMAGE_MODULE)
	@mkdir -p $(dir $@)
	$(CC) -DTESS_DUMP_MODULE_FILE='"$(IMAGE_MODULE)"' -c $< -o $@

$(LIB): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

tessera: $(CLI_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)

# the CAD-like assembly generator (tools/gen_assembly/README.md); the suite runs it
$(BUILD)/gen-assembly: $(GEN_ASSEMBLY_OBJ)
	$(CC) $(LDFLAGS) $(SAN) -o $@ $(GEN_ASSEMBLY_OBJ) -lm
gen-assembly: $(BUILD)/gen-assembly

# a mesh copied onto a grid as one binary PLY (tools/ply_replicate/ply_replicate.c: mesh_load, so it
# links the engine); make bench-massive makes the replicated CT bunny with it, the suite tests it
PLY_REPLICATE := $(BUILD)/ply-replicate
$(PLY_REPLICATE): $(BUILD)/tools/ply_replicate/ply_replicate.o $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(BUILD)/tools/ply_replicate/ply_replicate.o $(LIB) $(LDLIBS)
ply-replicate: $(PLY_REPLICATE)
# the dynamic load balancer's tile counter under N threads (tools/scaling/tile_contention.c)
$(BUILD)/tile-contention: $(TILE_CONTENTION_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(TILE_CONTENTION_OBJ) $(LIB) $(LDLIBS)

# the fast, non-robust kernels (engine/accel/intersect.h: TESSERA_UNROBUST) for the report's robustness
# knob: their own tree build-unrobust/ and binary build-unrobust/tessera; never ./tessera
unrobust:
	$(MAKE) BUILD=build-unrobust UNROBUST=1 build-unrobust/tessera
ifeq ($(UNROBUST),1)
$(BUILD)/tessera: $(CLI_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)
endif

# (the suite runs ./tessera too: `make test` builds it; the ASan build makes its own tessera-asan
# and must never overwrite ./tessera)
# the tests also link the CLI but its main (as the soak driver does): the input pick hook
# (app/input_pick.h: a scene's parts as input sees them) and the pipeline config parser
# (tests/test_pipeline_config.c reads back what a config sets)
TEST_CLI_OBJ := $(filter-out $(BUILD)/app/main.o,$(CLI_OBJ))
$(TEST_BIN): $(TEST_OBJ) $(TEST_CLI_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(TEST_OBJ) $(TEST_CLI_OBJ) $(LIB) $(LDLIBS) $(TEST_LDLIBS)

# fault injection (tests/fault/, docs/tests.md): a Criterion binary of its own whose link
# routes every allocation call in our objects (engine, wall, input, the CLI but main.o, the
# tests) through tests/fault/fault_alloc.c, so the n-th allocation of one operation can be
# made to fail, and their pwrite/close through fault_io.c (EIO on demand); the libraries'
# own calls are untouched
FAULT_SRC := $(wildcard tests/fault/*.c)
FAULT_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(FAULT_SRC))
FAULT_BIN := $(BUILD)/tessera_fault_tests
FAULT_WRAP := -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=aligned_alloc,--wrap=posix_memalign \
              -Wl,--wrap=strdup,--wrap=strndup,--wrap=getline,--wrap=open_memstream,--wrap=fopen \
              -Wl,--wrap=pwrite,--wrap=close
$(FAULT_BIN): $(FAULT_OBJ) $(filter-out $(BUILD)/app/main.o,$(CLI_OBJ)) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) $(FAULT_WRAP) -o $@ $^ $(LDLIBS) $(TEST_LDLIBS)

# the fault tests alone, without sanitizers (make test-asan runs them with LeakSanitizer)
test-fault:
	$(MAKE) $(FAULT_BIN)
	cd tests && ../$(FAULT_BIN) --jobs 2

# the main job on the built-in default scene (headless: frames to out/)
run: deps
	$(MAKE) tessera
	./tessera run

# the whole suite (Criterion prints its summary line), then the DRM/KMS wall end to end in a
# qemu guest (tests/vm_wall.sh), input driving it there (tests/vm_input.sh) and a wall of two
# machines on two cards under mpirun there (tests/vm_cluster.sh): each its own summary line;
# SKIPPED, said so, when qemu cannot be installed
# (.ci/run runs these same parts one by one, to time each: keep it in step)
test:
	$(MAKE) test-unit
	sh tests/vm_wall.sh
	sh tests/vm_input.sh
	sh tests/vm_cluster.sh

# the unit suite alone (what make test runs before the VM tests)
test-unit:
	@sh tools/deps.sh --test
	$(MAKE) $(TEST_BIN) tessera $(BUILD)/gen-assembly $(PLY_REPLICATE) check-headers check-layers
	cd tests && ../$(TEST_BIN) --jobs 2

# the kernel, robustness and image tests again as a CPU with only AVX2, then only SSE2, would
# run them (TESSERA_ISA_MAX, engine/accel/kernels.h): so the paths of a machine without AVX-512 (or
# AVX2) run on every submission, whatever CPU CI has. An ISA skipped is said on a SKIPPED line.
ISA_CAPS := avx2 sse2
ISA_CAP_TESTS := @(kernels|next_hit|iso_kind|robust|render|wall_render)/*
test-isa-caps:
	$(MAKE) $(TEST_BIN) tessera
	cd tests && for cap in $(ISA_CAPS); do \
	    echo "test-isa-caps: TESSERA_ISA_MAX=$$cap"; \
	    TESSERA_ISA_MAX=$$cap ../$(TEST_BIN) --filter '$(ISA_CAP_TESTS)' --jobs 2 || exit 1; \
	done

# the suite again under AddressSanitizer + UBSan, in its own build tree (the image module
# loaded from its file, so that a report inside it names its lines: wall/dump_module.h)
test-asan:
	@sh tools/deps.sh --test
	$(MAKE) BUILD=build-asan OPT=-O1 SAN="-fsanitize=address,undefined -fno-omit-frame-pointer" \
	    build-asan/tessera_tests tessera-asan build-asan/tessera_fault_tests build-asan/gen-assembly \
	    build-asan/ply-replicate
	cd tests && TESSERA_BIN=../tessera-asan TESSERA_GEN_ASSEMBLY=../build-asan/gen-assembly \
	    TESSERA_IMAGE_MODULE=$(CURDIR)/build-asan/wall/dump_oiio.so \
	    TESSERA_PLY_REPLICATE=../build-asan/ply-replicate ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0 LSAN_OPTIONS=suppressions=lsan.supp ../build-asan/tessera_tests --jobs 2
	cd tests && TESSERA_IMAGE_MODULE=$(CURDIR)/build-asan/wall/dump_oiio.so \
	    ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0 LSAN_OPTIONS=suppressions=lsan.supp ../build-asan/tessera_fault_tests --jobs 2

# the threaded tests under ThreadSanitizer; any report fails the run. Criterion
# cannot start under TSan (its issue #274), so these files are compiled against
# tests/tsan/criterion/criterion.h, a stand-in that runs the same Test() bodies.
TSAN_TESTS := tests/test_pipeline.c tests/test_overlay.c tests/test_input.c tests/test_governor.c \
              tests/test_frame_state.c tests/test_volume_series.c
TSAN_BIN := build-tsan/tessera_tsan_tests
# (both TSan binaries in one make, so that make -j builds the CLI's objects beside the rest)
test-tsan: deps
	$(MAKE) BUILD=build-tsan OPT=-O1 SAN="-fsanitize=thread" $(TSAN_BIN) tessera-tsan
	cd tests && TSAN_OPTIONS="halt_on_error=1 exitcode=66 second_deadlock_stack=1" ../$(TSAN_BIN)
	$(MAKE) $(TEST_BIN)
	cd tests && TESSERA_BIN=../tessera-tsan \
	    TSAN_OPTIONS="halt_on_error=1 exitcode=66 suppressions=$(CURDIR)/tests/tsan_mpi.supp" \
	    ../$(TEST_BIN) --filter 'cluster/*'

build-tsan/tessera_tsan_tests: $(TSAN_TESTS) $(LIB)
	$(CC) -Itests/tsan $(CPPFLAGS) $(CFLAGS) -o $@ $(TSAN_TESTS) $(LIB) $(LDLIBS) -lstdc++

tessera-asan: $(CLI_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)

# the binary under ThreadSanitizer, for what runs as processes (make test-tsan: the cluster's
# mpirun runs, tests/test_cluster.c with TESSERA_BIN=../tessera-tsan)
tessera-tsan: $(CLI_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)

# the soak (tests/soak.sh, docs/tests.md): the kiosk (run --wall, headless) under random
# transactions from several threads for SOAK_S seconds (default 3600), RSS, descriptors,
# frame gaps and transaction counts checked. SOAK_SAN=1: under ASan + UBSan in its own tree
# (build-soak-asan/; never build/ or ./tessera). SOAK_SEED, SOAK_THREADS (<= 2 here), SOAK_DIR.
.PHONY: soak clean-soak
SOAK_DRIVER_OBJ := $(filter-out $(BUILD)/app/main.o,$(CLI_OBJ)) $(BUILD)/tests/soak/soak_driver.o
$(BUILD)/soak_driver: $(SOAK_DRIVER_OBJ) $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(SOAK_DRIVER_OBJ) $(LIB) $(LDLIBS)
# tools/flip_check/check.sh: image pairs for checking tessera compare against NVlabs' FLIP
$(BUILD)/flip_pairs: $(BUILD)/tools/flip_check/pairs.o $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(BUILD)/tools/flip_check/pairs.o $(LIB) $(LDLIBS)
SOAK_SAN ?= 0
soak:
ifeq ($(SOAK_SAN),1)
	$(MAKE) BUILD=build-soak-asan OPT=-O1 SAN="-fsanitize=address,undefined -fno-omit-frame-pointer" \
	    build-soak-asan/soak_driver
	SOAK_DRIVER=build-soak-asan/soak_driver SOAK_SAN=1 sh tests/soak.sh
else
	$(MAKE) $(BUILD)/soak_driver
	SOAK_DRIVER=$(BUILD)/soak_driver sh tests/soak.sh
endif
clean: clean-soak
clean-soak:
	rm -rf build-soak-asan

# libFuzzer on every parser (tests/fuzz/README.md): clang with ASan + UBSan in its own tree
# build-fuzz/ (tests/fuzz/fuzz.mk, with this file's CPPFLAGS, LDLIBS and WARN), then each
# target for FUZZ_S seconds (default 60) alone; any crash, leak, hang > 1 s or OOM > 2 GiB
# fails. FUZZ_TARGETS="ply obj" picks targets. fuzz-smoke (3 s a target) is what CI runs.
# fuzz-build-tree runs in a make of its own, started after deps.sh: this make's pkg-config
# flags were read before deps.sh installed the packages, and on a fresh machine are empty.
.PHONY: fuzz fuzz-build fuzz-build-tree fuzz-smoke clean-fuzz
FUZZ_S ?= 60
FUZZ_TARGETS ?=
fuzz-build:
	@sh tools/deps.sh --fuzz
	$(MAKE) fuzz-build-tree
fuzz-build-tree:
	$(MAKE) -f tests/fuzz/fuzz.mk CPPFLAGS='$(CPPFLAGS)' LDLIBS='$(LDLIBS)' IMAGE_LDLIBS='$(IMAGE_LDLIBS)' WARN='$(WARN)'
fuzz: fuzz-build
	sh tests/fuzz/run.sh $(FUZZ_S) $(FUZZ_TARGETS)
fuzz-smoke:
	$(MAKE) fuzz FUZZ_S=3
clean: clean-fuzz
clean-fuzz:
	rm -rf build-fuzz

# the rooms of the tree and the uses each may make of the others (docs/layers.md): every
# include, then every call between our objects (a low room's header cannot hide a call up)
.PHONY: check-layers
check-layers: $(LIB_OBJ) $(CLI_OBJ)
	sh tools/check_layers.sh
	sh tools/check_layers.sh --objects $(filter %.o,$(LIB_OBJ) $(CLI_OBJ))
	@echo "check-layers: every include and every call goes down the layers"

# every header compiles on its own
HEADERS := $(sort $(filter-out engine/accel/isa/%,$(shell find engine -name '*.h'))) $(wildcard wall/*.h seat/*.h input/*.h remote/*.h cluster/*.h metrics/*.h app/*.h tools/robust/*.h tools/gen_assembly/*.h)
# isa/simd.h needs an ISA macro: it is checked by compiling the kernels
# (one target a header, so that make -j checks them side by side)
HEADER_CHECKS := $(addprefix check-header/,$(HEADERS))
.PHONY: $(HEADER_CHECKS)
check-headers: $(HEADER_CHECKS)
$(HEADER_CHECKS): check-header/%:
	@echo '#include "$*"' | $(CC) $(CPPFLAGS) -std=c11 $(WARN) -x c -fsyntax-only -

bench:
	@sh tools/deps.sh --bench
	$(MAKE) tessera $(BUILD)/gen-assembly $(EMBREE_PARTS)
	sh tools/bench.sh
	sh tools/bench_wall.sh
	sh tools/bench_pipeline.sh
	sh tools/bench_parts.sh
	sh tools/bench_ao.sh
	sh tools/bench_particles.sh

# Embree's two-level scene on an assembly (tools/embree_parts/embree_parts.c): built only for the
# benchmarks (it needs libembree-dev: tools/deps.sh --bench), never by make or make test
EMBREE_PARTS := $(BUILD)/embree_parts
$(EMBREE_PARTS): $(BUILD)/tools/embree_parts/embree_parts.o $(LIB)
	$(CXX) $(LDFLAGS) -pthread -o $@ $(BUILD)/tools/embree_parts/embree_parts.o $(LIB) $(LDLIBS) -lembree3

# parts and instances alone (tools/bench_parts.sh): the "## Parts and instances" section of BENCHMARKS.md
bench-parts:
	@sh tools/deps.sh --bench
	$(MAKE) tessera $(BUILD)/gen-assembly $(EMBREE_PARTS)
	sh tools/bench_parts.sh

# one mesh of 100 M triangles (tools/bench_massive.sh): the flattened assembly and the replicated CT
# bunny, load, build, peak memory and frame rate against Embree; the "## Massive models" section of
# BENCHMARKS.md. Not part of make bench (about 20 minutes and 15 GB of memory); BENCH_MASSIVE_TRIANGLES
# sets the scale (default 100000000)
bench-massive:
	@sh tools/deps.sh --bench
	$(MAKE) tessera $(BUILD)/gen-assembly $(PLY_REPLICATE) $(EMBREE_PARTS)
	sh tools/bench_massive.sh

# spatial splits' gain and cost (tools/bench_sbvh.sh): the "## Spatial splits" section of
# BENCHMARKS.md; not part of make bench
bench-sbvh:
	$(MAKE) tessera $(BUILD)/gen-assembly
	sh tools/bench_sbvh.sh

# ambient occlusion against Embree's AO rays alone (tools/bench_ao.sh): the "## Ambient occlusion"
# section of BENCHMARKS.md
bench-ao:
	@sh tools/deps.sh --bench
	$(MAKE) tessera
	sh tools/bench_ao.sh

# volumes' speed against error (tools/report_volumes.sh): the "## Volumes" section of REPORT.md
report-volumes:
	$(MAKE) tessera
	sh tools/report_volumes.sh

# the remote view's latency, frames per second and bytes a frame in headless Chromium
# (tools/bench_remote.sh): the "## Remote view" section of BENCHMARKS.md. The harness shares the
# browser tests' DevTools client (tests/cdp.c)
$(BUILD)/bench-remote: $(BUILD)/tools/bench_remote/bench_remote.o $(BUILD)/tests/cdp.o
	$(CC) $(LDFLAGS) $(SAN) -o $@ $^ $(shell pkg-config --libs json-c) -lm
bench-remote:
	@sh tools/deps.sh --test
	$(MAKE) tessera $(BUILD)/bench-remote
	sh tools/bench_remote.sh

# a wall of several processes on this machine (cluster/): BENCHMARKS.md "## Cluster"
bench-cluster: deps
	$(MAKE) tessera
	sh tools/bench_cluster.sh

# the remote view's JPEG frames (tools/report_remote.sh): bytes and encode time against FLIP per
# quality and chroma subsampling, the "## Remote view" section of REPORT.md
report-remote:
	@sh tools/deps.sh --report
	$(MAKE) tessera $(BUILD)/report_img
	sh tools/report_remote.sh

# particles against Embree's sphere points alone (tools/bench_particles.sh): the "## Particles"
# section of BENCHMARKS.md
bench-particles:
	@sh tools/deps.sh --bench
	$(MAKE) tessera
	sh tools/bench_particles.sh

# the wall benchmarks alone (bench --wall): the "## Wall" section of BENCHMARKS.md
bench-wall: deps
	$(MAKE) tessera
	sh tools/bench_wall.sh

# the pipeline benchmarks alone (scaling, camera transactions): the last section of BENCHMARKS.md
bench-pipeline: deps
	$(MAKE) tessera
	sh tools/bench_pipeline.sh

# the scaling model (BENCHMARKS.md "Scaling past this machine"): needs valgrind
scaling-model: deps
	$(MAKE) tessera $(BUILD)/tile-contention
	sh tools/scaling_model.sh

# the speed-against-error report (docs/report.md): REPORT.md and
# report/*.png from tools/report/report.sh, one section per quality knob (tools/report/knob_*.sh);
# REPORT_SIZE, REPORT_RUNS, REPORT_FRAMES, REPORT_THREADS tune it. report_img averages renders
# into the reference and cuts the crops.
.PHONY: report
$(BUILD)/report_img: $(BUILD)/tools/report/report_img.o $(LIB)
	$(CXX) $(LDFLAGS) -pthread $(SAN) -o $@ $(BUILD)/tools/report/report_img.o $(LIB) $(LDLIBS)
report:
	@sh tools/deps.sh --report
	$(MAKE) tessera $(BUILD)/report_img $(BUILD)/gen-assembly unrobust
	sh tools/report/report.sh

clean:
	rm -rf build build-asan build-tsan build-unrobust tessera tessera-asan tessera-tsan out

# dependency files are only read, never remade (else make's built-in rules try)
%.d: ;
-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
