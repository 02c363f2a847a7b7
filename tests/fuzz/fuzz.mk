# fuzz.mk - the libFuzzer build (tests/fuzz/README.md), run by `make fuzz` as
#   $(MAKE) -f tests/fuzz/fuzz.mk CPPFLAGS='...' LDLIBS='...' IMAGE_LDLIBS='...' WARN='...'
# from the top directory, with the Makefile's CPPFLAGS (pkg-config), LDLIBS
# and WARN, so the fuzzed code is compiled as the product is, by clang with
# libFuzzer, ASan and UBSan (every report fatal), in its own tree build-fuzz/.

FZ := build-fuzz
FZ_CC := clang
FZ_CXX := clang++
FZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
FZ_CFLAGS := -std=c11 -O1 -g $(WARN) -Werror -ffp-contract=off -fno-math-errno -pthread $(FZ_SAN) \
             -fsanitize=fuzzer-no-link
FZ_CXXFLAGS := -std=c++17 -O1 -g -Wall -Wextra -Werror -pthread $(FZ_SAN) -fsanitize=fuzzer-no-link

# one target per input format: tests/fuzz/fuzz_NAME.c
FZ_TARGETS := $(patsubst tests/fuzz/fuzz_%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
FZ_BINS := $(addprefix $(FZ)/fuzz_,$(FZ_TARGETS))

# the whole product but main(), as one archive: a target links what it uses
FZ_LIB_C := $(filter-out engine/accel/isa/%,$(shell find engine -name '*.c')) $(wildcard wall/*.c seat/*.c input/*.c remote/*.c cluster/*.c metrics/*.c) $(filter-out app/main.c,$(wildcard app/*.c))
FZ_LIB_OBJ := $(patsubst %.c,$(FZ)/%.o,$(FZ_LIB_C)) $(FZ)/wall/dump_module_blob.o \
              $(FZ)/engine/accel/isa/traverse_sse2.o $(FZ)/engine/accel/isa/traverse_avx2.o $(FZ)/engine/accel/isa/traverse_avx512.o \
              $(FZ)/remote/page_html.o
FZ_LIB := $(FZ)/libtessera_fuzz.a
FZ_ISA_sse2 := -DTESS_ISA_SSE2
FZ_ISA_avx2 := -DTESS_ISA_AVX2 -mavx2 -mno-fma
# (clang's avx512f implies fma, so -mno-fma would turn AVX-512 off again; -ffp-contract=off
# still keeps FMA out, and the fuzz build renders nothing that is compared)
FZ_ISA_avx512 := -DTESS_ISA_AVX512 -mavx512f -mavx512vl -mavx512dq -mavx512bw

.PHONY: all
all: $(FZ_BINS)

$(FZ)/%.o: %.c
	@mkdir -p $(dir $@)
	$(FZ_CC) $(CPPFLAGS) $(FZ_CFLAGS) -MMD -MP -c $< -o $@

$(FZ)/engine/accel/isa/traverse_%.o: engine/accel/isa/traverse.c
	@mkdir -p $(dir $@)
	$(FZ_CC) $(CPPFLAGS) $(FZ_CFLAGS) $(FZ_ISA_$*) -MMD -MP -c $< -o $@

$(FZ)/gen/remote/page_html.c: remote/page.html tools/embed_page.sh
	@mkdir -p $(dir $@)
	sh tools/embed_page.sh remote/page.html $@
$(FZ)/remote/page_html.o: $(FZ)/gen/remote/page_html.c
	@mkdir -p $(dir $@)
	$(FZ_CC) $(CPPFLAGS) $(FZ_CFLAGS) -c $< -o $@

$(FZ)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(FZ_CXX) $(CPPFLAGS) $(FZ_CXXFLAGS) -MMD -MP -c $< -o $@

# the image module (wall/dump_module.h), as the Makefile builds it: dump_oiio.cpp with its own
# err.c and srgb8.c, linked with IMAGE_LDLIBS, embedded by dump_module_blob.S
FZ_MODULE := $(FZ)/wall/dump_oiio.so
$(FZ)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(FZ_CC) $(CPPFLAGS) $(FZ_CFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@
$(FZ)/pic/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(FZ_CXX) $(CPPFLAGS) $(FZ_CXXFLAGS) -fPIC -fvisibility=hidden -MMD -MP -c $< -o $@
$(FZ_MODULE): $(patsubst %.cpp,$(FZ)/pic/%.o,$(wildcard wall/*.cpp)) $(FZ)/pic/engine/base/err.o $(FZ)/pic/engine/base/srgb8.o
	$(FZ_CXX) -shared $(FZ_SAN) -pthread -o $@ $^ $(IMAGE_LDLIBS) -lm
$(FZ)/wall/dump_module_blob.o: wall/dump_module_blob.S $(FZ_MODULE)
	@mkdir -p $(dir $@)
	$(FZ_CC) -DTESS_DUMP_MODULE_FILE='"$(FZ_MODULE)"' -c $< -o $@

$(FZ_LIB): $(FZ_LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(FZ)/fuzz_%: $(FZ)/tests/fuzz/fuzz_%.o $(FZ)/tests/fuzz/fuzz.o $(FZ_LIB)
	$(FZ_CXX) $(FZ_SAN) -fsanitize=fuzzer -pthread -o $@ $< $(FZ)/tests/fuzz/fuzz.o $(FZ_LIB) $(LDLIBS)

%.d: ;
-include $(shell find $(FZ) -name '*.d' 2>/dev/null)
