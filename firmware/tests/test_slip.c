#include <string.h>

#include "harness.h"
#include "protocol/slip.h"

static int feed(slip_decoder_t *d, const uint8_t *b, int n, int *errors, uint8_t *last, int *last_len)
{
    int frames = 0;
    for (int i = 0; i < n; i++) {
        slip_result_t r = slip_decode(d, b[i]);
        if (r == SLIP_FRAME) {
            frames++;
            memcpy(last, d->buf, d->len);
            *last_len = d->len;
        } else if (r == SLIP_ERROR) {
            (*errors)++;
        }
    }
    return frames;
}

static void split_stream_gives_one_frame(void)
{
    const uint8_t frame[] = {0x01, 0xC0, 0xDB, 0x02};
    uint8_t enc[16], last[200];
    uint16_t n = slip_encode(enc, frame, 4);
    CHECK(n == 8, "encoded %u", n);
    slip_decoder_t d;
    slip_decoder_init(&d);
    int errors = 0, len = 0, frames = 0;
    for (uint16_t i = 0; i < n; i++) /* byte by byte, as the UART delivers it */
        frames += feed(&d, enc + i, 1, &errors, last, &len);
    CHECK(frames == 1 && errors == 0 && len == 4 && memcmp(last, frame, 4) == 0, "frames %d errors %d", frames,
          errors);
}

static void merged_frames_and_empty_frames(void)
{
    const uint8_t stream[] = {0xC0, 0xC0, 0xC0, 1, 2, 0xC0, 3, 0xC0, 0xC0, 4, 5, 6, 0xC0};
    slip_decoder_t d;
    slip_decoder_init(&d);
    uint8_t last[200];
    int errors = 0, len = 0;
    int frames = feed(&d, stream, sizeof stream, &errors, last, &len);
    CHECK(frames == 3 && errors == 0, "frames %d errors %d", frames, errors);
    CHECK(len == 3 && last[0] == 4 && last[2] == 6, "last frame");
}

static void oversized_frame_is_dropped_and_the_next_one_survives(void)
{
    slip_decoder_t d;
    slip_decoder_init(&d);
    uint8_t big[400], last[200];
    memset(big, 0x11, sizeof big);
    big[sizeof big - 1] = 0xC0;
    int errors = 0, len = 0;
    int frames = feed(&d, big, sizeof big, &errors, last, &len);
    CHECK(frames == 0 && errors == 1, "frames %d errors %d", frames, errors);
    const uint8_t ok[] = {7, 8, 0xC0};
    frames = feed(&d, ok, 3, &errors, last, &len);
    CHECK(frames == 1 && len == 2 && last[0] == 7, "recovered");
    /* Exactly the largest frame fits. */
    uint8_t edge[PB_MAX_FRAME + 1];
    memset(edge, 0x22, sizeof edge);
    edge[PB_MAX_FRAME] = 0xC0;
    frames = feed(&d, edge, sizeof edge, &errors, last, &len);
    CHECK(frames == 1 && len == PB_MAX_FRAME, "largest frame %d %d", frames, len);
}

static void corrupted_escapes_drop_the_frame(void)
{
    const uint8_t bad1[] = {1, 0xDB, 0x00, 2, 0xC0}; /* ESC followed by a non-escape */
    const uint8_t bad2[] = {1, 2, 0xDB, 0xC0};       /* ESC then END */
    slip_decoder_t d;
    slip_decoder_init(&d);
    uint8_t last[200];
    int errors = 0, len = 0;
    CHECK(feed(&d, bad1, sizeof bad1, &errors, last, &len) == 0 && errors == 1, "bad escape");
    CHECK(feed(&d, bad2, sizeof bad2, &errors, last, &len) == 0 && errors == 2, "escape then end");
    const uint8_t ok[] = {0xDB, 0xDD, 0xDB, 0xDC, 0xC0};
    CHECK(feed(&d, ok, sizeof ok, &errors, last, &len) == 1 && len == 2 && last[0] == 0xDB && last[1] == 0xC0,
          "escapes decode");
}

/* Feeds `p` as comm does: plain bytes in bulk, the others one by one; counts the frames and errors. */
static void feed_bulk(slip_decoder_t *d, const uint8_t *p, uint16_t n, int *frames, int *errors, uint16_t *sum)
{
    while (n) {
        uint16_t k = slip_decode_plain(d, p, n);
        p += k;
        n = (uint16_t)(n - k);
        if (!n)
            break;
        slip_result_t r = slip_decode(d, *p++);
        n--;
        *frames += r == SLIP_FRAME;
        *errors += r == SLIP_ERROR;
        if (r != SLIP_NONE)
            *sum = (uint16_t)(*sum * 31u + slip_seen(d) + (r == SLIP_FRAME ? d->buf[d->len - 1] : d->overflow));
    }
}

static void bulk_decoding_agrees_with_byte_by_byte(void)
{
    uint8_t stream[3000];
    uint32_t x = 12345;
    for (unsigned i = 0; i < sizeof stream; i++) { /* ENDs, escapes (sound and broken) and runs past a frame */
        x = x * 1103515245u + 12345u;
        uint8_t r = (uint8_t)(x >> 24);
        stream[i] = r < 6 ? SLIP_END : r < 10 ? SLIP_ESC : r < 14 ? SLIP_ESC_END : (uint8_t)(x >> 16);
    }
    for (unsigned chunk = 1; chunk <= 200; chunk += 37) {
        slip_decoder_t a, b;
        slip_decoder_init(&a);
        slip_decoder_init(&b);
        int fa = 0, ea = 0, fb = 0, eb = 0;
        uint16_t sa = 0, sb = 0;
        for (unsigned i = 0; i < sizeof stream; i++) {
            slip_result_t r = slip_decode(&a, stream[i]);
            fa += r == SLIP_FRAME;
            ea += r == SLIP_ERROR;
            if (r != SLIP_NONE)
                sa = (uint16_t)(sa * 31u + slip_seen(&a) + (r == SLIP_FRAME ? a.buf[a.len - 1] : a.overflow));
        }
        for (unsigned i = 0; i < sizeof stream; i += chunk)
            feed_bulk(&b, stream + i, (uint16_t)(sizeof stream - i < chunk ? sizeof stream - i : chunk), &fb, &eb, &sb);
        CHECK(fa == fb && ea == eb && sa == sb && fa > 10 && ea > 10,
              "chunks of %u: %d frames, %d errors byte by byte; %d, %d in bulk", chunk, fa, ea, fb, eb);
    }
    /* And a byte at a time through slip_take_plain() first, as comm reads its UART. */
    slip_decoder_t a, c;
    slip_decoder_init(&a);
    slip_decoder_init(&c);
    for (unsigned i = 0; i < sizeof stream; i++) {
        slip_result_t ra = slip_decode(&a, stream[i]);
        slip_result_t rc = slip_take_plain(&c, stream[i]) ? SLIP_NONE : slip_decode(&c, stream[i]);
        if (ra != rc || slip_seen(&a) != slip_seen(&c)) {
            CHECK(0, "byte %u: %d, seen %u byte by byte; %d, seen %u taken plain first", i, ra, slip_seen(&a), rc,
                  slip_seen(&c));
            return;
        }
    }
}

void suite_slip(void)
{
    RUN(split_stream_gives_one_frame);
    RUN(merged_frames_and_empty_frames);
    RUN(oversized_frame_is_dropped_and_the_next_one_survives);
    RUN(corrupted_escapes_drop_the_frame);
    RUN(bulk_decoding_agrees_with_byte_by_byte);
}
