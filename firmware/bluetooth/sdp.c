#include "sdp.h"

#include <stddef.h>

#include "bluetooth/bt_config.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"

/* PDU ids. */
#define SDP_ERROR_RSP 0x01u
#define SDP_SEARCH_REQ 0x02u
#define SDP_SEARCH_RSP 0x03u
#define SDP_ATTRIBUTE_REQ 0x04u
#define SDP_ATTRIBUTE_RSP 0x05u
#define SDP_SEARCH_ATTRIBUTE_REQ 0x06u
#define SDP_SEARCH_ATTRIBUTE_RSP 0x07u

/* Error codes. */
#define ERR_BAD_HANDLE 0x0002u
#define ERR_BAD_SYNTAX 0x0003u
#define ERR_BAD_CONTINUATION 0x0005u

/* Data element types (the high five bits of a header byte). */
#define DE_UINT 1u
#define DE_UUID 3u
#define DE_SEQUENCE 6u

#define BE16(v) (uint8_t)((v) >> 8), (uint8_t)(v)
#define BE32(v) (uint8_t)((v) >> 24), (uint8_t)((v) >> 16), (uint8_t)((v) >> 8), (uint8_t)(v)
#define ATTR(id) 0x09, BE16(id)
#define LANGUAGE_BASE ATTR(0x0006), 0x35, 9, 0x09, 'e', 'n', 0x09, BE16(106), 0x09, BE16(0x0100) /* English, UTF-8 */
#define PUBLIC_BROWSE ATTR(0x0005), 0x35, 3, 0x19, BE16(0x1002)

#define UUID_L2CAP 0x0100u
#define UUID_RFCOMM 0x0003u
#define UUID_SERIAL_PORT 0x1101u
#define UUID_PUBLIC_BROWSE 0x1002u
/* A UUID as the server compares them: 16- and 32-bit values of the base UUID, or these two. */
#define UUID_FRAMED 0xFFFFFFFFul
#define UUID_OTHER 0xFFFFFFFEul

/* Attribute id and value pairs, in ascending id order, as they go on the wire. */
static const HAL_FLASH uint8_t spp_attrs[] = {
    ATTR(0x0000), 0x0A, BE32(BT_SDP_HANDLE_SPP),
    ATTR(0x0001), 0x35, 3, 0x19, BE16(UUID_SERIAL_PORT),
    ATTR(0x0004), 0x35, 12, 0x35, 3, 0x19, BE16(UUID_L2CAP), 0x35, 5, 0x19, BE16(UUID_RFCOMM), 0x08, BT_RFCOMM_CHANNEL,
    PUBLIC_BROWSE,
    LANGUAGE_BASE,
    ATTR(0x0009), 0x35, 8, 0x35, 6, 0x19, BE16(UUID_SERIAL_PORT), 0x09, BE16(0x0102),
    ATTR(0x0100), 0x25, 9, 'P', 'o', 'c', 'k', 'e', 't', 'B', 'o', 't',
};
static const HAL_FLASH uint8_t framed_attrs[] = {
    ATTR(0x0000), 0x0A, BE32(BT_SDP_HANDLE_FRAMED),
    ATTR(0x0001), 0x35, 17, 0x1C, BT_FRAMED_UUID,
    ATTR(0x0004), 0x35, 8, 0x35, 6, 0x19, BE16(UUID_L2CAP), 0x09, BE16(BT_PSM_FRAMED),
    PUBLIC_BROWSE,
    LANGUAGE_BASE,
    ATTR(0x0100), 0x25, 16, 'P', 'o', 'c', 'k', 'e', 't', 'B', 'o', 't', ' ', 'f', 'r', 'a', 'm', 'e', 'd',
};
static const HAL_FLASH uint8_t framed_uuid[16] = {BT_FRAMED_UUID};
static const HAL_FLASH uint8_t base_uuid_tail[12] = {0x00, 0x00, 0x10, 0x00, 0x80, 0x00,
                                                     0x00, 0x80, 0x5F, 0x9B, 0x34, 0xFB};

typedef struct {
    uint32_t handle;
    const HAL_FLASH uint8_t *attrs;
    uint8_t attrs_len;
    uint32_t uuids[4]; /* every UUID in the record (0: none) */
} record_t;

#define RECORDS 2u
static const HAL_FLASH record_t records[RECORDS] = {
    {BT_SDP_HANDLE_SPP, spp_attrs, sizeof spp_attrs, {UUID_SERIAL_PORT, UUID_L2CAP, UUID_RFCOMM, UUID_PUBLIC_BROWSE}},
    {BT_SDP_HANDLE_FRAMED, framed_attrs, sizeof framed_attrs, {UUID_FRAMED, UUID_L2CAP, UUID_PUBLIC_BROWSE, 0}},
};

static uint16_t be16(const uint8_t *p)
{
    return (uint16_t)((p[0] << 8) | p[1]);
}

static uint32_t be32(const uint8_t *p)
{
    return ((uint32_t)be16(p) << 16) | be16(p + 2);
}

/* ---- data elements of a request ---- */

typedef struct {
    uint8_t type;
    uint16_t head; /* header bytes */
    uint16_t len;  /* data bytes */
} de_t;

/* Reads the data element header at p (n bytes left). \return false when it is malformed or overruns. */
static bool de_read(const uint8_t *p, uint16_t n, de_t *de)
{
    if (n < 1)
        return false;
    uint8_t size = p[0] & 7u;
    de->type = p[0] >> 3;
    if (de->type == 0) {
        de->head = 1;
        de->len = 0;
    } else if (size < 5) {
        de->head = 1;
        de->len = (uint16_t)(1u << size);
    } else if (size == 5 && n >= 2) {
        de->head = 2;
        de->len = p[1];
    } else if (size == 6 && n >= 3) {
        de->head = 3;
        de->len = be16(p + 1);
    } else {
        return false; /* 32-bit lengths: no request is that long */
    }
    return (uint32_t)de->head + de->len <= n;
}

/* The UUID of a data element, as the server compares them. */
static uint32_t uuid_of(const uint8_t *p, const de_t *de)
{
    const uint8_t *v = p + de->head;
    if (de->len == 2)
        return be16(v);
    if (de->len == 4) {
        uint32_t u = be32(v);
        return u >= UUID_OTHER ? UUID_OTHER : u;
    }
    uint8_t base = 1, framed = 1;
    for (uint8_t i = 0; i < 16; i++) {
        if (v[i] != framed_uuid[i])
            framed = 0;
        if (i >= 4 && v[i] != base_uuid_tail[i - 4])
            base = 0;
    }
    if (framed)
        return UUID_FRAMED;
    return base ? be32(v) : UUID_OTHER;
}

static bool record_has(const HAL_FLASH record_t *r, uint32_t uuid)
{
    for (uint8_t i = 0; i < 4; i++)
        if (r->uuids[i] == uuid && uuid != 0)
            return true;
    return false;
}

/* Matches a search pattern (a sequence of 1..12 UUIDs of 2, 4 or 16 bytes at p) against the record `r`, or
 * only checks it (r NULL). \return 1 when the record holds every UUID, 0 when not, -1 when the pattern is not one. */
static int8_t record_matches(const HAL_FLASH record_t *r, const uint8_t *p, const de_t *pattern)
{
    if (pattern->type != DE_SEQUENCE || pattern->len == 0)
        return -1;
    const uint8_t *e = p + pattern->head;
    uint16_t left = pattern->len;
    uint8_t count = 0;
    int8_t match = 1;
    while (left) {
        de_t u;
        if (!de_read(e, left, &u) || u.type != DE_UUID || (u.len != 2 && u.len != 4 && u.len != 16) || ++count > 12)
            return -1;
        if (r && !record_has(r, uuid_of(e, &u)))
            match = 0;
        e += u.head + u.len;
        left = (uint16_t)(left - u.head - u.len);
    }
    return match;
}

/* \return whether an attribute id list (a sequence of 16-bit ids and 32-bit ranges) is well formed. */
static bool id_list_valid(const uint8_t *p, const de_t *list)
{
    if (list->type != DE_SEQUENCE || list->len == 0)
        return false;
    const uint8_t *e = p + list->head;
    uint16_t left = list->len;
    while (left) {
        de_t a;
        if (!de_read(e, left, &a) || a.type != DE_UINT || (a.len != 2 && a.len != 4))
            return false;
        e += a.head + a.len;
        left = (uint16_t)(left - a.head - a.len);
    }
    return true;
}

static bool id_wanted(const uint8_t *p, const de_t *list, uint16_t id)
{
    const uint8_t *e = p + list->head;
    uint16_t left = list->len;
    while (left) {
        de_t a;
        de_read(e, left, &a); /* checked by id_list_valid() */
        const uint8_t *v = e + a.head;
        if (a.len == 2 ? be16(v) == id : (be16(v) <= id && id <= be16(v + 2)))
            return true;
        e += a.head + a.len;
        left = (uint16_t)(left - a.head - a.len);
    }
    return false;
}

/* ---- the answer, as a stream of which one window is written ---- */

typedef struct {
    uint16_t pos;  /* bytes of the answer produced so far */
    uint16_t from; /* the window written: [from, to) */
    uint16_t to;
} out_t;

static void out_byte(out_t *o, uint8_t b)
{
    if (o->pos >= o->from && o->pos < o->to)
        hci_acl_put_byte(b);
    o->pos++;
}

static void out_sequence_header(out_t *o, uint16_t len)
{
    if (len < 256u) {
        out_byte(o, 0x35);
    } else {
        out_byte(o, 0x36);
        out_byte(o, (uint8_t)(len >> 8));
    }
    out_byte(o, (uint8_t)len);
}

static uint16_t sequence_header_len(uint16_t len)
{
    return len < 256u ? 2u : 3u;
}

/* Length of a flash data element of the forms the records use. */
static uint8_t flash_de_len(const HAL_FLASH uint8_t *p)
{
    uint8_t size = p[0] & 7u;
    return size < 5 ? (uint8_t)(1u + (1u << size)) : (uint8_t)(2u + p[1]);
}

/* The record's attributes that the list asks for, as an attribute list (a sequence); `o` NULL: only measures.
 * \return its length. */
static uint16_t out_record(const HAL_FLASH record_t *r, const uint8_t *p, const de_t *list, out_t *o)
{
    const HAL_FLASH uint8_t *a = r->attrs;
    uint8_t n = r->attrs_len;
    uint16_t body = 0;
    for (uint8_t i = 0; i < n;) {
        uint8_t len = (uint8_t)(3u + flash_de_len(a + i + 3));
        if (id_wanted(p, list, (uint16_t)((a[i + 1] << 8) | a[i + 2])))
            body = (uint16_t)(body + len);
        i = (uint8_t)(i + len);
    }
    if (o) {
        out_sequence_header(o, body);
        for (uint8_t i = 0; i < n;) {
            uint8_t len = (uint8_t)(3u + flash_de_len(a + i + 3));
            if (id_wanted(p, list, (uint16_t)((a[i + 1] << 8) | a[i + 2])))
                for (uint8_t k = 0; k < len; k++)
                    out_byte(o, a[i + k]);
            i = (uint8_t)(i + len);
        }
    }
    return (uint16_t)(sequence_header_len(body) + body);
}

/* ---- requests ---- */

/* Starts an answer (after the room for all of it was found): PDU id, transaction id, parameter length, and the
 * first two parameter bytes (`first`). */
static void answer_begin(uint8_t link, uint8_t pdu, uint16_t tid, uint16_t params, uint16_t first)
{
    uint8_t h[7] = {pdu, (uint8_t)(tid >> 8), (uint8_t)tid, (uint8_t)(params >> 8), (uint8_t)params,
                    (uint8_t)(first >> 8), (uint8_t)first};
    l2cap_begin(link, L2CAP_SDP, (uint16_t)(5u + params));
    hci_acl_put(h, 7);
}

static bool send_error(uint8_t link, uint16_t tid, uint16_t code)
{
    if (!l2cap_can_send(link, L2CAP_SDP, 7, false))
        return false;
    answer_begin(link, SDP_ERROR_RSP, tid, 2, code);
    hci_acl_end();
    return true;
}

static bool on_search(uint8_t link, uint16_t tid, const uint8_t *p, uint16_t n)
{
    de_t pattern;
    if (!de_read(p, n, &pattern) || record_matches(NULL, p, &pattern) < 0 || n < pattern.head + pattern.len + 3u)
        return send_error(link, tid, ERR_BAD_SYNTAX);
    uint16_t max = be16(p + pattern.head + pattern.len);
    uint8_t count = 0;
    bool match[RECORDS];
    for (uint8_t i = 0; i < RECORDS; i++) {
        match[i] = count < max && record_matches(&records[i], p, &pattern) > 0;
        count = (uint8_t)(count + match[i]);
    }
    uint16_t params = (uint16_t)(4u + 4u * count + 1u);
    if (!l2cap_can_send(link, L2CAP_SDP, (uint16_t)(5u + params), false))
        return false;
    answer_begin(link, SDP_SEARCH_RSP, tid, params, count); /* the total count, then the count in this part */
    hci_acl_put_byte(0);
    hci_acl_put_byte(count);
    for (uint8_t i = 0; i < RECORDS; i++)
        if (match[i]) {
            uint32_t h = records[i].handle;
            for (int8_t s = 24; s >= 0; s -= 8)
                hci_acl_put_byte((uint8_t)(h >> s));
        }
    hci_acl_put_byte(0); /* no continuation */
    hci_acl_end();
    return true;
}

/* Attribute requests: one record (`handle_req`) or every record the pattern matches, as attribute lists. */
static bool on_attributes(uint8_t link, uint8_t pdu, uint16_t tid, const uint8_t *p, uint16_t n)
{
    bool search = pdu == SDP_SEARCH_ATTRIBUTE_REQ;
    de_t pattern = {0, 0, 0}, list;
    uint16_t i = 0;
    uint8_t only = RECORDS; /* the record of a ServiceAttribute request */
    if (search) {
        if (!de_read(p, n, &pattern) || record_matches(NULL, p, &pattern) < 0)
            return send_error(link, tid, ERR_BAD_SYNTAX);
        i = (uint16_t)(pattern.head + pattern.len);
    } else {
        if (n < 4)
            return send_error(link, tid, ERR_BAD_SYNTAX);
        uint32_t handle = be32(p);
        for (uint8_t r = 0; r < RECORDS; r++)
            if (records[r].handle == handle)
                only = r;
        if (only == RECORDS)
            return send_error(link, tid, ERR_BAD_HANDLE);
        i = 4;
    }
    if (n < i + 2u)
        return send_error(link, tid, ERR_BAD_SYNTAX);
    uint16_t max = be16(p + i);
    i = (uint16_t)(i + 2u);
    if (max < 7u || !de_read(p + i, (uint16_t)(n - i), &list) || !id_list_valid(p + i, &list))
        return send_error(link, tid, ERR_BAD_SYNTAX);
    const uint8_t *ids = p + i;
    i = (uint16_t)(i + list.head + list.len);
    if (n < i + 1u || n < i + 1u + p[i])
        return send_error(link, tid, ERR_BAD_SYNTAX);
    uint16_t offset = 0;
    if (p[i] == 2)
        offset = be16(p + i + 1);
    else if (p[i] != 0)
        return send_error(link, tid, ERR_BAD_CONTINUATION);

    /* Measure the whole answer, then write the window [offset, offset + count) of it. */
    bool match[RECORDS];
    uint16_t inner = 0;
    for (uint8_t r = 0; r < RECORDS; r++) {
        match[r] = search ? record_matches(&records[r], p, &pattern) > 0 : r == only;
        if (match[r])
            inner = (uint16_t)(inner + out_record(&records[r], ids, &list, NULL));
    }
    uint16_t total = search ? (uint16_t)(sequence_header_len(inner) + inner) : inner;
    if (offset > total || (offset == total && offset != 0))
        return send_error(link, tid, ERR_BAD_CONTINUATION);
    uint16_t mtu = l2cap_peer_mtu(link, L2CAP_SDP); /* at least 48 while open */
    if (mtu == 0)
        return true; /* the channel closed meanwhile */
    uint16_t count = (uint16_t)(total - offset);
    if (count > max)
        count = max;
    if (count > SDP_CHUNK_MAX)
        count = SDP_CHUNK_MAX;
    if (count > mtu - 10u) /* header, byte count and continuation beside it */
        count = (uint16_t)(mtu - 10u);
    bool more = offset + count < total;
    uint16_t params = (uint16_t)(2u + count + (more ? 3u : 1u));
    if (!l2cap_can_send(link, L2CAP_SDP, (uint16_t)(5u + params), false))
        return false;
    answer_begin(link, (uint8_t)(pdu + 1u), tid, params, count);
    out_t o = {0, offset, (uint16_t)(offset + count)};
    if (search)
        out_sequence_header(&o, inner);
    for (uint8_t r = 0; r < RECORDS; r++)
        if (match[r])
            out_record(&records[r], ids, &list, &o);
    if (more) {
        uint16_t next = (uint16_t)(offset + count);
        hci_acl_put_byte(2);
        hci_acl_put_byte((uint8_t)(next >> 8));
        hci_acl_put_byte((uint8_t)next);
    } else {
        hci_acl_put_byte(0);
    }
    hci_acl_end();
    return true;
}

bool sdp_on_pdu(uint8_t link, const uint8_t *p, uint16_t n)
{
    if (n < 5)
        return true; /* no transaction id to answer */
    uint8_t pdu = p[0];
    uint16_t tid = be16(p + 1);
    uint16_t len = be16(p + 3);
    if (len > n - 5u)
        return send_error(link, tid, ERR_BAD_SYNTAX);
    p += 5;
    if (pdu == SDP_SEARCH_REQ)
        return on_search(link, tid, p, len);
    if (pdu == SDP_ATTRIBUTE_REQ || pdu == SDP_SEARCH_ATTRIBUTE_REQ)
        return on_attributes(link, pdu, tid, p, len);
    return send_error(link, tid, ERR_BAD_SYNTAX);
}
