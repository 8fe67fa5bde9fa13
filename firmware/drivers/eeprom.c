#include "eeprom.h"

#include <string.h>

#include "hal/hal.h"

static uint8_t pending[EEPROM_WRITE_MAX];
static uint16_t pending_addr;
static uint16_t pending_len;
static uint16_t pending_done;

void eeprom_init(void)
{
    pending_len = pending_done = 0;
}

void eeprom_read(uint16_t addr, void *dst, uint16_t len)
{
    hal_eeprom_read(addr, dst, len);
}

bool eeprom_write(uint16_t addr, const void *src, uint16_t len)
{
    if (eeprom_busy() || len > EEPROM_WRITE_MAX || (uint32_t)addr + len > HAL_EEPROM_SIZE)
        return false;
    memcpy(pending, src, len);
    pending_addr = addr;
    pending_len = len;
    pending_done = 0;
    return true;
}

bool eeprom_busy(void)
{
    return pending_done < pending_len || hal_eeprom_busy();
}

void eeprom_task(void)
{
    if (pending_done >= pending_len || hal_eeprom_busy())
        return;
    uint16_t addr = (uint16_t)(pending_addr + pending_done);
    uint16_t room = (uint16_t)(HAL_EEPROM_PAGE - addr % HAL_EEPROM_PAGE);
    uint16_t n = (uint16_t)(pending_len - pending_done);
    if (n > room)
        n = room;
    hal_eeprom_write_page(addr, pending + pending_done, (uint8_t)n);
    pending_done = (uint16_t)(pending_done + n);
}
