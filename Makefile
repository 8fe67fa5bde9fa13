# PocketBot top-level build: make drives the firmware (C) and Maven (every JVM module).
#
#   make test        everything CI runs: deps, protocol check, firmware tests, every Maven module's tests (the
#                    libraries then deployed to target/repository), then samples/outside built and run against them
#   make publish     the libraries as a Maven repository folder: $(PUBLISH_REPO) (PUBLISH_REPO=/other/dir)
#   make docs        the libraries' API docs (Dokka HTML): target/docs/index.html
#   make run         the control panel with an embedded emulator fleet; without a display, HelloRobot and the
#                    headless fleet demo ($(RUN_MAIN)) instead
#   make cli         builds the `pocketbot` command line: cli/target/pocketbot
#   make apk         the Android app: android-app/target/android/pocketbot.apk, signed and checked
#   make panel       the control panel (ARGS="--world fork --robots 5", --no-emulator, ...)
#   make screenshots the panel under Xvfb, driven through its views: PNGs in docs/images/
#   make hello       run the HelloRobot example
#   make push        thesis A.2: two robots push a heavy box off the track (host-coordinated), simulated time
#   make track       thesis A.3: three robots on a track, the behaviour in their firmware, simulated time
#   make emulator    run the emulator CLI, e.g. make emulator ARGS="--robots 3"
#   make jvm         mvn package of the reactor (no tests), after the firmware wasm and native engine
#   make bench | bench-emulator | profile-emulator | bench-sdk | bench-bluetooth | bench-desktop | fuzz | clean

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
PUSH_MAIN           ?= org.pocketbot.examples.CooperativePushKt
TRACK_MAIN          ?= org.pocketbot.examples.TrackDemoKt
EMULATOR_MAIN       ?= org.pocketbot.emulator.cli.MainKt
BENCH_EMULATOR_MAIN ?= org.pocketbot.emulator.bench.EmulatorBenchKt
BENCH_SDK_MAIN      ?= org.pocketbot.bench.SdkBenchKt
BENCH_BLUETOOTH_MAIN ?= org.pocketbot.bench.BluetoothBenchKt
PANEL_MAIN          ?= org.pocketbot.desktop.MainKt
BENCH_DESKTOP_MAIN  ?= org.pocketbot.desktop.bench.DesktopBenchKt
# Skia draws in software (no GPU on CI or under Xvfb) and unpacks its native library under target/, not ~/.skiko.
PANEL_JVM_FLAGS     ?= -Dskiko.renderApi=SOFTWARE -Dskiko.data.path=desktop-app/target/skiko
# Jazzer: JAZZER_FUZZ=1 turns @FuzzTest from regression (seeds only) into real fuzzing; it fuzzes
# one @FuzzTest per run, so pick it with FUZZ_TEST.
FUZZ_TEST           ?= *FuzzTest
FUZZ_MODULE         ?= sdk/jvm

WASM := firmware/build/wasm/pocketbot.wasm
# The emulator's native engine, made from that wasm (firmware/native/engine.c); Maven puts it in the emulator's jar.
NATIVE_ENGINE := $(wildcard firmware/build/native/lib/*/libpocketbot-firmware.so)

# The published libraries (and their parent POM and BOM), and the folder `make publish` deploys them to: a Maven
# repository on disk, never ~/.m2 (install is skipped; the local repository is shared with other builds).
LIBRARIES     := library,library/bom,sdk/protocol,sdk/core,sdk/jvm,emulator,emulator/simulated,sdk/mqtt
PUBLISH_REPO  ?= target/repository
publish_to     = -Dmaven.install.skip=true -DaltDeploymentRepository=pocketbot::file://$(abspath $(1))

# `make run` / `hello` / `emulator` start with plain `java -cp` from the classpath files Maven
# writes at package time, and rebuild only when a JVM source, pom or the firmware wasm changed.
JVM_INPUTS := $(shell find pom.xml .mvn library sdk emulator examples desktop-app -name target -prune -o -type f \
                \( -name '*.kt' -o -name '*.java' -o -name 'pom.xml' -o -name '*.json' \
                   -o -name 'jvm.config' -o -path '*/src/main/resources/*' \) -print 2>/dev/null)
RUN_STAMP  := examples/target/classpath.txt
PANEL_STAMP := desktop-app/target/classpath.txt
cp_of       = $(1)/target/classes:$$(cat $(1)/target/classpath.txt)

.PHONY: all deps firmware wasm protocol-check jvm test publish docs outside-sample run hello push track emulator cli \
        panel screenshots apk bench bench-emulator profile-emulator bench-sdk bench-bluetooth bench-desktop fuzz clean

all: jvm

deps:
	@bash scripts/ensure-deps.sh

firmware: deps
	$(MAKE) -C firmware all

# The firmware as the emulator runs it: the wasm, and the native engine made from it.
wasm: deps
	$(MAKE) -C firmware wasm native-engine

protocol-check: deps
	$(PYTHON) protocol/gen.py --check

jvm: wasm
	$(MAVEN) package -DskipTests

# Sequential on purpose (also under make -j): cheap checks first, the long Maven build last.
# -fae: a failing module still lets the independent ones run, so the log has every count.
# Bumble (the virtual Bluetooth controllers of the end-to-end tests) goes into a venv of its own, build/bumble.
test: deps
	@bash scripts/ensure-bumble.sh >/dev/null
	$(MAKE) --no-print-directory protocol-check
	$(MAKE) -C firmware test
	$(MAKE) -C firmware wasm native-engine
	rm -rf target/repository
	$(MAVEN) -fae deploy $(call publish_to,target/repository)
	$(MAKE) --no-print-directory outside-sample PUBLISH_REPO=target/repository

# The libraries without their tests (`make test` runs them, and publishes in the same Maven run).
publish: wasm
	$(MAVEN) deploy -pl $(LIBRARIES) -am -Dmaven.test.skip=true -Dpocketbot.jsgate.skip=true $(call publish_to,$(PUBLISH_REPO))
	@echo "published to $(PUBLISH_REPO):"; cd $(PUBLISH_REPO) && find org -name '*.pom' -o -name '*.jar' | sort

# A program outside the reactor (its own POM, no parent) built against $(PUBLISH_REPO) alone, plus Central.
outside-sample:
	bash samples/outside/build-and-run.sh $(abspath $(PUBLISH_REPO))

# One site for all libraries (library/docs), without the per-library docs and jars `make publish` makes.
docs: wasm
	$(MAVEN) package -pl library/docs -am -Dmaven.test.skip=true -Dpocketbot.jsgate.skip=true -Dpocketbot.publish.skip=true
	@echo "API reference: target/docs/index.html"

# Packages examples and everything it needs (emulator, sdk); skips tests and the Kotlin/JS gate,
# which `make test` covers.
$(RUN_STAMP): $(JVM_INPUTS) $(wildcard $(WASM)) $(NATIVE_ENGINE)
	$(MAVEN) package -pl examples -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

$(PANEL_STAMP): $(JVM_INPUTS) $(wildcard $(WASM)) $(NATIVE_ENGINE)
	$(MAVEN) package -pl desktop-app -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

# The panel when there is a display to show it on; the headless demo otherwise.
run: wasm
	@if [ -n "$$DISPLAY" ]; then $(MAKE) --no-print-directory panel; else \
	  echo "make run: no display (DISPLAY is not set), so the headless fleet demo runs instead of the panel"; \
	  $(MAKE) --no-print-directory $(RUN_STAMP) && \
	  $(JAVA) -cp "$(call cp_of,examples)" $(HELLO_MAIN) && \
	  $(JAVA) -cp "$(call cp_of,examples)" $(RUN_MAIN) $(ARGS); fi

EMULATOR_STAMP := emulator/target/classpath.txt
EMULATOR_CLI_STAMP := emulator/cli/target/classpath.txt
EMULATOR_INPUTS := $(shell find pom.xml .mvn library sdk/protocol sdk/core emulator -name target -prune -o -type f \
                     \( -name '*.kt' -o -name 'pom.xml' -o -name '*.json' -o -name 'jvm.config' \) -print 2>/dev/null)

$(EMULATOR_STAMP): $(EMULATOR_INPUTS) $(wildcard $(WASM)) $(NATIVE_ENGINE)
	$(MAVEN) package -pl emulator -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

# The command's --broker serves the robots through sdk/mqtt.
$(EMULATOR_CLI_STAMP): $(EMULATOR_INPUTS) $(wildcard $(WASM)) $(NATIVE_ENGINE) $(shell find sdk/mqtt/pom.xml sdk/mqtt/src/main -type f 2>/dev/null)
	$(MAVEN) package -pl emulator/cli -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

CLI_STAMP := cli/target/classpath.txt

$(CLI_STAMP): $(JVM_INPUTS) $(wildcard $(WASM)) $(NATIVE_ENGINE) $(shell find cli -name target -prune -o -type f -print 2>/dev/null)
	$(MAVEN) package -pl cli -am -DskipTests -Dpocketbot.jsgate.skip=true
	@touch $@

# A launcher script with this checkout's absolute classpath: copy or link it anywhere on the PATH.
cli: wasm
	@$(MAKE) --no-print-directory $(CLI_STAMP)
	@sh cli/launcher.sh "$(JAVA)" "$(CURDIR)/cli/target/classes:$$(cat cli/target/classpath.txt)" cli/target/pocketbot
	@echo "built cli/target/pocketbot; put it on the PATH with:"
	@echo "  ln -sf $(CURDIR)/cli/target/pocketbot ~/.local/bin/pocketbot"

# The APK without its tests (`make test` runs them, and builds and checks the APK in the same Maven run).
apk: wasm
	$(MAVEN) package -pl android-app -am -DskipTests -Dpocketbot.jsgate.skip=true
	@echo "built android-app/target/android/pocketbot.apk; install it with:"
	@echo "  adb install -r android-app/target/android/pocketbot.apk"

panel: wasm
	@bash scripts/ensure-deps.sh desktop
	@$(MAKE) --no-print-directory $(PANEL_STAMP)
	$(JAVA) $(PANEL_JVM_FLAGS) -cp "$(call cp_of,desktop-app)" $(PANEL_MAIN) $(ARGS)

screenshots: wasm
	@bash scripts/ensure-deps.sh screenshots
	@$(MAKE) --no-print-directory $(PANEL_STAMP)
	xvfb-run -a -s "-screen 0 1600x1000x24" $(JAVA) $(PANEL_JVM_FLAGS) -cp "$(call cp_of,desktop-app)" $(PANEL_MAIN) --screenshots docs/images

hello: wasm
	@$(MAKE) --no-print-directory $(RUN_STAMP)
	$(JAVA) -cp "$(call cp_of,examples)" $(HELLO_MAIN) $(ARGS)

# The multi-robot scenarios of thesis appendix A, headless against an embedded emulator on simulated time.
push: wasm
	@$(MAKE) --no-print-directory $(RUN_STAMP)
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,examples)" $(PUSH_MAIN) $(ARGS)

track: wasm
	@$(MAKE) --no-print-directory $(RUN_STAMP)
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,examples)" $(TRACK_MAIN) $(ARGS)

emulator: wasm
	@$(MAKE) --no-print-directory $(EMULATOR_CLI_STAMP)
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,emulator/cli)" $(EMULATOR_MAIN) $(ARGS)

bench: bench-emulator bench-sdk bench-bluetooth bench-desktop
	$(MAKE) -C firmware bench

bench-emulator: wasm
	@$(MAKE) --no-print-directory $(EMULATOR_STAMP)
	$(MAKE) -C firmware native-fleet
	$(JAVA) -XX:-DontCompileHugeMethods -Dpocketbot.bench.native=firmware/build/native/fleet -cp "$(call cp_of,emulator)" $(BENCH_EMULATOR_MAIN) $(ARGS)

# Where a robot-millisecond goes: the emulator benchmark under Java Flight Recorder (1 ms CPU samples, Java and native
# code), then the samples by category (firmware, line sensor geometry, IR, collisions, physics, link, stepping).
# ARGS: fleet sizes; PROFILE_ENGINE: native or chicory. One stepping thread: JFR samples one thread in native code a period.
PROFILE_ENGINE ?= native
profile-emulator: wasm
	@$(MAKE) --no-print-directory $(EMULATOR_STAMP)
	$(JAVA) -XX:-DontCompileHugeMethods "-XX:StartFlightRecording=filename=emulator/target/emulator-profile.jfr,settings=profile,jdk.ExecutionSample#period=1ms,jdk.NativeMethodSample#period=1ms" \
	  -Dpocketbot.bench.engines=$(PROFILE_ENGINE) -Dpocketbot.bench.threads=1 \
	  -cp "$(call cp_of,emulator)" $(BENCH_EMULATOR_MAIN) $(or $(ARGS),1000)
	PATH="$$(dirname $$(readlink -f $$(command -v $(JAVA))))":$$PATH $(PYTHON) scripts/emulator-profile-breakdown.py emulator/target/emulator-profile.jfr

bench-sdk: wasm
	$(MAVEN) package -pl sdk/bench -am -DskipTests -Dpocketbot.jsgate.skip=true
	$(JAVA) -cp "$(call cp_of,sdk/bench)" $(BENCH_SDK_MAIN) $(ARGS)

# State packets a second over the robot's own Bluetooth (RFCOMM, L2CAP) against its UART. ARGS: seconds per link.
bench-bluetooth: wasm
	$(MAVEN) package -pl sdk/bench -am -DskipTests -Dpocketbot.jsgate.skip=true
	$(JAVA) -XX:-DontCompileHugeMethods -cp "$(call cp_of,sdk/bench)" $(BENCH_BLUETOOTH_MAIN) $(ARGS)

bench-desktop: wasm
	@$(MAKE) --no-print-directory $(PANEL_STAMP)
	$(JAVA) $(PANEL_JVM_FLAGS) -Djava.awt.headless=true -cp "$(call cp_of,desktop-app)" $(BENCH_DESKTOP_MAIN) $(ARGS)

fuzz: wasm
	$(MAKE) -C firmware fuzz
	JAZZER_FUZZ=1 $(MAVEN) test -pl $(FUZZ_MODULE) -am -Dtest='$(FUZZ_TEST)' \
	  -Dsurefire.failIfNoSpecifiedTests=false -Dpocketbot.jsgate.skip=true -Djazzer.long=true

clean:
	$(MVN) $(MVN_FLAGS) clean
	rm -rf samples/outside/target
	-$(MAKE) -C firmware clean
