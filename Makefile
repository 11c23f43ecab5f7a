# tetraprobe front door. The README's two commands:
#   make demo   set up, build (Release), bake the bundled sample, render out/demo.png (full) and
#               out/demo_indirect.png, evaluate
#   make test   set up, build, run the whole test suite through ctest
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
TP := $(BUILD_DIR)/bin/tetraprobe
SAMPLE := samples/two_rooms/two_rooms.scene.json
WERROR := $(if $(CI),ON,OFF)

.PHONY: all setup configure build demo test bench update-references clean

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

# Re-render the visual regression references after an intended change (look at them before committing).
update-references: build
	@cd $(BUILD_DIR) && TETRAPROBE_UPDATE_REFERENCES=1 ctest -R Visual --output-on-failure
	@git status --short tests/visual/reference

bench: build
	@$(BUILD_DIR)/bin/tetraprobe_bench

clean:
	rm -rf $(BUILD_DIR) out
