#!/bin/sh
# Writes the `pocketbot` launcher: a shell script that runs the command line on JAVA with CLASSPATH.
# `make cli` writes cli/target/pocketbot with it; the CLI's process tests write and run their own the same way.
# usage: launcher.sh JAVA CLASSPATH OUT
set -eu
[ $# -eq 3 ] || { echo "usage: $0 JAVA CLASSPATH OUT" >&2; exit 2; }
mkdir -p "$(dirname "$3")"
printf '#!/bin/sh\nexec "%s" -cp "%s" org.pocketbot.cli.MainKt "$@"\n' "$1" "$2" > "$3"
chmod +x "$3"
