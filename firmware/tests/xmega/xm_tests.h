/** \file xm_tests.h  The suites of the HAL tests on the XMEGA model, one per file. */
#ifndef XM_TESTS_H
#define XM_TESTS_H

#include "harness.h"

void suite_xm_time(void);
void suite_xm_ir(void);
void suite_xm_colour(void);
void suite_xm_encoder(void);
void suite_xm_analog(void);
void suite_xm_recovery(void);
void suite_xm_uart(void);
void suite_xm_load(void);

#endif
