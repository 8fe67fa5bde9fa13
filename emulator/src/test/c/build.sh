#!/bin/sh
# Rebuilds the stand-in firmware used by the emulator's wiring tests (checked in as a test resource so
# the tests need no C compiler): clang-14 + wasm-ld, freestanding, no libc.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
clang --target=wasm32 -O2 -ffreestanding -nostdlib -Wall -Wextra -Werror \
  -Wl,--no-entry,--stack-first,--export-dynamic -Wl,--allow-undefined \
  -o "$here/../resources/standin.wasm" "$here/standin.c"
