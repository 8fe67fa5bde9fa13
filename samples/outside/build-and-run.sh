#!/usr/bin/env bash
# Builds and runs the sample as a user's project: the PocketBot artifacts only from the Maven repository folder $1
# (what `make publish` writes), everything else from Maven Central, through a local repository of its own under
# target/ (never ~/.m2, where this build's own artifacts could be found). The PocketBot artifacts are deleted from it
# first, so every run resolves them from $1 again. Checks that the three robots' odometry agrees with ground truth.
set -euo pipefail
repository=$1
here=$(cd "$(dirname "$0")" && pwd)

# The README shows this program: its copy must be the program that builds and runs here.
python3 - "$here/../../README.md" "$here/src/main/kotlin/Squares.kt" <<'PY'
import sys
readme, program = (open(f).read() for f in sys.argv[1:])
marker = "<!-- samples/outside/src/main/kotlin/Squares.kt"
block = readme.split(marker, 1)[1].split("```kotlin\n", 1)[1].split("```", 1)[0]
if block != program:
    sys.exit("outside sample: the program in README.md differs from samples/outside/src/main/kotlin/Squares.kt")
PY
local_repo=$here/target/m2
version=$(sed -n 's:^  <version>\(.*\)</version>$:\1:p' "$here/../../library/pom.xml")
rm -rf "$local_repo/org/pocketbot"
out=$here/target/run.txt
mkdir -p "$here/target"
${MVN:-mvn} -B -U -f "$here/pom.xml" -Dmaven.repo.local="$local_repo" -Dpocketbot.repository="file://$repository" \
  -Dpocketbot.version="$version" package exec:exec | tee "$out"

# Resolved from the published folder, not from anywhere else.
for a in pocketbot-sdk-core pocketbot-emulator pocketbot-emulator-simulated pocketbot-protocol; do
  grep -q '>pocketbot=' "$local_repo/org/pocketbot/$a/$version/_remote.repositories" \
    || { echo "outside sample: $a $version did not come from $repository"; exit 1; }
done
lines=$(grep -E '^PocketBot-[0-9]+: odometry .* off by [0-9.]+ mm' "$out" || true)
[ "$(echo "$lines" | grep -c . )" = 3 ] || { echo "outside sample: expected three robots' results"; exit 1; }
worst=$(echo "$lines" | sed -E 's/.* off by ([0-9.]+) mm.*/\1/' | sort -g | tail -1)
awk -v w="$worst" 'BEGIN { exit !(w < 10) }' || { echo "outside sample: odometry off by $worst mm"; exit 1; }
echo "outside sample: three robots drove their squares, odometry within $worst mm of ground truth"
