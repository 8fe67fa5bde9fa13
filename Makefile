# PocketBot top-level build: make drives the firmware (C) and Maven (every JVM module).
#
#   make test        everything CI runs: deps, protocol check, firmware tests, mvn verify
#   make run         build what is needed, then HelloRobot and the fleet demo ($(RUN_MAIN)) on the emulator
#   make hello       run the HelloRobot example
#   make emulator    run the emulator CLI, e.g. make emulator ARGS="--robots 3"
#   make jvm         mvn install of the reactor (no tests), after the firmware wasm
#   make bench | bench-emulator | bench-sdk | fuzz | clean

MVN       ?= mvn -B
# The Kotlin daemon would otherwise outlive the build (1-6 GB each).
MVN_FLAGS ?= -Dkotlin.compiler.daemon=false
# The emulator's firmware-wasm profile activates by itself when the wasm exists; naming it makes a
# missing wasm a build error here instead of an emulator built without its firmware.
MVN_PROFILES ?= -Pfirmware-wasm
MAVEN     := $(MVN) $(MVN_FLAGS) $(MVN_PROFILES)
JAVA      ?= java
PYTHON    ?= python3
ARGS      ?=

RUN_MAIN            ?= org.pocketbot.examples.FleetDemoKt
HELLO_MAIN          ?= org.pocketbot.examples.HelloRobotKt
EMULATOR_MAIN       ?= org.pocketbot.emulator.cli.MainKt
BENCH_EMULATOR_MAIN ?= org.pocketbot.emulator.bench.EmulatorBenchKt
BENCH_SDK_MAIN      ?= org.pocketbot.bench.SdkBenchKt
# Jazzer: JAZZER_FUZZ=1 turns @FuzzTest from regression (seeds only) into real fuzzing; it fuzzes
# one @FuzzTest per run, so pick it with FUZZ_TEST.
FUZZ_TEST           ?= *FuzzTest
FUZZ_MODULE         ?= sdk/jvm

WASM := firmware/build/wasm/pocketbot.wasm

# `make run` / `hello` / `emulator` start with plain `java -cp` from the classpath files Maven
# writes at package time, and rebuild only when a JVM source, pom or the firmware wasm changed.
JVM_INPUTS := $(shell find pom.xml .mvn sdk emulator examples -name target -prune -o -type f \
                \( -name '*.kt' -o -name '*.java' -o -name 'pom.xml' -o -name '*.json' \
                   -o -name 'jvm.config' -o -path '*/src/main/resources/*' \) -print 2>/dev/null)
RUN_STAMP  := examples/target/classpath.txt
cp_of       = $(1)/target/classes:$$(cat $(1)/target/classpath.txt)

.PHONY: all deps firmware wasm protocol-check jvm test run hello emulator \
        bench bench-emulator bench-sdk fuzz clean

all: jvm

deps:
	@bash scripts/ensure-deps.sh

firmware: deps
	$(MAKE) -C firmware all

wasm: deps
	$(MAKE) -C firmware wasm

protocol-check: deps
	$(PYTHON) protocol/gen.py --check

jvm: wasm
	$(MAVEN) install -DskipTests

# Sequential on purpose (also under make -j): cheap checks first, the long Maven build last.
# -fae: a failing module still lets the independent ones run, so the log has every count.
test: deps
	$(MAKE) --no-print-directory protocol-check
	$(MAKE) -C firmware test
	$(MAKE) -C firmware wasm
	$(MAVEN) -fae verify

# Packages examples and everything it needs (emulator, sdk); skips tests and the Kotlin/JS gate,
# which `make test` covers.
$(RUN_STAMP): $(JVM_INPUTS) $(wildcard $(WASM))
	$(MAVEN) package -pl examples -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

run: wasm
	@$(MAKE) --no-print-directory $(RUN_STAMP)
	$(JAVA) -cp "$(call cp_of,examples)" $(HELLO_MAIN)
	$(JAVA) -cp "$(call cp_of,examples)" $(RUN_MAIN) $(ARGS)

hello: wasm
	@$(MAKE) --no-print-directory $(RUN_STAMP)
	$(JAVA) -cp "$(call cp_of,examples)" $(HELLO_MAIN) $(ARGS)

emulator: wasm
	@if [ ! -f emulator/target/classpath.txt ] || [ -n "$$(find pom.xml sdk/core emulator $(WASM) -path '*/target' -prune -o -type f \( -name '*.kt' -o -name pom.xml -o -name '*.json' -o -name '*.wasm' \) -newer emulator/target/classpath.txt -print 2>/dev/null | head -1)" ]; then \
	  $(MAVEN) package -pl emulator -am -DskipTests -Dpocketbot.jsgate.skip=true && touch emulator/target/classpath.txt; fi
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,emulator)" $(EMULATOR_MAIN) $(ARGS)

bench: bench-emulator bench-sdk
	$(MAKE) -C firmware bench

bench-emulator: wasm
	@if [ ! -f emulator/target/classpath.txt ] || [ -n "$$(find pom.xml sdk/core emulator $(WASM) -path '*/target' -prune -o -type f \( -name '*.kt' -o -name pom.xml -o -name '*.json' -o -name '*.wasm' \) -newer emulator/target/classpath.txt -print 2>/dev/null | head -1)" ]; then \
	  $(MAVEN) package -pl emulator -am -DskipTests -Dpocketbot.jsgate.skip=true && touch emulator/target/classpath.txt; fi
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,emulator)" $(BENCH_EMULATOR_MAIN) $(ARGS)

bench-sdk: wasm
	$(MAVEN) package -pl sdk/bench -am -DskipTests -Dpocketbot.jsgate.skip=true
	$(JAVA) -cp "$(call cp_of,sdk/bench)" $(BENCH_SDK_MAIN) $(ARGS)

fuzz: wasm
	$(MAKE) -C firmware fuzz
	JAZZER_FUZZ=1 $(MAVEN) test -pl $(FUZZ_MODULE) -am -Dtest='$(FUZZ_TEST)' \
	  -Dsurefire.failIfNoSpecifiedTests=false -Dpocketbot.jsgate.skip=true -Djazzer.long=true

clean:
	$(MVN) $(MVN_FLAGS) clean
	-$(MAKE) -C firmware clean
