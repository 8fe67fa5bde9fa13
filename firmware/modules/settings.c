#include "settings.h"

#include <string.h>

#include "drivers/eeprom.h"
#include "hal/hal.h"
#include "modules/comm.h"
#include "protocol/pb_frame.h"

_Static_assert(SETTINGS_CHUNK == sizeof(((pb_settings_data_t *)0)->data), "a chunk fills settings_data");

/* The read_settings answer under way. */
static struct {
    uint8_t seq;
    uint16_t offset;
} reading;

static uint8_t on_update(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_read(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_save(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_load_defaults(const pb_frame_t *cmd, uint16_t *detail);
static bool answer_step(void);

typedef struct PB_PACKED {
    uint16_t magic;
    uint32_t layout_hash;
    uint16_t size;
} settings_header_t;

#define IMAGE_SIZE (sizeof(settings_header_t) + sizeof(pb_settings_t) + 2u)
_Static_assert(IMAGE_SIZE <= EEPROM_WRITE_MAX, "settings image exceeds the EEPROM write buffer");

/* The emulator gives each robot its id and name; a real robot keeps them in EEPROM. */
static void apply_board_identity(void)
{
    uint8_t id = hal_board_id();
    if (id == 0)
        return;
    settings.identity.robot_id = id;
    static const HAL_FLASH char prefix[] = "PocketBot-";
    uint8_t k = 0;
    while (prefix[k]) {
        settings.identity.name[k] = prefix[k];
        k++;
    }
    char digits[3];
    uint8_t n = 0;
    do {
        digits[n++] = (char)('0' + id % 10u);
        id /= 10u;
    } while (id);
    while (n)
        settings.identity.name[k++] = digits[--n];
    while (k < sizeof settings.identity.name)
        settings.identity.name[k++] = 0;
}

void settings_load_defaults(void)
{
    const HAL_FLASH uint8_t *src = (const HAL_FLASH uint8_t *)&pb_settings_defaults;
    uint8_t *dst = (uint8_t *)&settings;
    for (uint16_t i = 0; i < sizeof settings; i++)
        dst[i] = src[i];
    apply_board_identity();
    settings_generation++;
}

bool settings_load(void)
{
    settings_header_t h;
    eeprom_read(SETTINGS_EEPROM_ADDR, &h, sizeof h);
    if (h.magic != SETTINGS_MAGIC || h.layout_hash != PB_LAYOUT_HASH || h.size != sizeof(pb_settings_t))
        return false;
    static pb_settings_t candidate; /* static: 169 bytes are too many for the AVR stack */
    uint8_t crc_bytes[2];
    eeprom_read(SETTINGS_EEPROM_ADDR + sizeof h, &candidate, sizeof candidate);
    eeprom_read(SETTINGS_EEPROM_ADDR + sizeof h + sizeof candidate, crc_bytes, 2);
    uint16_t crc = pb_crc16(0xFFFFu, (const uint8_t *)&h, sizeof h);
    crc = pb_crc16(crc, (const uint8_t *)&candidate, sizeof candidate);
    if (crc != (uint16_t)(crc_bytes[0] | (crc_bytes[1] << 8)))
        return false;
    memcpy(&settings, &candidate, sizeof settings);
    apply_board_identity();
    settings_generation++;
    return true;
}

bool settings_init(void)
{
    comm_register(PB_PKT_UPDATE_SETTINGS, on_update);
    comm_register(PB_PKT_READ_SETTINGS, on_read);
    comm_register(PB_PKT_SAVE_SETTINGS, on_save);
    comm_register(PB_PKT_LOAD_DEFAULTS, on_load_defaults);
    eeprom_init();
    if (settings_load())
        return true;
    settings_load_defaults();
    return false;
}

bool settings_save(void)
{
    static uint8_t image[IMAGE_SIZE];
    if (eeprom_busy())
        return false;
    settings_header_t h = {SETTINGS_MAGIC, PB_LAYOUT_HASH, sizeof(pb_settings_t)};
    memcpy(image, &h, sizeof h);
    memcpy(image + sizeof h, &settings, sizeof settings);
    uint16_t crc = pb_crc16(0xFFFFu, image, sizeof h + sizeof settings);
    image[IMAGE_SIZE - 2] = (uint8_t)crc;
    image[IMAGE_SIZE - 1] = (uint8_t)(crc >> 8);
    return eeprom_write(SETTINGS_EEPROM_ADDR, image, IMAGE_SIZE);
}

/* Little-endian loads: the wire order, whatever the CPU. */
static uint32_t load_le(const uint8_t *p, uint8_t size)
{
    uint32_t v = 0;
    while (size--)
        v = (v << 8) | p[size];
    return v;
}

static bool value_ok(const HAL_FLASH pb_settings_field_t *f, const uint8_t *p)
{
    float v;
    uint32_t raw = load_le(p, f->elem_size);
    switch (f->type) {
    case PB_FIELD_CHAR:
        return true;
    case PB_FIELD_U8:
    case PB_FIELD_U16:
    case PB_FIELD_U32:
        v = (float)raw;
        break;
    case PB_FIELD_I8:
        v = (float)(int8_t)raw;
        break;
    case PB_FIELD_I16:
        v = (float)(int16_t)raw;
        break;
    case PB_FIELD_I32:
        v = (float)(int32_t)raw;
        break;
    case PB_FIELD_F32:
        if (((raw >> 23) & 0xFFu) == 0xFFu) /* infinity or NaN */
            return false;
        memcpy(&v, &raw, sizeof v);
        break;
    default:
        return false;
    }
    return v >= f->min && v <= f->max;
}

uint8_t settings_write(uint16_t offset, uint8_t len, const uint8_t *data, uint16_t *detail)
{
    *detail = offset;
    uint16_t end = (uint16_t)(offset + len);
    if (len == 0 || end > sizeof(pb_settings_t))
        return PB_ERROR_CODE_SETTINGS_RANGE;

    /* Find the field where the range starts; the table is in struct order without gaps. */
    uint8_t i = 0;
    while (i < PB_SETTINGS_FIELD_COUNT &&
           offset >= pb_settings_fields[i].offset +
                         (uint16_t)pb_settings_fields[i].elem_size * pb_settings_fields[i].count)
        i++;
    if (i == PB_SETTINGS_FIELD_COUNT)
        return PB_ERROR_CODE_SETTINGS_RANGE;

    /* Walk element by element; every step must land on a boundary the field allows. */
    uint16_t pos = offset;
    while (pos < end) {
        if (i >= PB_SETTINGS_FIELD_COUNT)
            return PB_ERROR_CODE_SETTINGS_RANGE;
        const HAL_FLASH pb_settings_field_t *f = &pb_settings_fields[i];
        uint16_t fend = (uint16_t)(f->offset + (uint16_t)f->elem_size * f->count);
        uint16_t rel = (uint16_t)(pos - f->offset);
        if (pos < f->offset || rel % f->elem_size != 0)
            return PB_ERROR_CODE_SETTINGS_RANGE;
        if (f->type == PB_FIELD_CHAR) {
            if (pos != f->offset || end < fend)
                return PB_ERROR_CODE_SETTINGS_RANGE;
            pos = fend;
        } else {
            if (end < pos + f->elem_size)
                return PB_ERROR_CODE_SETTINGS_RANGE;
            pos = (uint16_t)(pos + f->elem_size);
        }
        if (pos == fend)
            i++;
    }

    /* Range is sound: check every value before changing anything. */
    pos = offset;
    i = 0;
    while (pos < end) {
        while (pos >= pb_settings_fields[i].offset +
                          (uint16_t)pb_settings_fields[i].elem_size * pb_settings_fields[i].count)
            i++;
        const HAL_FLASH pb_settings_field_t *f = &pb_settings_fields[i];
        if (!value_ok(f, data + (pos - offset))) {
            *detail = pos;
            return PB_ERROR_CODE_SETTINGS_VALUE;
        }
        pos = (uint16_t)(pos + (f->type == PB_FIELD_CHAR ? (uint16_t)f->count : f->elem_size));
    }

    memcpy((uint8_t *)&settings + offset, data, len);
    settings_generation++;
    return PB_ERROR_CODE_NONE;
}

/* ---- host commands ---- */

static uint8_t on_update(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_update_settings_t c;
    memcpy(&c, cmd->payload, cmd->len);
    if (c.length != cmd->len - PB_UPDATE_SETTINGS_HEAD_SIZE) {
        *detail = c.length;
        return PB_ERROR_CODE_BAD_LENGTH;
    }
    return settings_write(c.offset, c.length, c.data, detail);
}

static uint8_t on_read(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)detail;
    reading.seq = cmd->seq; /* a new request restarts the answer: the host wants all of it, as it is now */
    reading.offset = 0;
    if (!answer_step())
        comm_answer_later(answer_step);
    return COMM_ANSWER_LATER;
}

static uint8_t on_save(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)cmd;
    (void)detail;
    return settings_save() ? PB_ERROR_CODE_NONE : PB_ERROR_CODE_BUSY;
}

static uint8_t on_load_defaults(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)cmd;
    (void)detail;
    settings_load_defaults();
    return PB_ERROR_CODE_NONE;
}

/* Sends what fits of the chunks, then the ack. \return true when all is out. */
static bool answer_step(void)
{
    for (;;) {
        if (reading.offset >= sizeof(pb_settings_t))
            return comm_ack(PB_PKT_READ_SETTINGS, reading.seq);
        pb_settings_data_t d;
        uint16_t left = (uint16_t)(sizeof(pb_settings_t) - reading.offset);
        d.offset = reading.offset;
        d.length = (uint8_t)(left < SETTINGS_CHUNK ? left : SETTINGS_CHUNK);
        memcpy(d.data, (const uint8_t *)&settings + reading.offset, d.length);
        if (!comm_offer(PB_PKT_SETTINGS_DATA, &d, (uint8_t)(PB_SETTINGS_DATA_HEAD_SIZE + d.length)))
            return false; /* the rest next tick */
        reading.offset = (uint16_t)(reading.offset + d.length);
    }
}
