# lsmorph — level-set metamorphosis between sparse slices.
#
#   make            build build/lsmorph (installs missing Debian packages first)
#   make demo       reconstruct a bundled example and say where the output is
#   make test       build and run the whole test suite
#   make bench      speed and memory benchmarks
#   make validate   validation report (validation/report/REPORT.md)
#
# Options: WERROR=1 (warnings are errors; CI sets it), NATIVE=1 (-march=native),
#          MPI=1 (Open MPI build into build-mpi/: mpirun -np N build-mpi/lsmorph ...),
#          DEBUG=1 (-O0 -g), SANITIZE=1 (AddressSanitizer + UndefinedBehaviorSanitizer,
#          built into build-san/ unless BUILD is given: make test SANITIZE=1).
#   make fuzz       libFuzzer harnesses (clang) for the PNG reader, the heights parser
#                   and the command line, FUZZ_SECONDS (default 60) each

CC      ?= cc
ifeq ($(SANITIZE),1)
BUILD   ?= build-san
endif
# MPI=1: Open MPI build (mpicc) into build-mpi/, gaps spread over ranks by
# `mpirun -np N build-mpi/lsmorph reconstruct ...`.
ifeq ($(MPI),1)
BUILD   ?= build-mpi
CC      := mpicc
endif
BUILD   ?= build
# one spelling per folder: a BUILD given as an absolute path inside the tree (the test
# scripts pass one to `make install`) is made relative, so that the objects' dependency files
# name the targets the way every other make does (else a header change was missed after it)
override BUILD := $(patsubst $(CURDIR)/%,%,$(BUILD))
PREFIX  ?= /usr/local

WARN    := -Wall -Wextra -Wpedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes
ifeq ($(WERROR),1)
WARN    += -Werror
endif
OPT     := -O3 -fno-math-errno -fno-trapping-math
ifeq ($(DEBUG),1)
OPT     := -O0 -g
endif
ifeq ($(NATIVE),1)
OPT     += -march=native
endif
# Sanitizers: -g for symbolised reports; UB aborts (a report must fail the test).
# float-cast-overflow (a double too large for its integer type: undefined in C)
# is not part of GCC's "undefined" set.
ifeq ($(SANITIZE),1)
OPT     += -g -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all \
           -fno-omit-frame-pointer
endif
CFLAGS  ?=
CFLAGS  += -std=c17 $(WARN) $(OPT) -fopenmp -D_POSIX_C_SOURCE=200809L -I. -MMD -MP
# nifticlib's headers include each other by bare name from /usr/include/nifti
CFLAGS  += -I/usr/include/nifti
# every library object also goes into liblsmorph.so, which exports lsmorph.h's
# functions only; not for tests (test_tiff_changing interposes libc's read())
OBJ_CFLAGS := -fPIC -fvisibility=hidden
ifeq ($(MPI),1)
CFLAGS  += -DLSM_WITH_MPI
endif
LDLIBS  += -lpng -ltiff -lz -lm -lOpenEXRCore -fopenmp -lOpenCL -lnifti2 -lteem

DEBIAN_PACKAGES := gcc make pkg-config libpng-dev libtiff-dev zlib1g-dev libcmocka-dev libnifti2-dev libteem-dev python3 python3-numpy python3-pil python3-matplotlib libopenexr-dev python3-vtk9 python3-nibabel openimageio-tools \
                   ocl-icd-opencl-dev opencl-headers pocl-opencl-icd libopenmpi-dev openmpi-bin
DEPS_STAMP := $(BUILD)/.deps-ok
# Only for validation/end_offsets.py's plain-spline references (make validate).
VALIDATE_PACKAGES := python3-scipy

# The library: every room's sources but the program's main (solver/app/lsmorph.c).
APP_MAIN := solver/app/lsmorph.c
LIB_SRC := $(filter-out $(APP_MAIN),$(wildcard solver/*/*.c) $(wildcard io/*.c) $(wildcard kernels/opencl/*.c))
LIB_OBJ := $(patsubst %.c,$(BUILD)/obj/%.o,$(LIB_SRC))
APP_OBJ := $(patsubst %.c,$(BUILD)/obj/%.o,$(APP_MAIN))
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
EXAMPLE_SRC := $(wildcard examples/*.c)
EXAMPLE_BIN := $(patsubst examples/%.c,$(BUILD)/examples/%,$(EXAMPLE_SRC))
VALIDATION_SRC := $(wildcard validation/*.c)
VALIDATION_BIN := $(patsubst validation/%.c,$(BUILD)/validation/%,$(VALIDATION_SRC))
FUZZ_NAMES := png tiff heights cli labels
REPLAY_BIN := $(patsubst %,$(BUILD)/fuzz-replay/replay_%,$(FUZZ_NAMES))
FUZZ_CC ?= clang
FUZZ_PACKAGES := clang libclang-rt-14-dev libomp-dev
FUZZ_DEPS_STAMP := $(BUILD)/.fuzz-deps-ok
FUZZ_SECONDS ?= 60
FUZZ_CFLAGS := -std=c17 -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined \
               -fno-sanitize-recover=undefined -fopenmp -D_POSIX_C_SOURCE=200809L -I. -MMD -MP \
               -I/usr/include/nifti
FUZZ_OBJ := $(patsubst %.c,$(BUILD)/fuzz/obj/%.o,$(LIB_SRC))
FUZZ_BIN := $(patsubst %,$(BUILD)/fuzz/fuzz_%,$(FUZZ_NAMES))

.PHONY: all deps demo test bench validate install clean fuzz fuzz-build
all: $(BUILD)/lsmorph $(EXAMPLE_BIN) $(BUILD)/liblsmorph.so $(BUILD)/python/lsmorph/__init__.py

# Install missing Debian packages once per build folder (apt-get; sudo when not root).
deps: $(DEPS_STAMP)
$(DEPS_STAMP):
	@sh tests/install-deps.sh $(DEBIAN_PACKAGES)
	@mkdir -p $(BUILD) && touch $@

# Objects are rebuilt when the compiler or its flags change (-fPIC came in with
# liblsmorph.so): a stamp holds them and is rewritten only when they differ.
FLAGS_STAMP := $(BUILD)/.cflags
$(shell mkdir -p $(BUILD) && echo '$(CC) $(CFLAGS) $(OBJ_CFLAGS)' | cmp -s - $(FLAGS_STAMP) || \
  echo '$(CC) $(CFLAGS) $(OBJ_CFLAGS)' > $(FLAGS_STAMP))
$(BUILD)/obj/%.o: %.c $(FLAGS_STAMP) | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(OBJ_CFLAGS) -c $< -o $@

# OpenCL kernels embedded in the binary: kernels/morph.cl then kernels/motion.cl, with
# the kernels/lsm_*.h headers they include spliced in at their #includes (the headers'
# own #include of lsm_cell.h dropped: it is already there; a header spliced twice is
# kept out by its guard), as a C byte array (a string literal would pass -Wpedantic's
# 4095-character limit), NUL-terminated.
KERNEL_CL := kernels/morph.cl kernels/motion.cl
KERNEL_GEN := $(BUILD)/gen/lsm_kernels.h
$(KERNEL_GEN): $(KERNEL_CL) $(wildcard kernels/lsm_*.h)
	@mkdir -p $(dir $@)
	@{ echo '/* Generated from kernels/morph.cl, motion.cl + kernels/lsm_*.h by the Makefile: do not edit. */'; \
	  echo 'static const unsigned char lsm_kernel_source[] = {'; \
	  awk 'FNR == 1 { cl = FILENAME; sub(/^kernels\//, "", cl); print "#line 1 \"" cl "\"" } \
	       /^#include "lsm_[a-z_]+\.h"/ { f = $$2; gsub(/"/, "", f); n = 0; \
	         while ((getline l < ("kernels/" f)) > 0) { n++; \
	           if (l ~ /^#include "kernels\/lsm_cell.h"/) l = ""; \
	           if (n == 1) print "#line 1 \"" f "\""; print l } \
	         close("kernels/" f); \
	         print "#line " (FNR + 1) " \"" cl "\""; next } { print }' $(KERNEL_CL) \
	    | od -An -v -tx1 | sed 's/^ *//; s/ *$$//; s/  */,0x/g; s/^/0x/; s/$$/,/'; \
	  echo '0x00};'; } > $@.tmp && mv $@.tmp $@
$(BUILD)/obj/kernels/opencl/lsm_cl_context.o $(BUILD)/fuzz/obj/kernels/opencl/lsm_cl_context.o: $(KERNEL_GEN)
$(BUILD)/obj/kernels/opencl/lsm_cl_context.o: CFLAGS += -I$(BUILD)/gen
$(BUILD)/fuzz/obj/kernels/opencl/lsm_cl_context.o: FUZZ_CFLAGS += -I$(BUILD)/gen

$(BUILD)/liblsmorph.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

# liblsmorph: the static archive above, and a shared library of the same objects
# exporting lsmorph.h (solver/api); make install adds its pkg-config file for PREFIX.
SONAME := liblsmorph.so.0
$(BUILD)/liblsmorph.so: $(LIB_OBJ)
	$(CC) $(CFLAGS) -shared -Wl,-soname,$(SONAME) $^ -o $@ $(LDLIBS)

# The Python package over the shared library (ctypes): build/python/lsmorph is importable
# (PYTHONPATH=build/python), with its own copy of liblsmorph.so.
$(BUILD)/python/lsmorph/__init__.py: solver/api/python/lsmorph/__init__.py $(BUILD)/liblsmorph.so
	@mkdir -p $(dir $@)
	cp $(BUILD)/liblsmorph.so $(dir $@)liblsmorph.so
	cp $< $@

$(BUILD)/lsmorph: $(APP_OBJ) $(BUILD)/liblsmorph.a
	$(CC) $(CFLAGS) $^ -o $@ $(LDLIBS)

$(BUILD)/examples/%: examples/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

$(BUILD)/validation/%: validation/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

$(BUILD)/tests/%: tests/%.c $(wildcard tests/lsm_test*.h) $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS) -lcmocka

demo: all
	@sh examples/demo.sh $(BUILD)

test: all $(TEST_BIN) $(REPLAY_BIN)
	@sh tests/run-tests.sh $(BUILD)

# Fuzz harnesses replayed on their corpora (tests/test_fuzz_corpus.sh), built
# with $(CC) and a small main() so make test needs no clang.
$(BUILD)/fuzz-replay/replay_%: tests/fuzz/fuzz_%.c tests/fuzz/replay.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) tests/fuzz/replay.c $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

# libFuzzer: the library and each harness built with clang, ASan and UBSan into
# $(BUILD)/fuzz/; each harness then runs FUZZ_SECONDS on a copy of its seed corpus.
fuzz-build: $(FUZZ_BIN)
fuzz: $(FUZZ_BIN)
	@sh tests/fuzz/run.sh $(BUILD) $(FUZZ_SECONDS) $(FUZZ_NAMES)

$(FUZZ_DEPS_STAMP): | $(DEPS_STAMP)
	@sh tests/install-deps.sh $(FUZZ_PACKAGES)
	@touch $@

$(BUILD)/fuzz/obj/%.o: %.c | $(FUZZ_DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -fsanitize=fuzzer-no-link -c $< -o $@

$(BUILD)/fuzz/liblsmorph.a: $(FUZZ_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/fuzz/fuzz_%: tests/fuzz/fuzz_%.c $(BUILD)/fuzz/liblsmorph.a
	$(FUZZ_CC) $(FUZZ_CFLAGS) -fsanitize=fuzzer $< $(BUILD)/fuzz/liblsmorph.a -o $@ $(LDLIBS)

bench: all $(BUILD)/bench/bench_scheme $(BUILD)/bench/bench_opencl $(BUILD)/bench/bench_morph
	@sh tests/bench.sh $(BUILD)

$(BUILD)/bench/%: tests/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

validate: all $(VALIDATION_BIN)
	@sh tests/install-deps.sh $(VALIDATE_PACKAGES)
	@sh validation/run.sh $(BUILD)

# The system Python 3's folder for packages under PREFIX, as Debian's python3 reads it
# (/usr/local/lib/python3.X/dist-packages is on its path).
PYTHON_SITE ?= $(shell /usr/bin/python3 -c "import sys; print('$(PREFIX)/lib/python%d.%d/dist-packages' % sys.version_info[:2])")
install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include
	install -m 755 $(BUILD)/lsmorph $(DESTDIR)$(PREFIX)/bin/lsmorph
	install -m 644 $(BUILD)/liblsmorph.a $(DESTDIR)$(PREFIX)/lib/liblsmorph.a
	install -m 755 $(BUILD)/liblsmorph.so $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/liblsmorph.so
	install -m 644 solver/api/lsmorph.h $(DESTDIR)$(PREFIX)/include/lsmorph.h
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	  'Name: lsmorph' 'Description: fill the gaps between sparse slices by level-set metamorphosis' \
	  'Version: $(shell sed -n "s/^#define LSMORPH_VERSION \"\(.*\)\"/\1/p" solver/api/lsmorph.h)' \
	  'Libs: -L$${libdir} -llsmorph' 'Libs.private: $(LDLIBS)' 'Cflags: -I$${includedir}' \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/lsmorph.pc
	install -d $(DESTDIR)$(PYTHON_SITE)/lsmorph
	install -m 644 solver/api/python/lsmorph/__init__.py $(DESTDIR)$(PYTHON_SITE)/lsmorph/__init__.py
	printf 'LIBRARY = "%s"\n' '$(PREFIX)/lib/$(SONAME)' > $(DESTDIR)$(PYTHON_SITE)/lsmorph/_installed.py
	-ldconfig 2>/dev/null

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
-include $(shell find $(BUILD)/fuzz/obj -name '*.d' 2>/dev/null)
