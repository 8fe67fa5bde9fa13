#include <math.h>
#include <string.h>

#include "drivers/eeprom.h"
#include "harness.h"
#include "modules/settings.h"
#include "world.h"

static pb_settings_t before;

static uint8_t write(uint16_t offset, uint8_t len, const void *data, uint16_t *detail)
{
    memcpy(&before, &settings, sizeof settings);
    uint8_t r = settings_write(offset, len, (const uint8_t *)data, detail);
    if (r != PB_ERROR_CODE_NONE)
        CHECK(memcmp(&before, &settings, sizeof settings) == 0, "a refused write changed settings (%u+%u)", offset,
              len);
    return r;
}

static void every_field_accepts_its_default_at_its_own_boundaries(void)
{
    world_reset(0);
    uint16_t detail;
    for (int i = 0; i < PB_SETTINGS_FIELD_COUNT; i++) {
        const pb_settings_field_t *f = &pb_settings_fields[i];
        uint16_t size = (uint16_t)(f->elem_size * f->count);
        const uint8_t *cur = (const uint8_t *)&settings + f->offset;
        uint8_t copy[64];
        memcpy(copy, cur, size);
        CHECK(write(f->offset, (uint8_t)size, copy, &detail) == PB_ERROR_CODE_NONE, "field %d whole", i);
        if (f->elem_size > 1) { /* starting or ending inside an element */
            CHECK(write((uint16_t)(f->offset + 1), (uint8_t)(size - 1), copy + 1, &detail) ==
                      PB_ERROR_CODE_SETTINGS_RANGE, "field %d start+1", i);
            CHECK(write(f->offset, (uint8_t)(size - 1), copy, &detail) == PB_ERROR_CODE_SETTINGS_RANGE,
                  "field %d end-1", i);
        }
        if (f->count > 1 && f->type != PB_FIELD_CHAR) /* one element of a numeric array */
            CHECK(write((uint16_t)(f->offset + f->elem_size), f->elem_size, copy + f->elem_size, &detail) ==
                      PB_ERROR_CODE_NONE, "field %d element 1", i);
        if (f->type == PB_FIELD_CHAR)
            CHECK(write((uint16_t)(f->offset + 1), 1, copy + 1, &detail) == PB_ERROR_CODE_SETTINGS_RANGE,
                  "field %d part of a string", i);
    }
}

static void writes_outside_or_across_the_struct_are_refused(void)
{
    world_reset(0);
    uint8_t zeros[64] = {0};
    uint16_t detail;
    uint16_t size = sizeof(pb_settings_t);
    CHECK(write(size, 1, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE && detail == size, "one past the end");
    CHECK(write((uint16_t)(size - 1), 2, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE, "straddles the end");
    CHECK(write(0xFFFF, 1, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE, "offset 0xffff");
    CHECK(write(0, 0, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE, "empty write");
    /* The last field (debug.level, 1 byte) is writable at its exact end. */
    uint8_t lvl = 3;
    CHECK(write((uint16_t)(size - 1), 1, &lvl, &detail) == PB_ERROR_CODE_NONE && settings.debug.level == 3, "last");
    /* Straddling two fields: from inside sync.mode..period to inside scheduler. */
    uint16_t sync = offsetof(pb_settings_t, sync);
    CHECK(write((uint16_t)(sync + 2), 2, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE, "mid-field start");
    CHECK(write(sync, 4, zeros, &detail) == PB_ERROR_CODE_SETTINGS_RANGE, "ends inside scheduler");
    /* A run over several whole fields is fine. */
    pb_settings_sync_t s = {PB_SYNC_MODE_REDUCED, 5};
    pb_settings_scheduler_t sch = {2000};
    uint8_t both[5];
    memcpy(both, &s, 3);
    memcpy(both + 3, &sch, 2);
    CHECK(write(sync, 5, both, &detail) == PB_ERROR_CODE_NONE, "two whole groups");
    CHECK(settings.sync.mode == PB_SYNC_MODE_REDUCED && settings.sync.period_ms == 5 &&
              settings.scheduler.main_period_us == 2000, "applied");
}

static void values_outside_their_range_are_refused(void)
{
    world_reset(0);
    uint16_t detail;
    for (int i = 0; i < PB_SETTINGS_FIELD_COUNT; i++) {
        const pb_settings_field_t *f = &pb_settings_fields[i];
        uint8_t buf[4];
        if (f->type == PB_FIELD_F32) {
            float bad[] = {NAN, INFINITY, -INFINITY, f->max * 1.01f + 1.0f, f->min - 1.0f};
            for (unsigned k = 0; k < sizeof bad / sizeof bad[0]; k++) {
                memcpy(buf, &bad[k], 4);
                CHECK(write(f->offset, 4, buf, &detail) == PB_ERROR_CODE_SETTINGS_VALUE && detail == f->offset,
                      "field %d float case %u", i, k);
            }
            memcpy(buf, &f->max, 4);
            CHECK(write(f->offset, 4, buf, &detail) == PB_ERROR_CODE_NONE, "field %d max accepted", i);
            memcpy(buf, &f->min, 4);
            CHECK(write(f->offset, 4, buf, &detail) == PB_ERROR_CODE_NONE, "field %d min accepted", i);
        } else if (f->type == PB_FIELD_U8 || f->type == PB_FIELD_U16) {
            uint32_t limit = f->type == PB_FIELD_U8 ? 255u : 65535u;
            uint32_t hi = (uint32_t)f->max, lo = (uint32_t)f->min;
            uint16_t at = (uint16_t)(f->offset + (f->count - 1) * f->elem_size); /* last element */
            if (hi < limit) {
                uint32_t v = hi + 1;
                memcpy(buf, &v, f->elem_size);
                CHECK(write(at, f->elem_size, buf, &detail) == PB_ERROR_CODE_SETTINGS_VALUE && detail == at,
                      "field %d max+1", i);
            }
            if (lo > 0) {
                uint32_t v = lo - 1;
                memcpy(buf, &v, f->elem_size);
                CHECK(write(at, f->elem_size, buf, &detail) == PB_ERROR_CODE_SETTINGS_VALUE, "field %d min-1", i);
            }
            memcpy(buf, &hi, f->elem_size);
            CHECK(write(at, f->elem_size, buf, &detail) == PB_ERROR_CODE_NONE, "field %d max", i);
            memcpy(buf, &lo, f->elem_size);
            CHECK(write(at, f->elem_size, buf, &detail) == PB_ERROR_CODE_NONE, "field %d min", i);
        }
    }
    /* One bad value in a multi-field write refuses all of it. */
    settings_load_defaults();
    pb_pid_t pid = {1.0f, 2.0f, NAN, 4.0f};
    CHECK(write(offsetof(pb_settings_t, speed_pid), sizeof pid, &pid, &detail) == PB_ERROR_CODE_SETTINGS_VALUE &&
              detail == offsetof(pb_settings_t, speed_pid) + 8, "NaN kd, detail %u", detail);
}

static void eeprom_image_round_trips_and_guards_against_stale_data(void)
{
    world_reset(0);
    settings.line_follow.speed_mps = 0.33f;
    CHECK(settings_save(), "save started");
    for (int i = 0; i < 20 && eeprom_busy(); i++)
        eeprom_task();
    CHECK(!eeprom_busy(), "save finished");
    settings_load_defaults();
    CHECK(settings_load() && settings.line_follow.speed_mps == 0.33f, "loaded back");
    /* A flipped byte in the image: the CRC refuses it. */
    uint8_t b;
    eeprom_read(20, &b, 1);
    b ^= 0x40;
    eeprom_write(20, &b, 1);
    while (eeprom_busy())
        eeprom_task();
    settings_load_defaults();
    CHECK(!settings_load() && settings.line_follow.speed_mps != 0.33f, "corrupt image refused");
    /* A different layout hash (firmware with another layout wrote it): refused. */
    uint8_t hash[4] = {1, 2, 3, 4};
    eeprom_write(2, hash, 4);
    while (eeprom_busy())
        eeprom_task();
    CHECK(!settings_init(), "stale image falls back to defaults");
    CHECK(settings.sync.period_ms == pb_settings_defaults.sync.period_ms, "defaults in place");
}

static void emulator_board_id_names_the_robot(void)
{
    world_reset(12);
    CHECK(settings.identity.robot_id == 12 && strcmp(settings.identity.name, "PocketBot-12") == 0, "name %s",
          settings.identity.name);
    settings_load_defaults();
    CHECK(settings.identity.robot_id == 12, "kept after load_defaults");
}

static void saved_settings_survive_a_reset(void)
{
    world_reset(0);
    settings.sync.period_ms = 250;
    CHECK(settings_save(), "save");
    world_run_ms(20);
    sim_init(0); /* a reset keeps the EEPROM */
    CHECK(settings.sync.period_ms == 250, "loaded at start: %u", settings.sync.period_ms);
}

void suite_settings(void)
{
    RUN(saved_settings_survive_a_reset);
    RUN(every_field_accepts_its_default_at_its_own_boundaries);
    RUN(writes_outside_or_across_the_struct_are_refused);
    RUN(values_outside_their_range_are_refused);
    RUN(eeprom_image_round_trips_and_guards_against_stale_data);
    RUN(emulator_board_id_names_the_robot);
}
