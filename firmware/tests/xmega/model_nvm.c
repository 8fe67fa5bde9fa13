/**
 * \file model_nvm.c
 * The NVM controller of the model: the EEPROM (2 kB, 32-byte pages) through its commands, and the production
 * signature row through LPM.
 *
 * READ_EEPROM (CMDEX) copies a byte to DATA0; with LOAD_EEPROM_BUFFER, writing DATA0 loads the page buffer at
 * ADDR; ERASE_EEPROM_BUFFER empties it; ERASE_WRITE_EEPROM_PAGE (CMDEX) replaces the loaded bytes of ADDR's page
 * and keeps NVMBUSY set for XM_EEPROM_WRITE_CYCLES. CMDEX is CCP-protected; commands while busy are misuses.
 * Not modelled: flash, fuses, lock bits, the EEPROM-ready interrupt, memory-mapped EEPROM.
 */
#include <string.h>

#include "model_internal.h"

static struct {
    xm_periph_t p;
    uint8_t ee[2048];
    uint8_t buf[32];
    uint32_t loaded; /* bytes of buf loaded */
    uint64_t busy_until;
} nvm;

static uint16_t address(void)
{
    return (uint16_t)((NVM.ADDR0 | NVM.ADDR1 << 8) & 0x7FFu);
}

static bool busy(void)
{
    return xm_time < nvm.busy_until;
}

static void execute(void)
{
    if (busy()) {
        xm_misuse("NVM command 0x%02x executed while the NVM is busy: ignored", NVM.CMD);
        return;
    }
    uint16_t a = address();
    switch (NVM.CMD) {
    case NVM_CMD_READ_EEPROM_gc:
        NVM.DATA0 = nvm.ee[a];
        break;
    case NVM_CMD_ERASE_EEPROM_BUFFER_gc:
        nvm.loaded = 0;
        NVM.STATUS &= (uint8_t)~NVM_EELOAD_bm;
        break;
    case NVM_CMD_ERASE_WRITE_EEPROM_PAGE_gc: {
        uint16_t page = (uint16_t)(a & ~31u);
        for (uint8_t i = 0; i < 32; i++)
            if (nvm.loaded & (1ul << i))
                nvm.ee[page + i] = nvm.buf[i];
        nvm.loaded = 0;
        NVM.STATUS &= (uint8_t)~NVM_EELOAD_bm;
        nvm.busy_until = xm_time + XM_EEPROM_WRITE_CYCLES;
        break;
    }
    default:
        xm_misuse("NVM command 0x%02x is not modelled", NVM.CMD);
    }
}

static void nvm_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    switch (off) {
    case 0x04: /* DATA0: loads the page buffer under LOAD_EEPROM_BUFFER */
        NVM.DATA0 = v;
        if (NVM.CMD == NVM_CMD_LOAD_EEPROM_BUFFER_gc) {
            if (busy())
                xm_misuse("EEPROM page buffer loaded while the NVM is busy");
            nvm.buf[address() & 31u] = v;
            nvm.loaded |= 1ul << (address() & 31u);
            NVM.STATUS |= NVM_EELOAD_bm;
        }
        return;
    case 0x0B: /* CTRLA */
        if (!xm_ccp_open()) {
            xm_misuse("NVM.CTRLA written without the CCP signature: ignored");
            return;
        }
        if (v & NVM_CMDEX_bm)
            execute();
        return;
    case 0x0F: /* STATUS is read-only */
        return;
    default:
        xm_io[0x1C0 + off] = v;
    }
}

static uint8_t nvm_read(xm_periph_t *p, uint16_t off)
{
    (void)p;
    if (off == 0x0F)
        return (uint8_t)((NVM.STATUS & ~NVM_NVMBUSY_bm) | (busy() ? NVM_NVMBUSY_bm : 0));
    return xm_io[0x1C0 + off];
}

void xm_nvm_power_on(void)
{
    uint8_t keep[sizeof nvm.ee];
    memcpy(keep, nvm.ee, sizeof keep);
    memset(&nvm, 0, sizeof nvm);
    if (xm_cold())
        memset(nvm.ee, 0xFF, sizeof nvm.ee);
    else
        memcpy(nvm.ee, keep, sizeof keep);
    nvm.p = (xm_periph_t){.base = 0x1C0, .size = 0x18, .read = nvm_read, .write = nvm_write};
    xm_attach(&nvm.p);
}

uint8_t *xm_eeprom(void)
{
    return nvm.ee;
}

uint8_t xm_lpm(uint16_t addr)
{
    if (NVM.CMD == NVM_CMD_READ_CALIB_ROW_gc)
        return xm_prod_signature(addr);
    xm_misuse("LPM from flash (0x%04x): flash is not modelled", addr);
    return 0xFF;
}
