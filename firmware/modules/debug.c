#include "debug.h"

#include <stdarg.h>

#include "modules/comm.h"

typedef struct {
    char *out;
    uint8_t size;
    uint8_t n;
} sink_t;

static void put(sink_t *s, char c)
{
    if (s->n < s->size)
        s->out[s->n++] = c;
}

static void put_unsigned(sink_t *s, uint32_t v, uint8_t base)
{
    char digits[10];
    uint8_t k = 0;
    do {
        uint8_t d = (uint8_t)(v % base);
        digits[k++] = (char)(d < 10 ? '0' + d : 'a' + d - 10);
        v /= base;
    } while (v);
    while (k)
        put(s, digits[--k]);
}

uint8_t debug_format(char *out, uint8_t size, const HAL_FLASH char *fmt, va_list ap)
{
    sink_t s = {out, size, 0};
    char c;
    while ((c = *fmt++) != 0) {
        if (c != '%') {
            put(&s, c);
            continue;
        }
        uint8_t is_long = 0;
        c = *fmt++;
        if (c == 'l') {
            is_long = 1;
            c = *fmt++;
        }
        switch (c) {
        case 'd':
        case 'i': {
            int32_t v = is_long ? va_arg(ap, long) : va_arg(ap, int);
            uint32_t mag = (uint32_t)v;
            if (v < 0) {
                put(&s, '-');
                mag = 0u - mag;
            }
            put_unsigned(&s, mag, 10);
            break;
        }
        case 'u':
        case 'x':
            put_unsigned(&s, is_long ? (uint32_t)va_arg(ap, unsigned long) : (uint32_t)va_arg(ap, unsigned),
                         c == 'u' ? 10 : 16);
            break;
        case 'c':
            put(&s, (char)va_arg(ap, int));
            break;
        case 's': {
            const char *str = va_arg(ap, const char *);
            while (str && *str)
                put(&s, *str++);
            break;
        }
        case '%':
            put(&s, '%');
            break;
        case 0:
            return s.n; /* a lone '%' ends the format */
        default:
            put(&s, '%');
            put(&s, c);
            break;
        }
    }
    return s.n;
}

void debug_printf(uint8_t module, uint8_t level, const HAL_FLASH char *fmt, ...)
{
    pb_debug_text_t msg;
    msg.module = module;
    msg.level = level;
    va_list ap;
    va_start(ap, fmt);
    uint8_t n = debug_format((char *)msg.text, sizeof msg.text, fmt, ap);
    va_end(ap);
    comm_send(PB_PKT_DEBUG_TEXT, &msg, (uint8_t)(PB_DEBUG_TEXT_HEAD_SIZE + n));
}
