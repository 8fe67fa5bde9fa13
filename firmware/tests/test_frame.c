#include <string.h>

#include "golden_vectors.h"
#include "harness.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"

static void crc_matches_the_ccitt_false_check_value(void)
{
    const uint8_t s[] = "123456789";
    CHECK(pb_crc16(0xFFFF, s, 9) == 0x29B1, "crc %04x", pb_crc16(0xFFFF, s, 9));
}

static void encoded_frame_checks_back(void)
{
    uint8_t buf[PB_MAX_FRAME];
    const uint8_t payload[3] = {1, 2, 0xC0};
    uint16_t n = pb_frame_encode(buf, 0x12, 7, payload, 3);
    CHECK(n == 8, "size %u", n);
    pb_frame_t f;
    CHECK(pb_frame_check(buf, n, &f) == PB_ERROR_CODE_NONE, "check");
    CHECK(f.type == 0x12 && f.seq == 7 && f.len == 3 && memcmp(f.payload, payload, 3) == 0, "fields");
    CHECK(pb_frame_encode(buf, 1, 1, payload, PB_MAX_PAYLOAD + 1) == 0, "over-long payload refused");
}

static void frame_decoder_refuses_damaged_frames(void)
{
    uint8_t buf[PB_MAX_FRAME + 10];
    uint8_t payload[PB_MAX_PAYLOAD];
    memset(payload, 0x5A, sizeof payload);
    pb_frame_t f;
    uint16_t n = pb_frame_encode(buf, PB_PKT_STOP, 3, payload, 1);
    for (uint16_t bit = 0; bit < n * 8; bit++) { /* every single bit error is caught */
        buf[bit / 8] ^= (uint8_t)(1 << (bit % 8));
        CHECK(pb_frame_check(buf, n, &f) != PB_ERROR_CODE_NONE, "bit %u undetected", bit);
        buf[bit / 8] ^= (uint8_t)(1 << (bit % 8));
    }
    for (uint16_t k = 0; k < 5; k++)
        CHECK(pb_frame_check(buf, k, &f) == PB_ERROR_CODE_TOO_SHORT, "short %u", k);
    n = pb_frame_encode(buf, PB_PKT_UPDATE_SETTINGS, 3, payload, PB_MAX_PAYLOAD);
    CHECK(pb_frame_check(buf, n, &f) == PB_ERROR_CODE_NONE, "largest frame accepted");
    CHECK(pb_frame_check(buf, (uint16_t)(n + 1), &f) == PB_ERROR_CODE_TOO_LONG, "over-long");
    /* A sound CRC around a length field that disagrees with the frame. */
    n = pb_frame_encode(buf, PB_PKT_STOP, 3, payload, 1);
    buf[2] = 2;
    uint16_t crc = pb_crc16(0xFFFF, buf, (uint16_t)(n - 2));
    buf[n - 2] = (uint8_t)crc;
    buf[n - 1] = (uint8_t)(crc >> 8);
    CHECK(pb_frame_check(buf, n, &f) == PB_ERROR_CODE_BAD_LENGTH, "length disagrees");
    CHECK(pb_packet_lookup(0x7F) == NULL, "unknown type");
    CHECK(pb_packet_lookup(PB_PKT_MOVE_STRAIGHT) != NULL, "known type");
}

void suite_frame(void)
{
    RUN(crc_matches_the_ccitt_false_check_value);
    RUN(encoded_frame_checks_back);
    RUN(frame_decoder_refuses_damaged_frames);
}

/* ---- golden vectors ---- */

static void golden_frames_decode_and_reencode_identically(void)
{
    for (int i = 0; i < PB_GOLDEN_COUNT; i++) {
        const pb_golden_t *g = &pb_golden[i];
        pb_frame_t f;
        uint8_t code = pb_frame_check(g->frame, g->frame_len, &f);
        CHECK(code == PB_ERROR_CODE_NONE, "%s: check code %u", g->name, code);
        if (code != PB_ERROR_CODE_NONE)
            continue;
        CHECK(f.type == g->type && f.seq == g->seq, "%s: type/seq", g->name);
        CHECK(f.len == g->payload_len && memcmp(f.payload, g->payload, g->payload_len) == 0,
              "%s: payload differs from the C struct", g->name);
        const PB_FLASH pb_packet_info_t *info = pb_packet_lookup(f.type);
        CHECK(info && f.len >= info->min_size && f.len <= info->max_size, "%s: length within the table", g->name);
        uint8_t out[PB_MAX_FRAME];
        uint16_t n = pb_frame_encode(out, g->type, g->seq, g->payload, g->payload_len);
        CHECK(n == g->frame_len && memcmp(out, g->frame, n) == 0, "%s: re-encoded frame differs", g->name);
        uint8_t slip[2 * PB_MAX_FRAME + 2];
        uint16_t m = slip_encode(slip, out, n);
        CHECK(m == g->slip_len && memcmp(slip, g->slip, m) == 0, "%s: SLIP bytes differ", g->name);
        CHECK(slip_encoded_size(out, n) == m, "%s: SLIP size", g->name);
        slip_decoder_t d;
        slip_decoder_init(&d);
        int frames = 0;
        for (uint16_t k = 0; k < g->slip_len; k++)
            if (slip_decode(&d, g->slip[k]) == SLIP_FRAME) {
                frames++;
                CHECK(d.len == g->frame_len && memcmp(d.buf, g->frame, d.len) == 0, "%s: unSLIPped", g->name);
            }
        CHECK(frames == 1, "%s: %d frames", g->name, frames);
    }
}

void suite_golden(void)
{
    RUN(golden_frames_decode_and_reencode_identically);
}

void golden_write_corpus(const char *dir)
{
    char path[512];
    for (int i = 0; i < PB_GOLDEN_COUNT; i++) {
        snprintf(path, sizeof path, "%s/golden_%s", dir, pb_golden[i].name);
        FILE *f = fopen(path, "wb");
        if (!f)
            continue;
        fwrite(pb_golden[i].slip, 1, pb_golden[i].slip_len, f);
        fclose(f);
    }
}
