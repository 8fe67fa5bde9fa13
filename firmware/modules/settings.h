/**
 * \file settings.h
 * The settings module (thesis 6.3): the global `settings` (core/data.h) from compiled-in defaults or the
 * EEPROM (guarded by a magic, the layout hash and a CRC), bounds-checked field writes from the host, and the
 * host's settings commands (update_settings, read_settings, save_settings, load_defaults).
 */
#ifndef SETTINGS_H
#define SETTINGS_H

#include <stdbool.h>
#include <stdint.h>

#include "core/data.h"
#include "pb_protocol.h"

/** EEPROM image: header, the settings, CRC-16 over both. */
#define SETTINGS_EEPROM_ADDR 0u
#define SETTINGS_MAGIC 0x5042u /* "PB" */

/** Loads the settings from EEPROM, or the defaults when the EEPROM image is missing, stale or corrupt, and
 *  registers the settings commands with comm (read_settings is answered chunk by chunk as the transmit buffer
 *  has room, through comm_answer_later()). \return true if the EEPROM image was used. */
bool settings_init(void);

/** Bytes of settings per settings_data chunk. */
#define SETTINGS_CHUNK 64u

/** Replaces the settings with the compiled-in defaults (not saved). */
void settings_load_defaults(void);

/** Starts saving the settings to EEPROM. \return false when a save is still in progress. */
bool settings_save(void);

/** Reloads the EEPROM image. \return false (settings unchanged) when it is not valid. */
bool settings_load(void);

/**
 * Writes `len` bytes at `offset` into the settings, all or nothing. The range must start and end on field
 * boundaries (element boundaries inside numeric arrays; char arrays only whole), lie inside the struct, and
 * every value must be within its min..max (floats also finite).
 * \param detail set to the offending offset on refusal
 * \return PB_ERROR_CODE_NONE (applied), PB_ERROR_CODE_SETTINGS_RANGE or PB_ERROR_CODE_SETTINGS_VALUE.
 */
uint8_t settings_write(uint16_t offset, uint8_t len, const uint8_t *data, uint16_t *detail);

#endif
