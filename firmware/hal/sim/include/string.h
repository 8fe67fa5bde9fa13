/**
 * \file string.h
 * The part of <string.h> the firmware uses, for the freestanding WebAssembly build (see sim_libc.c).
 */
#ifndef __wasm__
#error "hal/sim/include/string.h stands in for libc in the WebAssembly build only"
#endif
#ifndef SIM_STRING_H
#define SIM_STRING_H

#include <stddef.h>

void *memcpy(void *restrict dst, const void *restrict src, size_t n);
void *memmove(void *dst, const void *src, size_t n);
void *memset(void *dst, int c, size_t n);
int memcmp(const void *a, const void *b, size_t n);

#endif
