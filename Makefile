# lsmorph — level-set metamorphosis between sparse slices.
#
#   make            build build/lsmorph (installs missing Debian packages first)
#   make demo       reconstruct a bundled example and say where the output is
#   make test       build and run the whole test suite
#   make bench      speed and memory benchmarks
#   make validate   validation report (validation/report/REPORT.md)
#
# Options: WERROR=1 (warnings are errors; CI sets it), NATIVE=1 (-march=native),
#          DEBUG=1 (-O0 -g).

CC      ?= cc
BUILD   ?= build
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
CFLAGS  ?=
CFLAGS  += -std=c17 $(WARN) $(OPT) -fopenmp -D_POSIX_C_SOURCE=200809L -I. -MMD -MP
LDLIBS  += -lpng -lz -lm -lOpenEXRCore -fopenmp

DEBIAN_PACKAGES := gcc make pkg-config libpng-dev zlib1g-dev libcmocka-dev python3 python3-numpy python3-matplotlib libopenexr-dev python3-vtk9 openimageio-tools
DEPS_STAMP := $(BUILD)/.deps-ok

LIB_SRC := $(wildcard solver/lsm_*.c) $(wildcard io/*.c) $(wildcard kernels/*.c)
LIB_OBJ := $(patsubst %.c,$(BUILD)/obj/%.o,$(LIB_SRC))
APP_OBJ := $(BUILD)/obj/solver/lsmorph.o
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
EXAMPLE_SRC := $(wildcard examples/*.c)
EXAMPLE_BIN := $(patsubst examples/%.c,$(BUILD)/examples/%,$(EXAMPLE_SRC))
VALIDATION_SRC := $(wildcard validation/*.c)
VALIDATION_BIN := $(patsubst validation/%.c,$(BUILD)/validation/%,$(VALIDATION_SRC))

.PHONY: all deps demo test bench validate install clean
all: $(BUILD)/lsmorph $(EXAMPLE_BIN)

# Install missing Debian packages once per build folder (apt-get; sudo when not root).
deps: $(DEPS_STAMP)
$(DEPS_STAMP):
	@sh tests/install-deps.sh $(DEBIAN_PACKAGES)
	@mkdir -p $(BUILD) && touch $@

$(BUILD)/obj/%.o: %.c | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -c $< -o $@

$(BUILD)/liblsmorph.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/lsmorph: $(APP_OBJ) $(BUILD)/liblsmorph.a
	$(CC) $(CFLAGS) $^ -o $@ $(LDLIBS)

$(BUILD)/examples/%: examples/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

$(BUILD)/validation/%: validation/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

$(BUILD)/tests/%: tests/%.c tests/lsm_test.h $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS) -lcmocka

demo: all
	@sh examples/demo.sh $(BUILD)

test: all $(TEST_BIN)
	@sh tests/run-tests.sh $(BUILD)

bench: all $(BUILD)/bench/bench_scheme
	@sh tests/bench.sh $(BUILD)

$(BUILD)/bench/%: tests/%.c $(BUILD)/liblsmorph.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/liblsmorph.a -o $@ $(LDLIBS)

validate: all $(VALIDATION_BIN)
	@sh validation/run.sh $(BUILD)

install: all
	install -d $(DESTDIR)$(PREFIX)/bin
	install -m 755 $(BUILD)/lsmorph $(DESTDIR)$(PREFIX)/bin/lsmorph

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
