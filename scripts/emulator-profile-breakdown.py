#!/usr/bin/env python3
"""Where a robot-millisecond goes: classifies the CPU samples of a JFR recording of the emulator by the top frame.

    make profile-emulator ARGS="1000"      # records target/emulator-<N>.jfr and prints this breakdown
    scripts/emulator-profile-breakdown.py recording.jfr

Reads `jfr print --events jdk.ExecutionSample` (the JDK's own tool) and prints one line per category with its
share of the samples. The top frame decides, so time in a callee is its own (a host call from the firmware to the
line sensor counts as line sensor geometry, not as firmware).
"""
import collections
import re
import shutil
import subprocess
import sys

CATEGORIES = [  # (category, regex on "Class.method" of the top frame), first match wins
    ("firmware (wasm under Chicory, incl. export/host call glue)",
     r"^(org\.pocketbot\.emulator\.firmware\.|com\.dylibso\.chicory\.)"),
    ("line sensor and colour geometry", r"^org\.pocketbot\.emulator\.(world\.Surface|SimRobot\.(lineAdcSweep|computeSpots|sensorRead))"),
    ("IR between robots and obstacles", r"^org\.pocketbot\.emulator\.SimWorld\.(exchangeIr|deliverTo)|SimRobot\.(irSend|irHeard)"),
    ("collisions, box contacts, who is alone", r"^org\.pocketbot\.emulator\.(SimWorld\.(separateRobots|checkContacts|resolvePushes|buildGrid|afterStep|markAlone|nearBox)|physics\.Obb)"),
    ("robot physics (motion, encoders, battery)", r"^org\.pocketbot\.emulator\.SimRobot\."),
    ("link model", r"^org\.pocketbot\.emulator\.link\."),
    ("stepping and synchronization", r"^(org\.pocketbot\.emulator\.(internal\.ParallelStepper|Emulator\.)|java\.lang\.Thread\.|java\.util\.concurrent\.|jdk\.internal\.misc\.)"),
    ("math library", r"^java\.lang\.(Math|StrictMath)\."),
]


def main(path: str) -> None:
    jfr = shutil.which("jfr") or "jfr"
    out = subprocess.run([jfr, "print", "--events", "jdk.ExecutionSample", "--stack-depth", "1", path],
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
