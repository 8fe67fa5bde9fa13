/**
 * \file call_depth.h
 * The native engine's call depth count (firmware/Makefile includes it into wasm2c's code and engine.c): wasm2c's own
 * count is one global for every thread, and robots run on several. Per thread instead, and initial-exec (a plain
 * %fs-relative access, no call): every function of the firmware counts itself in and out, and runaway recursion traps
 * (WASM_RT_TRAP_EXHAUSTION) instead of overflowing the JVM thread's stack. engine.c zeroes it at each call in, since a
 * trap leaves it where it was.
 */
#ifndef POCKETBOT_NATIVE_CALL_DEPTH_H
#define POCKETBOT_NATIVE_CALL_DEPTH_H

#include <stdint.h>

extern __thread uint32_t engine_call_depth __attribute__((tls_model("initial-exec")));

/* wasm2c's default. The firmware's calls nest a few dozen deep at most; its largest native frame is 160 bytes, so 500
 * take under 100 kB of the stepping thread's stack (1 MB by default). */
#define ENGINE_MAX_CALL_DEPTH 500

#endif
