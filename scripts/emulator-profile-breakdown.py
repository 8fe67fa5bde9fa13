#!/usr/bin/env python3
"""Where a robot-millisecond goes: classifies the CPU samples of a JFR recording of the emulator by the top frame.

    make profile-emulator ARGS="1000"      # records target/emulator-<N>.jfr and prints this breakdown
    scripts/emulator-profile-breakdown.py recording.jfr

Reads `jfr print --events jdk.ExecutionSample,jdk.NativeMethodSample` (the JDK's own tool) and prints one line per
category with its share of the samples. The top frame decides, so time in a callee is its own. A thread in the native
firmware engine is sampled as a native method sample whose top frame is the JNI call into it (NativeEngine.*); JFR
samples at most one thread in native code per period, so the native engine's share is exact with one stepping
thread (`make profile-emulator` runs one).
"""
import collections
import re
import shutil
import subprocess
import sys

CATEGORIES = [  # (category, regex on "Class.method" of the top frame), first match wins
    ("firmware, native engine (machine code, JNI calls in)", r"^org\.pocketbot\.emulator\.firmware\.NativeEngine\."),
    ("firmware (wasm under Chicory, incl. export glue)",
     r"^(org\.pocketbot\.emulator\.firmware\.(Chicory|LinearMemory|FirmwareModule)|com\.dylibso\.chicory\.)"),
    ("firmware memory accessors (sensor inputs, outputs, events)",
     r"^(org\.pocketbot\.emulator\.firmware\.|java\.nio\.)"),
    ("line sensor and colour geometry", r"^org\.pocketbot\.emulator\.(world\.Surface|SimRobot\.(computeSpots|sense))"),
    ("IR between robots and obstacles", r"^org\.pocketbot\.emulator\.SimWorld\.(exchangeIr|deliverTo)|SimRobot\.(afterFirmware|irHeard)"),
    ("collisions, box contacts, who is alone", r"^org\.pocketbot\.emulator\.(SimWorld\.(separateRobots|checkContacts|resolvePushes|buildGrid|afterStep|markAlone|nearBox)|physics\.Obb)"),
    ("robot physics (motion, encoders, battery)", r"^org\.pocketbot\.emulator\.SimRobot\."),
    ("link model", r"^org\.pocketbot\.emulator\.link\."),
    ("stepping and synchronization", r"^(org\.pocketbot\.emulator\.(internal\.ParallelStepper|Emulator\.)|java\.lang\.Thread\.|java\.util\.concurrent\.|jdk\.internal\.misc\.)"),
    ("math library", r"^java\.lang\.(Math|StrictMath)\."),
]


def main(path: str) -> None:
    jfr = shutil.which("jfr") or "jfr"
    out = subprocess.run([jfr, "print", "--events", "jdk.ExecutionSample,jdk.NativeMethodSample", "--stack-depth", "1", path],
                         check=True, capture_output=True, text=True).stdout
    tops = re.findall(r"stackTrace = \[\s*\n\s*([\w.$<>]+)\(", out)
    counts = collections.Counter()
    for top in tops:
        for name, pattern in CATEGORIES:
            if re.search(pattern, top):
                counts[name] += 1
                break
        else:
            counts["other: " + top.rsplit(".", 2)[-2]] += 1
    total = sum(counts.values()) or 1
    print(f"{total} CPU samples in {path}")
    for name, n in counts.most_common(12):
        print(f"  {100.0 * n / total:5.1f} %  {name}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
