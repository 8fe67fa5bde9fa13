#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/debug.h"
#include "world.h"

static uint8_t fmt(char *out, uint8_t size, const char *f, ...)
{
    va_list ap;
    va_start(ap, f);
    uint8_t n = debug_format(out, size, f, ap);
    va_end(ap);
    out[n] = 0;
    return n;
}

static void tiny_formatter(void)
{
    char b[100];
    fmt(b, 99, "a%db%uc%xd%se%cf%%", -42, 65535u, 0xBEEFu, "str", 'Z');
    CHECK(strcmp(b, "a-42b65535cbeefdstreZf%") == 0, "got '%s'", b);
    fmt(b, 99, "%ld %lu %lx", -2147483647L - 1, 4294967295UL, 0x12345678UL);
    CHECK(strcmp(b, "-2147483648 4294967295 12345678") == 0, "got '%s'", b);
    uint8_t n = fmt(b, 5, "%s", "truncated text");
    CHECK(n == 5 && strcmp(b, "trunc") == 0, "truncated to the buffer: '%s'", b);
    fmt(b, 99, "%q%", 1);
    CHECK(strcmp(b, "%q") == 0, "unknown conversions pass through: '%s'", b);
    fmt(b, 99, "%s", (const char *)NULL);
    CHECK(b[0] == 0, "NULL string");
}

static void messages_reach_the_host_filtered_by_level(void)
{
    world_reset(1);
    host_clear();
    settings.debug.level = 2;
    DEBUG_PRINT(LOCOMOTION, 2, "speed %d mm/s", 123);
    DEBUG_PRINT(LOCOMOTION, 3, "verbose %d", 1);
    world_run_ms(5);
    host_collect();
    CHECK(host_count(PB_PKT_DEBUG_TEXT) == 1, "one message passes level 2: %d", host_count(PB_PKT_DEBUG_TEXT));
    const host_frame_t *f = host_find(PB_PKT_DEBUG_TEXT, 0);
    CHECK(f && f->payload[0] == PB_DEBUG_MODULE_LOCOMOTION && f->payload[1] == 2 && f->len == 2 + 14 &&
              memcmp(f->payload + 2, "speed 123 mm/s", 14) == 0, "module, level, text");
    settings.debug.level = 0;
    DEBUG_PRINT(MAIN, 1, "silent");
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_DEBUG_TEXT) == 1, "level 0 is silent");
}

void suite_debug(void)
{
    RUN(tiny_formatter);
    RUN(messages_reach_the_host_filtered_by_level);
}
