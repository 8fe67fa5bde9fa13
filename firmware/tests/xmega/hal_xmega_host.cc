/**
 * \file hal_xmega_host.cc
 * The robot's HAL, hal/xmega/hal_xmega.c, compiled on the host against the XMEGA model. It is compiled as C++ so
 * that the register types of include/avr/io.h can hand every register access to the model; the source is the
 * robot's, unchanged, with C linkage.
 */
#include <string.h>

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>

extern "C" {
#include "hal/xmega/hal_xmega.c"
}
