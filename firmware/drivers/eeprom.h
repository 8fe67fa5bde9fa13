/**
 * \file eeprom.h
 * Non-blocking EEPROM writer: a block is copied into a buffer and written page by page from eeprom_task()
 * while the NVM controller is idle.
 */
#ifndef EEPROM_H
#define EEPROM_H

#include <stdbool.h>
#include <stdint.h>

#define EEPROM_WRITE_MAX 192u

void eeprom_init(void);
/** Reads `len` bytes at `addr` (immediate). */
void eeprom_read(uint16_t addr, void *dst, uint16_t len);
/** Starts writing a copy of `src`. \return false if a write is in progress or the block does not fit. */
bool eeprom_write(uint16_t addr, const void *src, uint16_t len);
/** \return true while a write is in progress. */
bool eeprom_busy(void);
/** Writes the next page when the NVM controller is free. */
void eeprom_task(void);

#endif
