# Thin wrapper over CMake.  `make demo` and `make test` install missing
# Debian packages first (scripts/deps.sh), then build and run.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
# New build trees (this one and those the tests configure) use Ninja when it
# is installed (scripts/deps.sh installs it): a whole build takes about 12 %
# less CPU than with Makefiles; an existing tree keeps its generator.  Expanded
# when a recipe runs, i.e. after deps.
CMAKE_GENERATOR ?= $(shell command -v ninja >/dev/null 2>&1 && echo Ninja || echo "Unix Makefiles")
export CMAKE_GENERATOR

.PHONY: all test demo bench tradeoff cross fuzz coverage soak clean deps
FUZZ_SECONDS ?= 2700
FUZZ_HOST_SECONDS ?= 3600

all: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j$(JOBS)

deps:
	@scripts/deps.sh

test: all
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# the demo builds only the CLI (not the tests and benchmarks)
demo: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j$(JOBS) --target conetrace_cli
	scripts/demo.sh $(BUILD)

# ct_bench and ct_bench_geoloc last: scripts/bench_targets.py runs them, keeps their output in
# $(BUILD)/bench/logs/ and ends with issue 14's targets as this run measured them
bench: all
	$(BUILD)/bench/ct_bench_tiles
	$(BUILD)/bench/ct_bench_build
	$(BUILD)/bench/ct_bench_ddt
	scripts/bench_m4.sh $(BUILD)
	/usr/bin/python3 scripts/viewshed_vs_gdal.py $(BUILD)
	/usr/bin/python3 scripts/bench_targets.py run $(BUILD)

# what each knob buys and costs: build/tradeoff/tradeoff.csv and its plots
# (a few minutes; docs/benchmarks.md)
tradeoff: all
	$(BUILD)/bench/ct_tradeoff --out $(BUILD)/tradeoff
	/usr/bin/python3 scripts/plot_tradeoff.py $(BUILD)/tradeoff

cross: deps
	scripts/cross.sh $(BUILD)/cross

# long fuzzing of lib/ (10^7 inputs or FUZZ_SECONDS, whichever comes first,
# one worker per core), then of the host tools' file readers (FUZZ_HOST_SECONDS);
# the corpora are kept in $(BUILD)/fuzz_corpus and $(BUILD)/fuzz_host_corpus between runs
fuzz: all
	sh tests/fuzz/fuzz.sh $(BUILD) 10000000 $(FUZZ_SECONDS) $(BUILD)/fuzz_corpus
	sh tests/fuzz/fuzz_host.sh $(BUILD) 10000000 $(FUZZ_HOST_SECONDS) $(BUILD)/fuzz_host_corpus

# many seeded rays (10^7, or SOAK_SECONDS) on generated terrain against the
# long-double reference, the methods compared (tests/soak.cpp)
SOAK_SECONDS ?= 1800
soak: all
	$(BUILD)/tests/ct_soak --rays 10000000 --seconds $(SOAK_SECONDS)

# line and branch coverage of lib/ by the test suite (gcov, gcovr), in a
# separate build directory
coverage: deps
	scripts/coverage.sh $(BUILD)-coverage

clean:
	rm -rf $(BUILD)
