# tetraprobe front door. The README's two commands:
#   make demo   set up, build (Release), bake the bundled sample, render out/demo.png (full) and
#               out/demo_indirect.png, evaluate
#   make test   set up, build, run the whole test suite through ctest
#   make fuzz   libFuzzer harnesses over the level and scene loaders, FUZZ_SECONDS each (clang; own build dir)
#   make test-sanitize   the suite under AddressSanitizer + UndefinedBehaviorSanitizer (own build dir)
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
TP := $(BUILD_DIR)/bin/tetraprobe
SAMPLE := samples/two_rooms/two_rooms.scene.json
WERROR := $(if $(CI),ON,OFF)
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
SANITIZE_DIR ?= build-sanitize
# Left out of the sanitizer run (ctest -E below): the visual tests (lavapipe's LLVM JIT under ASan, minutes
# for pixels the normal run compares) and the ten-million-query cell-grid sweeps (the paths the small CellGrid
# tests take, 10^7 times).

.PHONY: all setup configure build demo test fuzz test-sanitize bench update-references clean

all: build

setup:
	@tools/setup/setup.sh

configure: setup
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DTETRAPROBE_WERROR=$(WERROR) >/dev/null

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

demo: build
	@mkdir -p out
	$(TP) bake $(SAMPLE) --spacing 0.5 -o out/two_rooms.tpb --report out/bake_report.json
	$(TP) render $(SAMPLE) out/two_rooms.tpb -o out/demo.png --camera overview --mode full
	$(TP) render $(SAMPLE) out/two_rooms.tpb -o out/demo_indirect.png --camera overview --mode indirect
	$(TP) eval $(SAMPLE) out/two_rooms.tpb --report out/eval_report.json

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

fuzz: build
	@JOBS=$(JOBS) tools/fuzz/run.sh $(TP) $(FUZZ_DIR) $(FUZZ_SECONDS)

# The suite under ASan + UBSan (GCC), every report fails the run; third-party leaks, should one appear, go in
# tools/sanitize/lsan.supp with the reason. SANITIZE_TARGETS: `all` (the default) or the test executables to
# build and run (CI: all).
SANITIZE_TARGETS ?= all
# Never under the sanitizers: the visual tests (lavapipe's LLVM JIT under ASan), the ten-million-query sweeps
# and the install test (it builds an outside project against the installed library, which is instrumented
# here, without the sanitizer runtime: a link error, not a finding); with a subset of targets also the script
# tests that run the CLI binary it does not build.
SANITIZE_EXCLUDE := _NOT_BUILT|^Visual\.|TenMillionQueries|^InstallPackage\.$(if $(filter all,$(SANITIZE_TARGETS)),,|^distributed\.)
# The Vulkan loader dlcloses the lavapipe driver at vkDestroyInstance; what the driver's globals still pointed
# to then reads as 240 bytes "leaked" from an unknown module, which no suppression can name. Preloading the
# driver keeps it mapped to the end of the process (its memory stays reachable: nothing is reported).
LAVAPIPE := $(firstword $(shell sed -n 's/.*"library_path": *"\([^"]*\)".*/\1/p' /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null))
SANITIZE_PRELOAD := $(if $(LAVAPIPE),LD_PRELOAD=$(LAVAPIPE) ,)
# -O1 -g1: half the compile time of -O2 -g on the CGAL and Embree units (bench_locate.cpp 81 s -> 36 s) for
# tests about 1.3x slower; line tables are all a sanitizer report needs for file:line frames.
SANITIZE_FLAGS := -O1 -g1 -DNDEBUG
test-sanitize: setup
	@cmake -S . -B $(SANITIZE_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTETRAPROBE_SANITIZE=ON \
		-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$(SANITIZE_FLAGS)" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$(SANITIZE_FLAGS)" \
		-DTETRAPROBE_BUILD_BENCH=OFF -DTETRAPROBE_WERROR=$(WERROR) >/dev/null
	@cmake --build $(SANITIZE_DIR) -j $(JOBS) --target $(SANITIZE_TARGETS)
	@cd $(SANITIZE_DIR) && $(SANITIZE_PRELOAD)ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:verify_asan_link_order=0 \
		LSAN_OPTIONS=suppressions=$(CURDIR)/tools/sanitize/lsan.supp:print_suppressions=0 \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
		ctest --output-on-failure -j $(JOBS) -E "$(SANITIZE_EXCLUDE)"

# Re-render the visual regression references after an intended change (look at them before committing).
update-references: build
	@cd $(BUILD_DIR) && TETRAPROBE_UPDATE_REFERENCES=1 ctest -R Visual --output-on-failure
	@git status --short tests/visual/reference

bench: build
	@$(BUILD_DIR)/bin/tetraprobe_bench
	@$(BUILD_DIR)/bin/tetraprobe_bench_load

clean:
	rm -rf $(BUILD_DIR) $(FUZZ_DIR) $(SANITIZE_DIR) out
